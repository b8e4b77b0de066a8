/*
 * sfun_harness: a MEX function that drives simulink/sfun_hystcomp.c as Simulink would (for
 * tests; Simulink cannot run on the test machine), against the stand-in simstruc.h beside it:
 *
 *   [V, TS] = sfun_harness(MODEL_FILE, METHOD, LIMITS, SAMPLE_TIME, YD)
 *
 * calls mdlInitializeSizes (checking the parameters), mdlInitializeSampleTimes, mdlStart, then
 * mdlOutputs once per sample of YD, then mdlTerminate, and returns the outputs and the sample
 * time the S-function set. An error status set by the S-function becomes the MATLAB error
 * hystcomp:sfunction with its message.
 */
#include <string.h>

#include "simstruc.h"

#include "../../simulink/sfun_hystcomp.c"

void mexFunction(int nlhs, mxArray *plhs[], int nrhs, const mxArray *prhs[]) {
    SimStruct S;
    const double *yd;
    double *v;
    size_t n, k;
    int p;
    memset(&S, 0, sizeof S);
    S.params_given = nrhs - 1;
    for (p = 0; p < nrhs - 1 && p < STUB_MAX_PARAMS; p++) {
        S.params[p] = prhs[p];
    }
    if (nrhs < 1 || !mxIsDouble(prhs[nrhs - 1]) || mxIsComplex(prhs[nrhs - 1])) {
        mexErrMsgIdAndTxt("hystcomp:nargin", "sfun_harness(MODEL, METHOD, LIMITS, TS, YD)");
    }
    mdlInitializeSizes(&S);
    if (S.params_expected != S.params_given) {
        mexErrMsgIdAndTxt("hystcomp:sfunction", "the S-function expects %d parameters, not %d",
                          S.params_expected, S.params_given);
    }
    if (S.error != NULL) {
        mexErrMsgIdAndTxt("hystcomp:sfunction", "%s", S.error);
    }
    if (S.input_ports != 1 || S.output_ports != 1 || S.input_width != 1 ||
        S.output_width != 1 || S.feedthrough != 1 || S.sample_times != 1 || S.pwork_count != 1) {
        mexErrMsgIdAndTxt("hystcomp:sfunction", "unexpected sizes from mdlInitializeSizes");
    }
    mdlInitializeSampleTimes(&S);
    mdlStart(&S);
    if (S.error != NULL) {
        mdlTerminate(&S);
        mexErrMsgIdAndTxt("hystcomp:sfunction", "%s", S.error);
    }
    n = mxGetNumberOfElements(prhs[nrhs - 1]);
    yd = mxGetPr(prhs[nrhs - 1]);
    plhs[0] = mxCreateDoubleMatrix(n, 1, mxREAL);
    v = mxGetPr(plhs[0]);
    S.input_ptrs[0] = &S.input;
    for (k = 0; k < n; k++) {
        S.input = yd[k];
        mdlOutputs(&S, 0);
        v[k] = S.output[0];
    }
    mdlTerminate(&S);
    if (nlhs > 1) {
        plhs[1] = mxCreateDoubleScalar(S.sample_time);
    }
}
