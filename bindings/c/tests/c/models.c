/*
 * The C ABI's models, identification, one-shot compensation and indices, called from C:
 * identify a model from a record of Table 1's MPIM, take it apart into values and build it
 * again, save and load it, compensate a trajectory in one shot and through the forward model
 * check P[C[y_d]] = y_d, compute the indices, and check that NULL, empty, mismatched and NaN
 * arguments are refused with their status. Compiled with -Wall -Wextra -Werror -pedantic and run
 * by bindings/c/tests/c_example.rs; prints "models OK" and exits 0 when every check passes.
 *
 * usage: models TEMPORARY_DIRECTORY
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

int main(int argc, char **argv) {
    static double volts[N], um[N], desired[N], drive[N], reached[N], predicted[N];
    char path[4096];
    HystcompMpim *table1 = NULL;
    HystcompModel *model = NULL, *copy = NULL, *loaded = NULL;
    HystcompFitReport report;
    HystcompIdentifyOptions options;
    HystcompModelValues values, again;
    HystcompDiagnostics diagnostics;
    double worst = 0.0, e_m = -1.0, e_rms = -1.0, e_mhe = -1.0, pi = acos(-1.0);
    size_t k;

    if (argc != 2) {
        fprintf(stderr, "usage: %s TEMPORARY_DIRECTORY\n", argv[0]);
        return 2;
    }
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

    /* Identification, with a hold-out, as the command line does by default. */
    CHECK(hystcomp_identify_options_default(&options) == HYSTCOMP_STATUS_OK);
    CHECK(options.operators == 10 && options.solver == HYSTCOMP_SOLVER_LEAST_SQUARES);
    options.holdout = 0.2;
    CHECK(hystcomp_identify(volts, N, um, N, &options, &model, &report) == HYSTCOMP_STATUS_OK);
    CHECK(model != NULL);
    CHECK(report.samples_total == N && report.samples_holdout > 0);
    CHECK(report.fit.rms_percent < 0.1 && report.holdout.samples == report.samples_holdout);
    CHECK(report.violated_constraints == 0 && report.min_branch_slope > 0.0);

    /* Values out, and a model built again from them. */
    CHECK(hystcomp_model_values(model, &values) == HYSTCOMP_STATUS_OK);
    CHECK(values.direction == HYSTCOMP_DIRECTION_PLANT && values.operators == 10);
    CHECK(strcmp(values.input.unit, "V") == 0 && strcmp(values.output.unit, "um") == 0);
    CHECK(values.identification_json != NULL && strstr(values.identification_json, "\"fit\""));
    CHECK(hystcomp_model_from_values(&values, &copy) == HYSTCOMP_STATUS_OK);
    CHECK(hystcomp_model_values(copy, &again) == HYSTCOMP_STATUS_OK);
    CHECK(again.a1 == values.a1 && again.a2 == values.a2 &&
          again.output.offset == values.output.offset && again.input.scale == values.input.scale);
    for (k = 0; k < values.operators; k++) {
        CHECK(again.thresholds[k] == values.thresholds[k] && again.weights[k] == values.weights[k]);
    }

    /* Saved and loaded. */
    snprintf(path, sizeof path, "%s/identified.json", argv[1]);
    CHECK(hystcomp_model_save(copy, path) == HYSTCOMP_STATUS_OK);
    CHECK(hystcomp_model_load(path, &loaded) == HYSTCOMP_STATUS_OK);
    CHECK(hystcomp_model_values(loaded, &again) == HYSTCOMP_STATUS_OK);
    CHECK(again.a1 == values.a1 && again.weights[9] == values.weights[9]);

    /* One-shot IHC of a trajectory within the fitted range, and the round trip. */
    for (k = 0; k < N; k++) {
        desired[k] = 12.0 + 37.5 + 25.0 * sin(2.0 * pi * (double)k / 1000.0);
    }
    CHECK(hystcomp_compensate(loaded, "ihc", 0.0, 0.0, 0, desired, N, drive, N, &diagnostics) ==
          HYSTCOMP_STATUS_OK);
    CHECK(diagnostics.saturated == 0 && diagnostics.non_finite == 0);
    CHECK(hystcomp_mpim_from_model(loaded, &table1) == HYSTCOMP_STATUS_OK);
    CHECK(hystcomp_mpim_process(table1, drive, reached, N) == HYSTCOMP_STATUS_OK);
    for (k = 0; k < N; k++) {
        double e = fabs(reached[k] - desired[k]);
        worst = e > worst ? e : worst;
        CHECK(drive[k] >= diagnostics.v_min && drive[k] <= diagnostics.v_max);
    }
    CHECK(worst < 1e-9);
    hystcomp_mpim_free(table1);
    /* The model run forward in one call: the same as the forward MPIM. */
    CHECK(hystcomp_model_predict(loaded, drive, N, predicted, N) == HYSTCOMP_STATUS_OK);
    CHECK(memcmp(predicted, reached, sizeof predicted) == 0);

    /* The indices of the identified model's prediction against the record. */
    CHECK(hystcomp_e_m(desired, N, reached, N, &e_m) == HYSTCOMP_STATUS_OK && e_m < 1e-9);
    CHECK(hystcomp_e_rms(desired, N, reached, N, &e_rms) == HYSTCOMP_STATUS_OK && e_rms < 1e-9);
    CHECK(hystcomp_e_mhe(desired, N, reached, N, HYSTCOMP_DEFAULT_MHE_BINS, &e_mhe) ==
              HYSTCOMP_STATUS_OK &&
          e_mhe > 0.0 && e_mhe <= 1.0 + 1e-9);

    /* Bad arguments: a status and a message each, and nothing written to *out. */
    {
        HystcompModel *none = NULL;
        double nan_record[3] = {1.0, NAN, 3.0};
        CHECK(hystcomp_identify(NULL, N, um, N, NULL, &none, NULL) ==
              HYSTCOMP_STATUS_NULL_POINTER);
        CHECK(hystcomp_identify(volts, N, um, N - 1, NULL, &none, NULL) ==
              HYSTCOMP_STATUS_INVALID_ARGUMENT);
        CHECK(strstr(hystcomp_last_error_message(), "displacement has 3999") != NULL);
        CHECK(hystcomp_identify(volts, 0, um, 0, NULL, &none, NULL) ==
              HYSTCOMP_STATUS_INVALID_ARGUMENT);
        options.operators = HYSTCOMP_MAX_OPERATORS + 1;
        CHECK(hystcomp_identify(volts, N, um, N, &options, &none, NULL) ==
              HYSTCOMP_STATUS_INVALID_ARGUMENT);
        for (k = 0; k < N; k++) {
            reached[k] = -um[k]; /* the wrong sign: no model */
        }
        CHECK(hystcomp_identify(volts, N, reached, N, NULL, &none, NULL) ==
              HYSTCOMP_STATUS_IDENTIFICATION_FAILED);
        CHECK(none == NULL);
        CHECK(hystcomp_e_rms(nan_record, 3, desired, 3, &e_rms) ==
              HYSTCOMP_STATUS_INVALID_ARGUMENT);
        CHECK(hystcomp_e_mhe(desired, N, reached, N, 0, &e_mhe) ==
              HYSTCOMP_STATUS_INVALID_ARGUMENT);
        CHECK(hystcomp_compensate(loaded, "dihc", 0.0, 0.0, 0, desired, N, drive, N, NULL) ==
              HYSTCOMP_STATUS_WRONG_DIRECTION);
        CHECK(hystcomp_compensate(loaded, "ihc", 0.0, 0.0, 0, nan_record, 3, drive, 3, NULL) ==
              HYSTCOMP_STATUS_NON_FINITE_INPUT);
        CHECK(drive[1] == drive[0]);
        CHECK(hystcomp_model_load("no-such-dir/no-such-model.json", &none) ==
              HYSTCOMP_STATUS_IO);
        CHECK(none == NULL);
        values.operators = 0;
        CHECK(hystcomp_model_from_values(&values, &none) == HYSTCOMP_STATUS_INVALID_ARGUMENT);
        CHECK(hystcomp_model_save(NULL, path) == HYSTCOMP_STATUS_NULL_POINTER);
        CHECK(strcmp(hystcomp_status_name(HYSTCOMP_STATUS_IDENTIFICATION_FAILED),
                     "identification failed") == 0);
    }

    hystcomp_model_free(model);
    hystcomp_model_free(copy);
    hystcomp_model_free(loaded);
    if (failures != 0) {
        fprintf(stderr, "%d check(s) failed\n", failures);
        return 1;
    }
    printf("models OK: fit %.4f %% RMS, round trip within %.3g um, e_mhe %.4f %%\n",
           report.fit.rms_percent, worst, e_mhe);
    return 0;
}
