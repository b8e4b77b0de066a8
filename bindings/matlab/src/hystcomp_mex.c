/*
 * hystcomp_mex: the MATLAB/Octave gateway to hystcomp's C ABI (bindings/c/include/hystcomp.h).
 *
 * One MEX function, called by the +hystcomp package as hystcomp_mex(COMMAND, ...). It converts
 * arguments, calls the C library and converts the results; it implements nothing of its own.
 * Every argument is checked before use (class, complexity, sparsity, shape, emptiness, NaN,
 * integer-valued sizes) and every failure is a MATLAB error with an identifier
 * (hystcomp:notInvertible, hystcomp:wrongType, ...) and the library's message: no argument can
 * crash MATLAB or Octave.
 *
 * This file holds the commands and their dispatch; args.c the errors and checked arguments,
 * model.c the model structs, handles.c the compensator handle table (ids with generations: a
 * freed or made-up id is refused, never dereferenced).
 *
 * Build: see build.m (Octave: mkoctfile --mex; MATLAB: mex), after
 *   cargo build --release -p hystcomp-c
 */
#include <stdint.h>
#include <string.h>

#include "gateway.h"

typedef void (*Command)(int nlhs, mxArray *plhs[], int nrhs, const mxArray *prhs[]);

/* The drive limits argument: [] or absent for the model's range, else [v_min v_max]. */
static int limits_arg(int nrhs, const mxArray *prhs[], int at, double *lo, double *hi) {
    const mxArray *a;
    if (nrhs <= at || mxIsEmpty(prhs[at])) {
        *lo = 0.0;
        *hi = 0.0;
        return 0;
    }
    a = prhs[at];
    require_double(a, "the limits");
    if (mxGetNumberOfElements(a) != 2) {
        fail("hystcomp:wrongSize", "the limits must be [v_min v_max] (2 values) or [], not %d "
             "values", (int)mxGetNumberOfElements(a));
    }
    *lo = mxGetPr(a)[0];
    *hi = mxGetPr(a)[1];
    return 1;
}

/* hystcomp_mex('version') -> the library's version. */
static void cmd_version(int nlhs, mxArray *plhs[], int nrhs, const mxArray *prhs[]) {
    (void)nlhs; (void)nrhs; (void)prhs;
    plhs[0] = mxCreateString(hystcomp_version());
}

/* hystcomp_mex('identify', v, y, name, value, ...) -> model struct. */
static void cmd_identify(int nlhs, mxArray *plhs[], int nrhs, const mxArray *prhs[]) {
    HystcompIdentifyOptions o;
    HystcompModel *model = NULL;
    size_t nv, ny;
    const double *v, *y;
    int k, status;
    (void)nlhs;
    v = signal(prhs[1], "the voltage", &nv);
    y = signal(prhs[2], "the displacement", &ny);
    if (nv != ny) {
        fail("hystcomp:lengthMismatch", "the voltage has %lu samples but the displacement has "
             "%lu; give one displacement per voltage sample", (unsigned long)nv,
             (unsigned long)ny);
    }
    hystcomp_identify_options_default(&o);
    o.holdout = 0.2; /* as `hystcomp identify` and the Python package hold out */
    if ((nrhs - 3) % 2 != 0) {
        fail("hystcomp:invalidOption", "options come in name, value pairs; the last name has no "
             "value");
    }
    for (k = 3; k < nrhs; k += 2) {
        const mxArray *value = prhs[k + 1];
        char *name;
        if (!mxIsChar(prhs[k])) {
            fail("hystcomp:invalidOption", "option names are text (e.g. 'n'), not %s",
                 mxGetClassName(prhs[k]));
        }
        name = string(prhs[k], "the option name");
        if (same_name(name, "n")) {
            o.operators = count(value, "n", HYSTCOMP_MAX_OPERATORS);
        } else if (same_name(name, "thresholds")) {
            size_t n;
            o.thresholds = signal(value, "thresholds", &n);
            o.threshold_count = n;
        } else if (same_name(name, "direction")) {
            char *d = string(value, "direction");
            if (same_name(d, "plant")) {
                o.direction = HYSTCOMP_DIRECTION_PLANT;
            } else if (same_name(d, "inverse")) {
                o.direction = HYSTCOMP_DIRECTION_INVERSE;
            } else {
                fail("hystcomp:invalidOption", "direction '%s' is unknown; give 'plant' "
                     "(voltage to displacement) or 'inverse' (displacement to voltage)", d);
            }
        } else if (same_name(name, "method")) {
            char *m = string(value, "method");
            if (same_name(m, "ls")) {
                o.solver = HYSTCOMP_SOLVER_LEAST_SQUARES;
            } else if (same_name(m, "pso")) {
                o.solver = HYSTCOMP_SOLVER_PARTICLE_SWARM;
            } else {
                fail("hystcomp:invalidOption", "method '%s' is unknown; give 'ls' (least "
                     "squares) or 'pso' (particle swarm)", m);
            }
        } else if (same_name(name, "warmup")) {
            if (mxIsChar(value)) {
                char *w = string(value, "warmup");
                if (!same_name(w, "auto")) {
                    fail("hystcomp:invalidOption", "warmup '%s' is unknown; give 'auto' or a "
                         "number of samples", w);
                }
                o.warmup_auto = 1;
            } else {
                o.warmup_auto = 0;
                o.warmup_samples = count(value, "warmup", 9007199254740992.0);
            }
        } else if (same_name(name, "holdout")) {
            o.holdout = scalar(value, "holdout");
        } else if (same_name(name, "offset")) {
            if (mxIsChar(value)) {
                char *m = string(value, "offset");
                if (same_name(m, "fit")) {
                    o.offset_mode = HYSTCOMP_OFFSET_MODE_FIT;
                } else if (same_name(m, "none")) {
                    o.offset_mode = HYSTCOMP_OFFSET_MODE_NONE;
                } else {
                    fail("hystcomp:invalidOption", "offset '%s' is unknown; give 'fit', 'none' "
                         "or a number", m);
                }
            } else {
                o.offset_mode = HYSTCOMP_OFFSET_MODE_VALUE;
                o.offset_value = scalar(value, "offset");
            }
        } else if (same_name(name, "margin")) {
            o.margin = scalar(value, "margin");
        } else if (same_name(name, "max_condition")) {
            o.max_condition = scalar(value, "max_condition");
        } else if (same_name(name, "accept_poor_fit")) {
            o.accept_poor_fit = flag(value, "accept_poor_fit");
        } else if (same_name(name, "seed")) {
            o.seed = (uint64_t)count(value, "seed", 9007199254740992.0);
        } else if (same_name(name, "particles")) {
            o.particles = count(value, "particles", HYSTCOMP_MAX_PARTICLES);
        } else if (same_name(name, "iterations")) {
            o.iterations = count(value, "iterations", HYSTCOMP_MAX_ITERATIONS);
        } else if (same_name(name, "polish")) {
            o.polish = flag(value, "polish");
        } else if (same_name(name, "voltage_unit")) {
            o.voltage_unit = string(value, "voltage_unit");
        } else if (same_name(name, "displacement_unit")) {
            o.displacement_unit = string(value, "displacement_unit");
        } else {
            fail("hystcomp:invalidOption", "unknown option '%s'; the options are n, thresholds, "
                 "direction, method, warmup, holdout, offset, margin, max_condition, "
                 "accept_poor_fit, seed, particles, iterations, polish, voltage_unit, "
                 "displacement_unit", name);
        }
    }
    status = hystcomp_identify(v, nv, y, ny, &o, &model, NULL);
    if (status != HYSTCOMP_STATUS_OK) {
        fail_status(status);
    }
    plhs[0] = model_struct(model);
}

/* hystcomp_mex('load_model', path) -> model struct. */
static void cmd_load_model(int nlhs, mxArray *plhs[], int nrhs, const mxArray *prhs[]) {
    HystcompModel *model = NULL;
    int status;
    (void)nlhs; (void)nrhs;
    status = hystcomp_model_load(string(prhs[1], "the file name"), &model);
    if (status != HYSTCOMP_STATUS_OK) {
        fail_status(status);
    }
    plhs[0] = model_struct(model);
}

/* hystcomp_mex('save_model', model, path). */
static void cmd_save_model(int nlhs, mxArray *plhs[], int nrhs, const mxArray *prhs[]) {
    char *path = string(prhs[2], "the file name");
    HystcompModel *model = model_from(prhs[1]);
    int status = hystcomp_model_save(model, path);
    (void)nlhs; (void)plhs; (void)nrhs;
    hystcomp_model_free(model);
    if (status != HYSTCOMP_STATUS_OK) {
        fail_status(status);
    }
}

/* hystcomp_mex('check_model', model) -> the model struct as the library reads it back. */
static void cmd_check_model(int nlhs, mxArray *plhs[], int nrhs, const mxArray *prhs[]) {
    (void)nlhs; (void)nrhs;
    plhs[0] = model_struct(model_from(prhs[1]));
}

/* hystcomp_mex('predict', model, x) -> the model's output (the whole chain), from rest. */
static void cmd_predict(int nlhs, mxArray *plhs[], int nrhs, const mxArray *prhs[]) {
    size_t n;
    const double *x = signal(prhs[2], "the model input", &n);
    /* Outputs are allocated before any library handle exists: nothing can leak if MATLAB
     * runs out of memory. */
    mxArray *y = like_shape(prhs[2], n);
    HystcompModel *model = model_from(prhs[1]);
    int status = hystcomp_model_predict(model, x, n, mxGetPr(y), n);
    (void)nlhs; (void)nrhs;
    hystcomp_model_free(model);
    if (status != HYSTCOMP_STATUS_OK) {
        mxDestroyArray(y);
        fail_status(status);
    }
    plhs[0] = y;
}

static mxArray *diagnostics_struct(double saturated, double loop_saturated, double non_finite,
                                   double lo, double hi) {
    static const char *names[] = {"saturated", "loop_saturated", "non_finite", "limits"};
    mxArray *d = mxCreateStructMatrix(1, 1, 4, names), *limits;
    mxSetField(d, 0, "saturated", mxCreateDoubleScalar(saturated));
    mxSetField(d, 0, "loop_saturated", mxCreateDoubleScalar(loop_saturated));
    mxSetField(d, 0, "non_finite", mxCreateDoubleScalar(non_finite));
    limits = mxCreateDoubleMatrix(1, 2, mxREAL);
    mxGetPr(limits)[0] = lo;
    mxGetPr(limits)[1] = hi;
    mxSetField(d, 0, "limits", limits);
    return d;
}

/* hystcomp_mex('compensate', model, method, yd, limits) -> [v, diagnostics]. */
static void cmd_compensate(int nlhs, mxArray *plhs[], int nrhs, const mxArray *prhs[]) {
    size_t n;
    double lo, hi;
    char *method = string(prhs[2], "the method");
    const double *yd = signal(prhs[3], "the desired trajectory", &n);
    int use_limits = limits_arg(nrhs, prhs, 4, &lo, &hi);
    mxArray *v = like_shape(prhs[3], n);
    HystcompModel *model = model_from(prhs[1]);
    HystcompDiagnostics d;
    int status = hystcomp_compensate(model, method, lo, hi, use_limits, yd, n, mxGetPr(v), n, &d);
    hystcomp_model_free(model);
    if (status != HYSTCOMP_STATUS_OK) {
        mxDestroyArray(v);
        fail_status(status);
    }
    plhs[0] = v;
    if (nlhs > 1) {
        plhs[1] = diagnostics_struct((double)d.saturated, (double)d.loop_saturated,
                                     (double)d.non_finite, d.v_min, d.v_max);
    }
}

/* hystcomp_mex('compensator_new', model, method, limits, allow_unstable_delay) -> id. A plain
 * delayed method whose loop can oscillate (gain >= 1) is refused (hystcomp:unstableDelay)
 * unless allow_unstable_delay is true. */
static void cmd_compensator_new(int nlhs, mxArray *plhs[], int nrhs, const mxArray *prhs[]) {
    double lo, hi;
    char *method = string(prhs[2], "the method");
    int use_limits = limits_arg(nrhs, prhs, 3, &lo, &hi);
    int flags = (nrhs > 4 && flag(prhs[4], "AllowUnstableDelay")) ? HYSTCOMP_ALLOW_UNSTABLE_DELAY
                                                                   : 0;
    /* Allocated before the compensator exists, so that no error can leak it. */
    mxArray *id = mxCreateNumericMatrix(1, 1, mxUINT64_CLASS, mxREAL);
    HystcompModel *model = model_from(prhs[1]);
    HystcompCompensator *c = NULL;
    int status =
        hystcomp_compensator_from_model_with(model, method, lo, hi, use_limits, flags, &c);
    (void)nlhs;
    hystcomp_model_free(model);
    if (status != HYSTCOMP_STATUS_OK) {
        mxDestroyArray(id);
        fail_status(status);
    }
    *(uint64_t *)mxGetData(id) = handle_store(c);
    plhs[0] = id;
}

/* hystcomp_mex('compensator_step', id, yd) -> v. */
static void cmd_compensator_step(int nlhs, mxArray *plhs[], int nrhs, const mxArray *prhs[]) {
    HystcompCompensator *c = handle_get(prhs[1]);
    double yd = finite_scalar(prhs[2], "the desired position"), v = 0.0;
    int status = hystcomp_compensator_step(c, yd, &v);
    (void)nlhs; (void)nrhs;
    if (status != HYSTCOMP_STATUS_OK) {
        fail_status(status);
    }
    plhs[0] = mxCreateDoubleScalar(v);
}

/* hystcomp_mex('compensator_process', id, yd) -> v. */
static void cmd_compensator_process(int nlhs, mxArray *plhs[], int nrhs,
                                    const mxArray *prhs[]) {
    HystcompCompensator *c = handle_get(prhs[1]);
    size_t n;
    const double *yd = signal(prhs[2], "the desired trajectory", &n);
    mxArray *v = like_shape(prhs[2], n);
    int status = hystcomp_compensator_process(c, yd, mxGetPr(v), n);
    (void)nlhs; (void)nrhs;
    if (status != HYSTCOMP_STATUS_OK) {
        mxDestroyArray(v);
        fail_status(status);
    }
    plhs[0] = v;
}

/* hystcomp_mex('compensator_reset', id). */
static void cmd_compensator_reset(int nlhs, mxArray *plhs[], int nrhs, const mxArray *prhs[]) {
    int status = hystcomp_compensator_reset(handle_get(prhs[1]));
    (void)nlhs; (void)plhs; (void)nrhs;
    if (status != HYSTCOMP_STATUS_OK) {
        fail_status(status);
    }
}

/* hystcomp_mex('compensator_diagnostics', id) -> struct (counts since the last reset, limits,
 * the delayed WIHC's worst-case loop gain or NaN, the vibration inverse's preview in samples:
 * streaming, the drive lags the desired position by it). */
static void cmd_compensator_diagnostics(int nlhs, mxArray *plhs[], int nrhs,
                                        const mxArray *prhs[]) {
    HystcompCompensator *c = handle_get(prhs[1]);
    uint64_t saturated = 0, non_finite = 0, loop_saturated = 0;
    size_t preview = 0;
    double lo = 0.0, hi = 0.0, gain = mxGetNaN();
    int status = hystcomp_compensator_diagnostics(c, &saturated, &non_finite);
    (void)nlhs; (void)nrhs;
    if (status == HYSTCOMP_STATUS_OK) {
        status = hystcomp_compensator_loop_saturated(c, &loop_saturated);
    }
    if (status == HYSTCOMP_STATUS_OK) {
        status = hystcomp_compensator_limits(c, &lo, &hi);
    }
    if (status == HYSTCOMP_STATUS_OK) {
        status = hystcomp_compensator_preview(c, &preview);
    }
    if (status != HYSTCOMP_STATUS_OK) {
        fail_status(status);
    }
    /* Only the delayed and guarded loops have a delayed loop gain; the others answer
     * INVALID_ARGUMENT, which here means "not applicable". */
    if (hystcomp_compensator_delayed_loop_gain(c, &gain) != HYSTCOMP_STATUS_OK) {
        gain = mxGetNaN();
    }
    plhs[0] = diagnostics_struct((double)saturated, (double)loop_saturated, (double)non_finite,
                                 lo, hi);
    mxAddField(plhs[0], "delayed_loop_gain");
    mxSetField(plhs[0], 0, "delayed_loop_gain", mxCreateDoubleScalar(gain));
    mxAddField(plhs[0], "preview");
    mxSetField(plhs[0], 0, "preview", mxCreateDoubleScalar((double)preview));
}

/* hystcomp_mex('compensator_free', id): frees a live compensator; an id that is not alive is
 * ignored (a destructor must not fail), and reported by the output (true when freed). */
static void cmd_compensator_free(int nlhs, mxArray *plhs[], int nrhs, const mxArray *prhs[]) {
    int freed = handle_free(prhs[1]);
    (void)nrhs;
    if (nlhs > 0) {
        plhs[0] = mxCreateLogicalScalar(freed != 0);
    }
}

/* hystcomp_mex('live_compensators') -> how many compensators are alive (for tests). */
static void cmd_live_compensators(int nlhs, mxArray *plhs[], int nrhs, const mxArray *prhs[]) {
    (void)nlhs; (void)nrhs; (void)prhs;
    plhs[0] = mxCreateDoubleScalar((double)handle_count());
}

typedef int (*Index)(const double *, size_t, const double *, size_t, double *);

static void index_command(mxArray *plhs[], int nrhs, const mxArray *prhs[], Index index,
                          int with_bins) {
    size_t nd, ny;
    const double *yd = signal(prhs[1], "the desired trajectory", &nd);
    const double *y = signal(prhs[2], "the measured response", &ny);
    double percent = 0.0;
    int status;
    if (nd != ny) {
        fail("hystcomp:lengthMismatch", "the desired trajectory has %lu samples but the measured "
             "response has %lu; give records of equal length", (unsigned long)nd,
             (unsigned long)ny);
    }
    if (with_bins) {
        size_t bins = HYSTCOMP_DEFAULT_MHE_BINS;
        if (nrhs > 3 && !mxIsEmpty(prhs[3])) {
            bins = count(prhs[3], "bins", 9007199254740992.0);
        }
        status = hystcomp_e_mhe(yd, nd, y, ny, bins, &percent);
    } else {
        status = index(yd, nd, y, ny, &percent);
    }
    if (status != HYSTCOMP_STATUS_OK) {
        fail_status(status);
    }
    plhs[0] = mxCreateDoubleScalar(percent);
}

static void cmd_e_m(int nlhs, mxArray *plhs[], int nrhs, const mxArray *prhs[]) {
    (void)nlhs;
    index_command(plhs, nrhs, prhs, hystcomp_e_m, 0);
}

static void cmd_e_rms(int nlhs, mxArray *plhs[], int nrhs, const mxArray *prhs[]) {
    (void)nlhs;
    index_command(plhs, nrhs, prhs, hystcomp_e_rms, 0);
}

static void cmd_e_mhe(int nlhs, mxArray *plhs[], int nrhs, const mxArray *prhs[]) {
    (void)nlhs;
    index_command(plhs, nrhs, prhs, NULL, 1);
}

/* ------------------------------------------------------------------------------------------ */
/* Dispatch                                                                                    */
/* ------------------------------------------------------------------------------------------ */

typedef struct {
    const char *name;
    int min_in, max_in; /* arguments after the command name */
    int max_out;
    Command run;
    const char *usage;
} Entry;

static const Entry COMMANDS[] = {
    {"version", 0, 0, 1, cmd_version, "hystcomp_mex('version')"},
    {"identify", 2, 2 + 2 * 16, 1, cmd_identify,
     "hystcomp.identify(v, y, name, value, ...)"},
    {"load_model", 1, 1, 1, cmd_load_model, "hystcomp.load_model(file)"},
    {"save_model", 2, 2, 0, cmd_save_model, "hystcomp.save_model(model, file)"},
    {"check_model", 1, 1, 1, cmd_check_model, "hystcomp_mex('check_model', model)"},
    {"predict", 2, 2, 1, cmd_predict, "hystcomp.predict(model, x)"},
    {"compensate", 3, 4, 2, cmd_compensate,
     "hystcomp.compensate(model, method, yd, [v_min v_max])"},
    {"compensator_new", 2, 4, 1, cmd_compensator_new,
     "hystcomp.Compensator(model, method, [v_min v_max], 'AllowUnstableDelay', false)"},
    {"compensator_step", 2, 2, 1, cmd_compensator_step, "c.step(yd)"},
    {"compensator_process", 2, 2, 1, cmd_compensator_process, "c.process(yd)"},
    {"compensator_reset", 1, 1, 0, cmd_compensator_reset, "c.reset()"},
    {"compensator_diagnostics", 1, 1, 1, cmd_compensator_diagnostics, "c.diagnostics()"},
    {"compensator_free", 1, 1, 1, cmd_compensator_free, "delete(c)"},
    {"live_compensators", 0, 0, 1, cmd_live_compensators, "hystcomp_mex('live_compensators')"},
    {"e_m", 2, 2, 1, cmd_e_m, "hystcomp.e_m(yd, y)"},
    {"e_rms", 2, 2, 1, cmd_e_rms, "hystcomp.e_rms(yd, y)"},
    {"e_mhe", 2, 3, 1, cmd_e_mhe, "hystcomp.e_mhe(yd, y, bins)"},
};

void mexFunction(int nlhs, mxArray *plhs[], int nrhs, const mxArray *prhs[]) {
    char name[64];
    size_t k;
    if (nrhs < 1 || !mxIsChar(prhs[0]) || mxGetNumberOfElements(prhs[0]) >= sizeof name ||
        mxGetString(prhs[0], name, sizeof name) != 0) {
        fail("hystcomp:unknownCommand", "hystcomp_mex is called by the +hystcomp package: "
             "hystcomp_mex(COMMAND, ...) with COMMAND a text such as 'identify'");
    }
    for (k = 0; k < sizeof COMMANDS / sizeof COMMANDS[0]; k++) {
        const Entry *e = &COMMANDS[k];
        if (strcmp(e->name, name) != 0) {
            continue;
        }
        if (nrhs - 1 < e->min_in) {
            fail("hystcomp:nargin", "not enough input arguments: %s", e->usage);
        }
        if (nrhs - 1 > e->max_in) {
            fail("hystcomp:nargin", "too many input arguments: %s", e->usage);
        }
        if (nlhs > e->max_out) {
            fail("hystcomp:nargout", "too many output arguments: %s returns %d", e->usage,
                 e->max_out);
        }
        e->run(nlhs, plhs, nrhs, prhs);
        return;
    }
    fail("hystcomp:unknownCommand", "hystcomp_mex has no command '%s'", name);
}
