/*
 * Model structs of the hystcomp MEX gateway: a MATLAB struct (direction, description, input,
 * output, input_range, thresholds, weights, a1, a2, sample_rate_hz, creep, vibration,
 * identification, report) to and from the C
 * library's HystcompModel, by its values (hystcomp_model_values, hystcomp_model_from_values).
 * The gateway checks classes and shapes; the library checks the values.
 */
#include <stdio.h>
#include <string.h>

#include "gateway.h"

/* The field `name` of the 1x1 struct `s`, or an error (hystcomp:invalidModel). */
static const mxArray *field(const mxArray *s, const char *name, const char *what) {
    const mxArray *f = mxGetField(s, 0, name);
    if (f == NULL) {
        fail("hystcomp:invalidModel", "%s has no field '%s'", what, name);
    }
    return f;
}

/* The scale struct `name` (quantity, unit, offset, scale) of the model struct `s`. */
static HystcompScale scale_from(const mxArray *s, const char *name) {
    HystcompScale scale;
    char what[64];
    const mxArray *f = field(s, name, "the model");
    if (!mxIsStruct(f) || mxGetNumberOfElements(f) != 1) {
        fail("hystcomp:invalidModel", "model.%s must be a struct with fields quantity, unit, "
             "offset and scale", name);
    }
    snprintf(what, sizeof what, "model.%s.quantity", name);
    scale.quantity = string(field(f, "quantity", "the scale"), what);
    snprintf(what, sizeof what, "model.%s.unit", name);
    scale.unit = string(field(f, "unit", "the scale"), what);
    snprintf(what, sizeof what, "model.%s.offset", name);
    scale.offset = scalar(field(f, "offset", "the scale"), what);
    snprintf(what, sizeof what, "model.%s.scale", name);
    scale.scale = scalar(field(f, "scale", "the scale"), what);
    return scale;
}

/* An optional text field of the model struct: NULL when absent or empty. */
static const char *optional_text(const mxArray *s, const char *name, const char *what) {
    const mxArray *f = mxGetField(s, 0, name);
    if (f == NULL || mxIsEmpty(f)) {
        return NULL;
    }
    return string(f, what);
}

/* A double array field of a link struct: its values and their number (0 for []). */
static const double *numbers(const mxArray *link, const char *name, const char *what,
                             size_t *len) {
    const mxArray *f = field(link, name, what);
    char full[96];
    snprintf(full, sizeof full, "%s.%s", what, name);
    require_double(f, full);
    *len = mxGetNumberOfElements(f);
    return *len > 0 ? mxGetPr(f) : NULL;
}

/* An optional link struct field (creep, vibration): NULL when absent or []. */
static const mxArray *optional_link(const mxArray *s, const char *name) {
    const mxArray *f = mxGetField(s, 0, name);
    if (f == NULL || mxIsEmpty(f)) {
        return NULL;
    }
    if (!mxIsStruct(f) || mxGetNumberOfElements(f) != 1) {
        fail("hystcomp:invalidModel", "model.%s must be a 1x1 struct or [], not %s", name,
             mxGetClassName(f));
    }
    return f;
}

/* The creep and vibration links (format version 2) of the model struct `s` into `values`. */
static void links_from(const mxArray *s, HystcompModelValues *values) {
    static const double empty = 0.0;
    const mxArray *rate = mxGetField(s, 0, "sample_rate_hz");
    const mxArray *creep = optional_link(s, "creep");
    const mxArray *vibration = optional_link(s, "vibration");
    if (rate != NULL && !mxIsEmpty(rate)) {
        values->sample_rate_hz = scalar(rate, "model.sample_rate_hz");
    }
    if (creep != NULL) {
        size_t n = 0, m = 0;
        values->creep_origin = scalar(field(creep, "origin", "model.creep"), "model.creep.origin");
        values->creep_time_constants_s = numbers(creep, "time_constants_s", "model.creep", &n);
        values->creep_weights = numbers(creep, "weights", "model.creep", &m);
        if (n != m || n == 0) {
            fail("hystcomp:invalidModel", "model.creep has %d time constants and %d weights; "
                 "give one weight per time constant, at least one", (int)n, (int)m);
        }
        values->creep_elements = n;
    }
    if (vibration != NULL) {
        size_t n = 0, m = 0;
        values->vibration_delay_samples =
            count(field(vibration, "delay_samples", "model.vibration"),
                  "model.vibration.delay_samples", 1e6);
        values->vibration_numerator = numbers(vibration, "numerator", "model.vibration", &n);
        values->vibration_denominator = numbers(vibration, "denominator", "model.vibration", &m);
        if (n == 0) {
            fail("hystcomp:invalidModel", "model.vibration.numerator is empty");
        }
        values->vibration_numerator_len = n;
        values->vibration_denominator_len = m;
        if (m == 0) {
            values->vibration_denominator = &empty; /* refused by the library, not NULL */
        }
    }
}

/* As hystcomp.identify and hystcomp.load_model return it, possibly edited by the user. */
HystcompModel *model_from(const mxArray *s) {
    HystcompModelValues values;
    HystcompModel *model = NULL;
    const mxArray *range, *thresholds, *weights;
    char *direction;
    int status;
    if (mxIsChar(s)) {
        /* A model file's path. */
        status = hystcomp_model_load(string(s, "the model file name"), &model);
        if (status != HYSTCOMP_STATUS_OK) {
            fail_status(status);
        }
        return model;
    }
    if (!mxIsStruct(s) || mxGetNumberOfElements(s) != 1) {
        fail("hystcomp:invalidModel", "the model must be a 1x1 struct (from hystcomp.identify "
             "or hystcomp.load_model) or a model file's name, not %s", mxGetClassName(s));
    }
    memset(&values, 0, sizeof values);
    direction = string(field(s, "direction", "the model"), "model.direction");
    if (same_name(direction, "plant")) {
        values.direction = HYSTCOMP_DIRECTION_PLANT;
    } else if (same_name(direction, "inverse")) {
        values.direction = HYSTCOMP_DIRECTION_INVERSE;
    } else {
        fail("hystcomp:invalidModel", "model.direction is '%s'; give 'plant' or 'inverse'",
             direction);
    }
    values.input = scale_from(s, "input");
    values.output = scale_from(s, "output");
    range = field(s, "input_range", "the model");
    require_double(range, "model.input_range");
    if (mxGetNumberOfElements(range) != 2) {
        fail("hystcomp:invalidModel", "model.input_range must hold 2 values, not %d",
             (int)mxGetNumberOfElements(range));
    }
    values.input_range_min = mxGetPr(range)[0];
    values.input_range_max = mxGetPr(range)[1];
    thresholds = field(s, "thresholds", "the model");
    weights = field(s, "weights", "the model");
    require_double(thresholds, "model.thresholds");
    require_double(weights, "model.weights");
    if (mxGetNumberOfElements(thresholds) != mxGetNumberOfElements(weights)) {
        fail("hystcomp:invalidModel", "model.thresholds has %d values but model.weights has %d; "
             "give one weight per threshold", (int)mxGetNumberOfElements(thresholds),
             (int)mxGetNumberOfElements(weights));
    }
    values.operators = mxGetNumberOfElements(thresholds);
    /* The library refuses NULL arrays: give it a valid pointer even for 0 operators. */
    values.thresholds = values.operators ? mxGetPr(thresholds) : &values.a1;
    values.weights = values.operators ? mxGetPr(weights) : &values.a1;
    values.a1 = scalar(field(s, "a1", "the model"), "model.a1");
    values.a2 = scalar(field(s, "a2", "the model"), "model.a2");
    values.description = optional_text(s, "description", "model.description");
    values.identification_json = optional_text(s, "identification", "model.identification");
    links_from(s, &values);
    status = hystcomp_model_from_values(&values, &model);
    if (status != HYSTCOMP_STATUS_OK) {
        fail_status(status);
    }
    return model;
}

static mxArray *column(const double *x, size_t n) {
    mxArray *a = mxCreateDoubleMatrix(n, 1, mxREAL);
    if (n > 0) {
        memcpy(mxGetPr(a), x, n * sizeof *x);
    }
    return a;
}

static mxArray *text_or_empty(const char *s) {
    return mxCreateString(s == NULL ? "" : s);
}

static mxArray *scale_struct(const HystcompScale *scale) {
    static const char *names[] = {"quantity", "unit", "offset", "scale"};
    mxArray *s = mxCreateStructMatrix(1, 1, 4, names);
    mxSetField(s, 0, "quantity", text_or_empty(scale->quantity));
    mxSetField(s, 0, "unit", text_or_empty(scale->unit));
    mxSetField(s, 0, "offset", mxCreateDoubleScalar(scale->offset));
    mxSetField(s, 0, "scale", mxCreateDoubleScalar(scale->scale));
    return s;
}

/* A link's struct, e.g. creep: origin, time_constants_s, weights. */
static mxArray *link_struct(int count, const char **names, mxArray **values) {
    mxArray *s = mxCreateStructMatrix(1, 1, count, names);
    int k;
    for (k = 0; k < count; k++) {
        mxSetField(s, 0, names[k], values[k]);
    }
    return s;
}

mxArray *model_struct(HystcompModel *model) {
    static const char *names[] = {"direction", "description", "input", "output", "input_range",
                                  "thresholds", "weights", "a1", "a2", "sample_rate_hz", "creep",
                                  "vibration", "identification", "report"};
    static const char *creep_names[] = {"origin", "time_constants_s", "weights"};
    static const char *vibration_names[] = {"delay_samples", "numerator", "denominator"};
    HystcompModelValues v;
    mxArray *s, *range, *text, *report = NULL;
    int status = hystcomp_model_values(model, &v);
    if (status != HYSTCOMP_STATUS_OK) {
        hystcomp_model_free(model);
        fail_status(status);
    }
    s = mxCreateStructMatrix(1, 1, 14, names);
    mxSetField(s, 0, "direction",
               mxCreateString(v.direction == HYSTCOMP_DIRECTION_PLANT ? "plant" : "inverse"));
    mxSetField(s, 0, "description", text_or_empty(v.description));
    mxSetField(s, 0, "input", scale_struct(&v.input));
    mxSetField(s, 0, "output", scale_struct(&v.output));
    range = mxCreateDoubleMatrix(1, 2, mxREAL);
    mxGetPr(range)[0] = v.input_range_min;
    mxGetPr(range)[1] = v.input_range_max;
    mxSetField(s, 0, "input_range", range);
    mxSetField(s, 0, "thresholds", column(v.thresholds, v.operators));
    mxSetField(s, 0, "weights", column(v.weights, v.operators));
    mxSetField(s, 0, "a1", mxCreateDoubleScalar(v.a1));
    mxSetField(s, 0, "a2", mxCreateDoubleScalar(v.a2));
    /* The chain's links ([] without them). */
    mxSetField(s, 0, "sample_rate_hz", v.sample_rate_hz > 0.0
                                           ? mxCreateDoubleScalar(v.sample_rate_hz)
                                           : mxCreateDoubleMatrix(0, 0, mxREAL));
    if (v.creep_elements > 0) {
        mxArray *parts[3];
        parts[0] = mxCreateDoubleScalar(v.creep_origin);
        parts[1] = column(v.creep_time_constants_s, v.creep_elements);
        parts[2] = column(v.creep_weights, v.creep_elements);
        mxSetField(s, 0, "creep", link_struct(3, creep_names, parts));
    } else {
        mxSetField(s, 0, "creep", mxCreateDoubleMatrix(0, 0, mxREAL));
    }
    if (v.vibration_numerator_len > 0) {
        mxArray *parts[3];
        parts[0] = mxCreateDoubleScalar((double)v.vibration_delay_samples);
        parts[1] = column(v.vibration_numerator, v.vibration_numerator_len);
        parts[2] = column(v.vibration_denominator, v.vibration_denominator_len);
        mxSetField(s, 0, "vibration", link_struct(3, vibration_names, parts));
    } else {
        mxSetField(s, 0, "vibration", mxCreateDoubleMatrix(0, 0, mxREAL));
    }
    text = text_or_empty(v.identification_json);
    mxSetField(s, 0, "identification", text);
    hystcomp_model_free(model);
    /* The fit report (or whatever the file's identification holds) as a struct, decoded by
     * MATLAB's own jsondecode (MATLAB R2016b+, Octave 7+); [] when there is none. */
    if (!mxIsEmpty(text)) {
        mexCallMATLAB(1, &report, 1, &text, "jsondecode");
    }
    mxSetField(s, 0, "report", report != NULL ? report : mxCreateDoubleMatrix(0, 0, mxREAL));
    return s;
}
