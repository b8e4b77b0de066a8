/*
 * The C ABI's learner, called from C as a real-time board would between cycles: a "stage"
 * (Table 1's MPIM run forward, its output 5 % short of what the model says) repeats one period
 * of a sine; each trial plays the drive three times and records the middle period, and the
 * learner computes the next drive. Checks that e_rms falls a hundredfold in six trials, that
 * every drive stays within the limits, that a gain far too high is stopped with
 * HYSTCOMP_STATUS_LEARNING_STOPPED and the first drive given back, and that bad arguments are
 * refused. Compiled with -Wall -Wextra -Werror -pedantic and run by
 * bindings/c/tests/c_example.rs; prints "learner OK" and exits 0 when every check passes.
 *
 * usage: learner MODEL_FILE (models/table1-plant.json)
 */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "check.h"
#include "hystcomp.h"

#define N 1000

/* The stage: the model forward over three periods of the drive, the middle one kept, 0.95x. */
static void stage(HystcompMpim *plant, const double *drive, double *measured) {
    size_t pass, k;
    double y = 0.0;
    CHECK(hystcomp_mpim_reset(plant) == HYSTCOMP_STATUS_OK);
    for (pass = 0; pass < 3; pass++) {
        for (k = 0; k < N; k++) {
            CHECK(hystcomp_mpim_step(plant, drive[k], &y) == HYSTCOMP_STATUS_OK);
            if (pass == 1) {
                measured[k] = 0.95 * y;
            }
        }
    }
}

int main(int argc, char **argv) {
    static double desired[N], drive[N], first[N], measured[N];
    HystcompModel *model = NULL;
    HystcompMpim *plant = NULL;
    HystcompLearner *learner = NULL, *wild = NULL;
    HystcompLearningOptions options;
    HystcompLearningUpdate update;
    HystcompLearningLaw law;
    double e_rms[6], pi = acos(-1.0);
    size_t k, trial, samples = 0;
    int status;

    if (argc != 2) {
        fprintf(stderr, "usage: %s MODEL_FILE\n", argv[0]);
        return 2;
    }
    for (k = 0; k < N; k++) {
        desired[k] = 35.0 + 20.0 * sin(2.0 * pi * (double)k / N);
    }
    CHECK(hystcomp_model_load(argv[1], &model) == HYSTCOMP_STATUS_OK);
    CHECK(hystcomp_mpim_from_model(model, &plant) == HYSTCOMP_STATUS_OK);
    CHECK(hystcomp_learning_options_default(1000.0, &options) == HYSTCOMP_STATUS_OK);
    CHECK(hystcomp_learner_new(model, desired, N, &options, &learner) == HYSTCOMP_STATUS_OK);
    if (failures) {
        return 1;
    }
    CHECK(hystcomp_learner_samples(learner, &samples) == HYSTCOMP_STATUS_OK && samples == N);
    CHECK(hystcomp_learner_law(learner, &law) == HYSTCOMP_STATUS_OK);
    CHECK(law.gain == 0.8 && law.bandwidth_hz == 10.0 && law.periodic == 1);
    CHECK(law.stationary_noise_ratio > 0.0 && law.stationary_noise_ratio < 0.1);
    CHECK(hystcomp_learner_drive(learner, drive, N) == HYSTCOMP_STATUS_OK);
    memcpy(first, drive, sizeof drive);
    for (trial = 0; trial < 6; trial++) {
        stage(plant, drive, measured);
        /* In place: the measured period in, the next drive out. */
        memcpy(drive, measured, sizeof drive);
        CHECK(hystcomp_learner_update(learner, drive, N, drive, &update) == HYSTCOMP_STATUS_OK);
        CHECK(update.trial == trial && update.has_prediction && !update.diverged);
        e_rms[trial] = update.e_rms_percent;
        for (k = 0; k < N; k++) {
            CHECK(drive[k] >= law.v_min && drive[k] <= law.v_max);
        }
    }
    CHECK(e_rms[0] > 1.0);
    CHECK(e_rms[5] < e_rms[0] / 100.0);

    /* Refusals: the wrong length, a NaN sample (nothing changed), NULL. */
    CHECK(hystcomp_learner_update(learner, measured, N - 1, drive, NULL) ==
          HYSTCOMP_STATUS_INVALID_ARGUMENT);
    measured[4] = NAN;
    CHECK(hystcomp_learner_update(learner, measured, N, drive, NULL) ==
          HYSTCOMP_STATUS_NON_FINITE_INPUT);
    CHECK(strstr(hystcomp_last_error_message(), "measured[4]") != NULL);
    CHECK(hystcomp_learner_update(NULL, measured, N, drive, NULL) == HYSTCOMP_STATUS_NULL_POINTER);
    options.gain = -1.0;
    CHECK(hystcomp_learner_new(model, desired, N, &options, &wild) ==
          HYSTCOMP_STATUS_INVALID_ARGUMENT);
    CHECK(wild == NULL);

    /* A gain far too high: stopped on trial 1, the first drive given back. */
    options.gain = 10.0;
    options.bandwidth_hz = 400.0;
    CHECK(hystcomp_learner_new(model, desired, N, &options, &wild) == HYSTCOMP_STATUS_OK);
    CHECK(hystcomp_learner_drive(wild, drive, N) == HYSTCOMP_STATUS_OK);
    stage(plant, drive, measured);
    CHECK(hystcomp_learner_update(wild, measured, N, drive, &update) == HYSTCOMP_STATUS_OK);
    stage(plant, drive, measured);
    status = hystcomp_learner_update(wild, measured, N, drive, &update);
    CHECK(status == HYSTCOMP_STATUS_LEARNING_STOPPED);
    CHECK(update.diverged == 1 && update.best_trial == 0);
    CHECK(memcmp(drive, first, sizeof drive) == 0);
    CHECK(hystcomp_learner_update(wild, measured, N, drive, &update) ==
          HYSTCOMP_STATUS_LEARNING_STOPPED);

    hystcomp_learner_free(learner);
    hystcomp_learner_free(wild);
    hystcomp_mpim_free(plant);
    hystcomp_model_free(model);
    if (failures) {
        fprintf(stderr, "%d checks failed\n", failures);
        return 1;
    }
    printf("learner OK: e_rms %.4f %% -> %.6f %% in 6 trials\n", e_rms[0], e_rms[5]);
    return 0;
}
