/*
 * A stand-in for Simulink's simstruc.h, for tests only: just enough of the SimStruct API for
 * simulink/sfun_hystcomp.c to compile under Octave's mkoctfile and be driven step by step by
 * sfun_harness.c, as Simulink would drive it (Simulink cannot run on the test machine). It
 * follows the documented meaning of each macro; it is not MathWorks' header.
 */
#ifndef HYSTCOMP_SIMSTRUC_STUB_H
#define HYSTCOMP_SIMSTRUC_STUB_H

#include "mex.h"

typedef double real_T;
typedef int int_T;
typedef const real_T *const *InputRealPtrsType;

#define STUB_MAX_PARAMS 8
#define STUB_MAX_PWORK 4

typedef struct SimStruct {
    int params_expected;
    int params_given;
    const mxArray *params[STUB_MAX_PARAMS];
    int tunable[STUB_MAX_PARAMS];
    const char *error;
    int input_ports, output_ports, input_width, output_width, feedthrough;
    int sample_times, pwork_count;
    unsigned options;
    double sample_time, offset_time;
    void *pwork[STUB_MAX_PWORK];
    real_T input;
    const real_T *input_ptrs[1];
    real_T output[1];
} SimStruct;

#define SS_PRM_NOT_TUNABLE 0
#define SS_OPTION_CALL_TERMINATE_ON_EXIT 1u

#define ssSetNumSFcnParams(S, n) ((S)->params_expected = (n))
#define ssGetNumSFcnParams(S) ((S)->params_expected)
#define ssGetSFcnParamsCount(S) ((S)->params_given)
#define ssGetSFcnParam(S, k) ((S)->params[(k)])
#define ssSetSFcnParamTunable(S, k, t) ((S)->tunable[(k)] = (t))
#define ssSetErrorStatus(S, message) ((S)->error = (message))
#define ssGetErrorStatus(S) ((S)->error)
#define ssSetNumContStates(S, n) ((void)(S), (void)(n))
#define ssSetNumDiscStates(S, n) ((void)(S), (void)(n))
#define ssSetNumInputPorts(S, n) ((S)->input_ports = (n), 1)
#define ssSetNumOutputPorts(S, n) ((S)->output_ports = (n), 1)
#define ssSetInputPortWidth(S, port, w) ((void)(port), (S)->input_width = (w))
#define ssSetOutputPortWidth(S, port, w) ((void)(port), (S)->output_width = (w))
#define ssSetInputPortDirectFeedThrough(S, port, f) ((void)(port), (S)->feedthrough = (f))
#define ssSetNumSampleTimes(S, n) ((S)->sample_times = (n))
#define ssSetNumPWork(S, n) ((S)->pwork_count = (n))
#define ssGetPWork(S) ((S)->pwork)
#define ssSetOptions(S, o) ((S)->options = (o))
#define ssSetSampleTime(S, k, t) ((void)(k), (S)->sample_time = (t))
#define ssSetOffsetTime(S, k, t) ((void)(k), (S)->offset_time = (t))
#define ssGetInputPortRealSignalPtrs(S, port) ((void)(port), (InputRealPtrsType)(S)->input_ptrs)
#define ssGetOutputPortRealSignal(S, port) ((void)(port), (S)->output)

#endif
