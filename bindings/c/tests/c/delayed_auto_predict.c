/*
 * Issue 10's identification options and the prediction of a record, called from C: a record
 * of Table 1's MPIM identified with the delayed-loop bound (for_delayed: the report says the
 * bound and what it cost, and the model's plain delayed WIHC can then be built), with the number
 * of play operators chosen by held-out error (operators_auto: the report names the choice),
 * and hystcomp_predict of the record (predicted and error per sample, equal to
 * hystcomp_model_predict's output minus the measurement; the summary's RMS from them), with its
 * refusals. Compiled with -Wall -Wextra -Werror -pedantic and run (also under valgrind) by
 * bindings/c/tests/c_example.rs; prints "delayed_auto_predict OK" and exits 0 when every check
 * passes.
 */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "check.h"
#include "hystcomp.h"

#define N 4000

static const double THRESHOLDS[10] = {0.0, 0.1, 0.2, 0.3, 0.4, 0.5, 0.6, 0.7, 0.8, 0.9};
static const double WEIGHTS[10] = {0.2313, 0.3059, 0.0155, 0.0752, 0.0683,
                                   0.0252, 0.0035, 0.0094, 0.0264, 0.0032};

int main(void) {
    static double volts[N], um[N], predicted[N], error[N], forward[N];
    HystcompMpim *table1 = NULL;
    HystcompModel *free_fit = NULL, *bounded = NULL, *chosen = NULL;
    HystcompCompensator *wihc = NULL;
    HystcompFitReport free_report, report, auto_report;
    HystcompIdentifyOptions options;
    HystcompPrediction summary;
    double pi = acos(-1.0), sum = 0.0, lo = INFINITY, hi = -INFINITY, worst = 0.0;
    size_t k;

    /* A record of Table 1 (0 .. 10 V -> 0 .. 75 um) with a sensor offset of 12 um. */
    CHECK(hystcomp_mpim_from_parameters(THRESHOLDS, WEIGHTS, 10, -0.1569, 0.4603, &table1) ==
          HYSTCOMP_STATUS_OK);
    for (k = 0; k < N; k++) {
        double t = (double)k / 200.0;
        double y = 0.0;
        volts[k] = 5.0 - 5.0 * exp(-t / 10.0) * cos(2.0 * pi * t);
        CHECK(hystcomp_mpim_step(table1, volts[k] / 10.0, &y) == HYSTCOMP_STATUS_OK);
        um[k] = 12.0 + 75.0 * y;
    }
    hystcomp_mpim_free(table1);

    /* The defaults leave both new options off. */
    CHECK(hystcomp_identify_options_default(&options) == HYSTCOMP_STATUS_OK);
    CHECK(options.for_delayed == 0 && options.operators_auto == 0);
    CHECK(options.delayed_loop_bound > 0.0 && options.delayed_loop_bound < 1.0);
    CHECK(hystcomp_identify(volts, N, um, N, &options, &free_fit, &free_report) ==
          HYSTCOMP_STATUS_OK);
    CHECK(isnan(free_report.delayed_loop_bound) && free_report.operators == 10);
    /* Table 1's delayed WIHC rings (gain 1.66): refused on the free fit. */
    CHECK(hystcomp_compensator_from_model(free_fit, "wihc-delayed", 0.0, 10.0, 1,
                                          &wihc) == HYSTCOMP_STATUS_UNSTABLE_DELAY);
    CHECK(wihc == NULL);

    /* for_delayed: the bound and its cost in the report; the delayed WIHC builds. */
    options.for_delayed = 1;
    options.delayed_loop_bound = 0.9;
    CHECK(hystcomp_identify(volts, N, um, N, &options, &bounded, &report) == HYSTCOMP_STATUS_OK);
    CHECK(report.delayed_loop_bound == 0.9);
    CHECK(fabs(report.unconstrained_fit_rms_percent - free_report.fit.rms_percent) < 1e-9);
    CHECK(report.fit.rms_percent >= report.unconstrained_fit_rms_percent - 1e-12);
    CHECK(report.fit.rms_percent < 10.0);
    CHECK(hystcomp_compensator_from_model(bounded, "wihc-delayed", 0.0, 10.0, 1,
                                          &wihc) == HYSTCOMP_STATUS_OK);
    hystcomp_compensator_free(wihc);
    /* A bound outside (0, 1) is refused, naming it. */
    options.delayed_loop_bound = 1.5;
    CHECK(hystcomp_identify(volts, N, um, N, &options, &chosen, NULL) ==
          HYSTCOMP_STATUS_INVALID_ARGUMENT);
    CHECK(chosen == NULL && strstr(hystcomp_last_error_message(), "delayed") != NULL);

    /* operators_auto: one of the candidates, named in the report; operators ignored. */
    CHECK(hystcomp_identify_options_default(&options) == HYSTCOMP_STATUS_OK);
    options.operators_auto = 1;
    options.operators = 3;
    CHECK(hystcomp_identify(volts, N, um, N, &options, &chosen, &auto_report) ==
          HYSTCOMP_STATUS_OK);
    CHECK(auto_report.operators == 5 || auto_report.operators == 10 ||
          auto_report.operators == 15 || auto_report.operators == 20 ||
          auto_report.operators == 30 || auto_report.operators == 40 ||
          auto_report.operators == 50);

    /* The prediction of the record: the model's output, minus the measurement. */
    CHECK(hystcomp_predict(free_fit, volts, um, N, 0, predicted, error, &summary) ==
          HYSTCOMP_STATUS_OK);
    CHECK(hystcomp_model_predict(free_fit, volts, N, forward, N) == HYSTCOMP_STATUS_OK);
    for (k = 0; k < N; k++) {
        double d = fabs(predicted[k] - forward[k]);
        worst = d > worst ? d : worst;
        CHECK(error[k] == predicted[k] - um[k]);
        sum += error[k] * error[k];
        lo = um[k] < lo ? um[k] : lo;
        hi = um[k] > hi ? um[k] : hi;
    }
    CHECK(worst == 0.0);
    CHECK(summary.error.samples == N && summary.outside_input_range == 0);
    CHECK(fabs(summary.error.range - (hi - lo)) < 1e-12 * (hi - lo));
    CHECK(fabs(summary.error.rms_percent - 100.0 * sqrt(sum / N) / (hi - lo)) < 1e-9);
    /* Only the summary, and refusals: nothing written on failure. */
    CHECK(hystcomp_predict(free_fit, volts, um, N, 1, NULL, NULL, &summary) ==
          HYSTCOMP_STATUS_OK);
    CHECK(hystcomp_predict(NULL, volts, um, N, 0, predicted, error, &summary) ==
          HYSTCOMP_STATUS_NULL_POINTER);
    CHECK(hystcomp_predict(free_fit, volts, um, 0, 0, predicted, error, &summary) ==
          HYSTCOMP_STATUS_INVALID_ARGUMENT);
    um[7] = NAN;
    predicted[0] = -1.0;
    CHECK(hystcomp_predict(free_fit, volts, um, N, 0, predicted, error, &summary) ==
          HYSTCOMP_STATUS_INVALID_ARGUMENT);
    CHECK(predicted[0] == -1.0);

    hystcomp_model_free(free_fit);
    hystcomp_model_free(bounded);
    hystcomp_model_free(chosen);
    if (failures > 0) {
        fprintf(stderr, "%d check(s) failed\n", failures);
        return 1;
    }
    printf("delayed_auto_predict OK: fit %.4f %% free, %.4f %% bounded (<= %.2f), auto n = %zu, "
           "prediction RMS %.4f %%\n",
           free_report.fit.rms_percent, report.fit.rms_percent, report.delayed_loop_bound,
           auto_report.operators, summary.error.rms_percent);
    return 0;
}
