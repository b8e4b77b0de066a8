/*
 * Errors and checked arguments of the hystcomp MEX gateway: every argument is checked for class,
 * complexity, sparsity, shape, emptiness and NaN before it reaches the library, and every
 * failure is a MATLAB error with an identifier.
 */
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <string.h>

#include "gateway.h"

static char message[2048];

void fail(const char *id, const char *format, ...) {
    va_list args;
    va_start(args, format);
    vsnprintf(message, sizeof message, format, args);
    va_end(args);
    mexErrMsgIdAndTxt(id, "%s", message);
}

/* The MATLAB identifier of a library status. */
const char *status_id(int status) {
    switch (status) {
    case HYSTCOMP_STATUS_NULL_POINTER: return "hystcomp:nullPointer";
    case HYSTCOMP_STATUS_INVALID_ARGUMENT: return "hystcomp:invalidArgument";
    case HYSTCOMP_STATUS_NOT_INVERTIBLE: return "hystcomp:notInvertible";
    case HYSTCOMP_STATUS_IO: return "hystcomp:io";
    case HYSTCOMP_STATUS_INVALID_MODEL_FILE: return "hystcomp:invalidModelFile";
    case HYSTCOMP_STATUS_WRONG_DIRECTION: return "hystcomp:wrongDirection";
    case HYSTCOMP_STATUS_NON_FINITE_INPUT: return "hystcomp:nonFiniteInput";
    case HYSTCOMP_STATUS_INTERNAL: return "hystcomp:internal";
    case HYSTCOMP_STATUS_IDENTIFICATION_FAILED: return "hystcomp:identificationFailed";
    case HYSTCOMP_STATUS_UNSTABLE_DELAY: return "hystcomp:unstableDelay";
    case HYSTCOMP_STATUS_LEARNING_STOPPED: return "hystcomp:learningStopped";
    default: return "hystcomp:unknownStatus";
    }
}

/* Raises the library's error of a failed call (its message, its status's identifier). */
void fail_status(int status) {
    fail(status_id(status), "%s", hystcomp_last_error_message());
}

/* ------------------------------------------------------------------------------------------ */
/* Checked arguments                                                                           */
/* ------------------------------------------------------------------------------------------ */

/* A real, full double array, or an error naming `what`. */
void require_double(const mxArray *a, const char *what) {
    if (!mxIsDouble(a)) {
        fail("hystcomp:wrongType", "%s must be of class double, not %s", what, mxGetClassName(a));
    }
    if (mxIsComplex(a)) {
        fail("hystcomp:wrongType", "%s must be real, not complex", what);
    }
    if (mxIsSparse(a)) {
        fail("hystcomp:wrongType", "%s must be a full array, not sparse", what);
    }
}

/* A real double scalar. */
double scalar(const mxArray *a, const char *what) {
    require_double(a, what);
    if (mxGetNumberOfElements(a) != 1) {
        fail("hystcomp:wrongSize", "%s must be a scalar, not %dx%d", what, (int)mxGetM(a),
             (int)mxGetN(a));
    }
    return mxGetScalar(a);
}

/* A finite scalar (NaN and infinities refused). */
double finite_scalar(const mxArray *a, const char *what) {
    double x = scalar(a, what);
    if (!isfinite(x)) {
        fail("hystcomp:nonFiniteInput", "%s is NaN or infinite; give a finite number", what);
    }
    return x;
}

/* A non-negative integer-valued scalar, at most `max`, as a size. */
size_t count(const mxArray *a, const char *what, double max) {
    double x = scalar(a, what);
    if (!(x >= 0.0 && x <= max && x == floor(x))) {
        fail("hystcomp:invalidArgument", "%s must be a whole number from 0 to %.0f, not %g", what,
             max, x);
    }
    return (size_t)x;
}

/* A logical or numeric scalar as a flag. */
int flag(const mxArray *a, const char *what) {
    if (mxIsLogical(a) && mxGetNumberOfElements(a) == 1) {
        return mxIsLogicalScalarTrue(a) ? 1 : 0;
    }
    if (mxIsDouble(a) && !mxIsComplex(a) && mxGetNumberOfElements(a) == 1) {
        double x = mxGetScalar(a);
        if (x == 0.0 || x == 1.0) {
            return x == 1.0;
        }
    }
    fail("hystcomp:wrongType", "%s must be true or false", what);
    return 0;
}

/* A non-empty real double vector (row or column) of finite samples; its length in *len. */
const double *signal(const mxArray *a, const char *what, size_t *len) {
    size_t k, n;
    const double *x;
    require_double(a, what);
    n = mxGetNumberOfElements(a);
    if (n == 0) {
        fail("hystcomp:empty", "%s is empty; give at least one sample", what);
    }
    if (mxGetNumberOfDimensions(a) > 2 || (mxGetM(a) != 1 && mxGetN(a) != 1)) {
        fail("hystcomp:wrongSize", "%s must be a vector, not a %dx%d matrix", what,
             (int)mxGetM(a), (int)mxGetN(a));
    }
    x = mxGetPr(a);
    for (k = 0; k < n; k++) {
        if (!isfinite(x[k])) {
            fail("hystcomp:nonFiniteInput", "%s(%lu) is %s; give finite samples", what,
                 (unsigned long)(k + 1), isnan(x[k]) ? "NaN" : "infinite");
        }
    }
    *len = n;
    return x;
}

/* A character row vector as a C string (freed by MATLAB when the call ends). */
char *string(const mxArray *a, const char *what) {
    char *s;
    if (!mxIsChar(a) || (mxGetM(a) > 1 && mxGetNumberOfElements(a) > 0)) {
        fail("hystcomp:wrongType", "%s must be a character vector (text), not %s", what,
             mxGetClassName(a));
    }
#if defined(MATLAB_MEX_FILE) && !defined(HAVE_OCTAVE)
    s = mxArrayToUTF8String(a); /* MATLAB's char is UTF-16; the library reads UTF-8 */
#else
    s = mxArrayToString(a); /* Octave's char holds UTF-8 bytes */
#endif
    if (s == NULL) {
        fail("hystcomp:wrongType", "%s could not be read as text", what);
    }
    return s;
}

/* Case-insensitive comparison of ASCII names. */
int same_name(const char *a, const char *b) {
    for (; *a && *b; a++, b++) {
        char x = (*a >= 'A' && *a <= 'Z') ? (char)(*a - 'A' + 'a') : *a;
        char y = (*b >= 'A' && *b <= 'Z') ? (char)(*b - 'A' + 'a') : *b;
        if (x != y) {
            return 0;
        }
    }
    return *a == *b;
}

/* A new double array shaped like `like` (a vector) holding `len` values to be filled. */
mxArray *like_shape(const mxArray *like, size_t len) {
    return mxGetM(like) == 1 ? mxCreateDoubleMatrix(1, len, mxREAL)
                             : mxCreateDoubleMatrix(len, 1, mxREAL);
}
