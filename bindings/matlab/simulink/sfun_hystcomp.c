/*
 * sfun_hystcomp: a Simulink C S-function (level 2) running a hystcomp feedforward compensator,
 * one sample per time step: desired position in (input port 1, scalar), drive voltage out
 * (output port 1, scalar), through the C ABI's step function (hystcomp_compensator_step).
 *
 * Parameters (S-function block, "S-function parameters" field):
 *   1  model file name   a JSON model file, e.g. 'plant.json' (from hystcomp.save_model or
 *                        `hystcomp identify`)
 *   2  method            'ihc', 'ihc-delayed', 'wihc', 'wihc-delayed', 'ihc-guarded',
 *                        'wihc-guarded' or 'dihc' (a plain delayed loop that can oscillate
 *                        is refused: use the guarded one)
 *   3  drive limits      [v_min v_max] in the model's voltage unit, or [] for the range the
 *                        model was identified on
 *   4  sample time       in s (> 0), e.g. 1e-4 for a 10 kHz loop
 * e.g.  'plant.json', 'ihc', [0 10], 1e-4
 *
 * The compensator is created in mdlStart (model errors, e.g. a model not invertible over the
 * limits, stop the simulation with the library's message) and freed in mdlTerminate. Every
 * output lies within the limits and is never NaN; a NaN or infinite input holds the previous
 * output (the library's behaviour for real-time loops). The S-function allocates nothing per
 * step.
 *
 * Build (MATLAB, from bindings/matlab, after `cargo build --release -p hystcomp-c`):
 *   mex -I../c/include simulink/sfun_hystcomp.c ../../target/release/libhystcomp.a
 *       -lpthread -ldl -lm
 * The hystcomp tests compile this file with Octave's mkoctfile against a stand-in of
 * simstruc.h (tests/simulink_stub) and drive it step by step (Simulink itself cannot run
 * there); see README.md for the MATLAB Function block and code generation.
 */
#define S_FUNCTION_NAME sfun_hystcomp
#define S_FUNCTION_LEVEL 2

#include <stdio.h>

#include "simstruc.h"

#include "hystcomp.h"

enum { PARAM_MODEL, PARAM_METHOD, PARAM_LIMITS, PARAM_SAMPLE_TIME, PARAM_COUNT };

/* Simulink keeps the pointer given to ssSetErrorStatus: the message must outlive the call. */
static char error_message[1024];

static void set_error(SimStruct *S, const char *what) {
    snprintf(error_message, sizeof error_message, "sfun_hystcomp: %s", what);
    ssSetErrorStatus(S, error_message);
}

#define MDL_CHECK_PARAMETERS
/* Checks the classes and sizes of the parameters (their values are checked by the library in
 * mdlStart). */
static void mdlCheckParameters(SimStruct *S) {
    const mxArray *limits = ssGetSFcnParam(S, PARAM_LIMITS);
    const mxArray *ts = ssGetSFcnParam(S, PARAM_SAMPLE_TIME);
    if (!mxIsChar(ssGetSFcnParam(S, PARAM_MODEL))) {
        set_error(S, "parameter 1 must be the model file's name (text)");
        return;
    }
    if (!mxIsChar(ssGetSFcnParam(S, PARAM_METHOD))) {
        set_error(S, "parameter 2 must be the method (text): 'ihc', 'ihc-delayed', 'wihc', "
                     "'wihc-delayed', 'ihc-guarded', 'wihc-guarded' or 'dihc'");
        return;
    }
    if (!mxIsDouble(limits) || mxIsComplex(limits) ||
        (mxGetNumberOfElements(limits) != 0 && mxGetNumberOfElements(limits) != 2)) {
        set_error(S, "parameter 3 must be the drive limits [v_min v_max] or []");
        return;
    }
    if (!mxIsDouble(ts) || mxIsComplex(ts) || mxGetNumberOfElements(ts) != 1 ||
        !(mxGetPr(ts)[0] > 0.0)) {
        set_error(S, "parameter 4 must be the sample time in s (> 0)");
        return;
    }
}

static void mdlInitializeSizes(SimStruct *S) {
    int k;
    ssSetNumSFcnParams(S, PARAM_COUNT);
    if (ssGetNumSFcnParams(S) != ssGetSFcnParamsCount(S)) {
        return; /* Simulink reports the wrong number of parameters */
    }
    mdlCheckParameters(S);
    if (ssGetErrorStatus(S) != NULL) {
        return;
    }
    for (k = 0; k < PARAM_COUNT; k++) {
        ssSetSFcnParamTunable(S, k, SS_PRM_NOT_TUNABLE);
    }
    ssSetNumContStates(S, 0);
    ssSetNumDiscStates(S, 0);
    if (!ssSetNumInputPorts(S, 1)) {
        return;
    }
    ssSetInputPortWidth(S, 0, 1);
    ssSetInputPortDirectFeedThrough(S, 0, 1);
    if (!ssSetNumOutputPorts(S, 1)) {
        return;
    }
    ssSetOutputPortWidth(S, 0, 1);
    ssSetNumSampleTimes(S, 1);
    ssSetNumPWork(S, 1); /* the compensator */
    ssSetOptions(S, SS_OPTION_CALL_TERMINATE_ON_EXIT);
}

static void mdlInitializeSampleTimes(SimStruct *S) {
    ssSetSampleTime(S, 0, mxGetPr(ssGetSFcnParam(S, PARAM_SAMPLE_TIME))[0]);
    ssSetOffsetTime(S, 0, 0.0);
}

#define MDL_START
static void mdlStart(SimStruct *S) {
    char path[4096], method[32];
    const mxArray *limits = ssGetSFcnParam(S, PARAM_LIMITS);
    HystcompCompensator *c = NULL;
    int use_limits = mxGetNumberOfElements(limits) == 2;
    double lo = use_limits ? mxGetPr(limits)[0] : 0.0;
    double hi = use_limits ? mxGetPr(limits)[1] : 0.0;
    int status;
    ssGetPWork(S)[0] = NULL;
    if (mxGetString(ssGetSFcnParam(S, PARAM_MODEL), path, sizeof path) != 0 ||
        mxGetString(ssGetSFcnParam(S, PARAM_METHOD), method, sizeof method) != 0) {
        set_error(S, "the model file's name or the method is too long");
        return;
    }
    status = hystcomp_compensator_from_model_file(path, method, lo, hi, use_limits, &c);
    if (status != HYSTCOMP_STATUS_OK) {
        set_error(S, hystcomp_last_error_message());
        return;
    }
    ssGetPWork(S)[0] = c;
}

static void mdlOutputs(SimStruct *S, int_T tid) {
    InputRealPtrsType u = ssGetInputPortRealSignalPtrs(S, 0);
    real_T *y = ssGetOutputPortRealSignal(S, 0);
    HystcompCompensator *c = (HystcompCompensator *)ssGetPWork(S)[0];
    double v = 0.0;
    (void)tid;
    /* NON_FINITE_INPUT still writes the held output, within the limits: nothing to do. */
    (void)hystcomp_compensator_step(c, *u[0], &v);
    y[0] = v;
}

static void mdlTerminate(SimStruct *S) {
    hystcomp_compensator_free((HystcompCompensator *)ssGetPWork(S)[0]);
    ssGetPWork(S)[0] = NULL;
}

#ifdef MATLAB_MEX_FILE
#include "simulink.c" /* the MEX-file interface of a Simulink S-function */
#else
#include "cg_sfun.h" /* code generation */
#endif
