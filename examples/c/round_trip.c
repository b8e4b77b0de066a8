/*
 * hystcomp from C: an inverse hysteresis compensator (IHC) built from a model file drives the
 * forward model of the same file, and the round trip P[C[y_d]] = y_d is checked.
 *
 *   round_trip models/table1-plant.json
 *
 * Build (see the Makefile beside this file):
 *   cargo build -p hystcomp-c
 *   gcc -std=c99 -Wall -Wextra -I bindings/c/include examples/c/round_trip.c \
 *       target/debug/libhystcomp.a -lpthread -ldl -lm -o round_trip
 *
 * Exit status: 0 when every check passes, 1 otherwise.
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>

#include "hystcomp.h"

#ifndef M_PI /* not in strict C99 */
#define M_PI 3.14159265358979323846
#endif

#define SAMPLE_RATE_HZ 10000.0
#define SAMPLES 20000 /* two seconds */

/* Prints the reason of a failed call and returns 1. */
static int report(const char *what, int status) {
    fprintf(stderr, "%s failed: %s (%d): %s\n", what, hystcomp_status_name(status), status,
            hystcomp_last_error_message());
    return 1;
}

int main(int argc, char **argv) {
    if (argc != 2) {
        fprintf(stderr, "usage: %s MODEL.json (a plant model, e.g. models/table1-plant.json)\n",
                argv[0]);
        return 2;
    }
    const char *model_path = argv[1];
    printf("hystcomp %s\n", hystcomp_version());

    /* The compensator (desired um in, command V out) and the plant model (V in, um out). */
    HystcompCompensator *ihc = NULL;
    HystcompMpim *plant = NULL;
    int status = hystcomp_compensator_from_model_file(model_path, "ihc", 0.0, 0.0, 0, &ihc);
    if (status != HYSTCOMP_STATUS_OK) return report("hystcomp_compensator_from_model_file", status);
    status = hystcomp_mpim_from_model_file(model_path, &plant);
    if (status != HYSTCOMP_STATUS_OK) return report("hystcomp_mpim_from_model_file", status);

    double v_min = 0.0, v_max = 0.0;
    status = hystcomp_compensator_limits(ihc, &v_min, &v_max);
    if (status != HYSTCOMP_STATUS_OK) return report("hystcomp_compensator_limits", status);
    printf("IHC from %s, drive limits [%g, %g] V\n", model_path, v_min, v_max);

    /* One sample at a time, as a real-time loop does. */
    int failures = 0;
    double worst_um = 0.0;
    for (int k = 0; k < SAMPLES; ++k) {
        double t = k / SAMPLE_RATE_HZ;
        double desired_um = 32.5 + 15.0 * sin(2.0 * M_PI * t + 1.5) + 8.0 * sin(4.6 * M_PI * t);
        double volts = 0.0, reached_um = 0.0;
        status = hystcomp_compensator_step(ihc, desired_um, &volts);
        if (status != HYSTCOMP_STATUS_OK) return report("hystcomp_compensator_step", status);
        if (!(volts >= v_min && volts <= v_max)) {
            fprintf(stderr, "sample %d: %g V outside the limits\n", k, volts);
            ++failures;
        }
        status = hystcomp_mpim_step(plant, volts, &reached_um);
        if (status != HYSTCOMP_STATUS_OK) return report("hystcomp_mpim_step", status);
        double error = fabs(reached_um - desired_um);
        if (error > worst_um) worst_um = error;
    }
    printf("step:    %d samples, max |P[C[y_d]] - y_d| = %.3e um\n", SAMPLES, worst_um);
    if (!(worst_um < 1e-9)) {
        fprintf(stderr, "round trip error %.3e um exceeds 1e-9 um\n", worst_um);
        ++failures;
    }

    /* A whole signal at once, in place, after a reset of both. */
    double *signal = malloc(SAMPLES * sizeof *signal);
    double *desired = malloc(SAMPLES * sizeof *desired);
    if (signal == NULL || desired == NULL) return 1;
    for (int k = 0; k < SAMPLES; ++k) {
        double t = k / SAMPLE_RATE_HZ;
        desired[k] = 40.0 + 25.0 * sin(2.0 * M_PI * t);
        signal[k] = desired[k];
    }
    hystcomp_compensator_reset(ihc);
    hystcomp_mpim_reset(plant);
    status = hystcomp_compensator_process(ihc, signal, signal, SAMPLES); /* um -> V */
    if (status != HYSTCOMP_STATUS_OK) return report("hystcomp_compensator_process", status);
    status = hystcomp_mpim_process(plant, signal, signal, SAMPLES); /* V -> um */
    if (status != HYSTCOMP_STATUS_OK) return report("hystcomp_mpim_process", status);
    worst_um = 0.0;
    for (int k = 0; k < SAMPLES; ++k) {
        double error = fabs(signal[k] - desired[k]);
        if (error > worst_um) worst_um = error;
    }
    printf("process: %d samples, max |P[C[y_d]] - y_d| = %.3e um\n", SAMPLES, worst_um);
    if (!(worst_um < 1e-9)) {
        fprintf(stderr, "round trip error %.3e um exceeds 1e-9 um\n", worst_um);
        ++failures;
    }
    free(signal);
    free(desired);

    /* Bad input gives a status and a reason, never a crash. */
    HystcompCompensator *missing = NULL;
    status = hystcomp_compensator_from_model_file("no-such-model.json", "ihc", 0.0, 0.0, 0,
                                                  &missing);
    printf("missing file: %s: %s\n", hystcomp_status_name(status), hystcomp_last_error_message());
    if (status != HYSTCOMP_STATUS_IO || missing != NULL) ++failures;
    status = hystcomp_compensator_step(NULL, 1.0, &worst_um);
    printf("NULL handle: %s: %s\n", hystcomp_status_name(status), hystcomp_last_error_message());
    if (status != HYSTCOMP_STATUS_NULL_POINTER) ++failures;

    hystcomp_compensator_free(ihc);
    hystcomp_mpim_free(plant);
    hystcomp_compensator_free(NULL); /* allowed */

    printf(failures == 0 ? "round trip OK\n" : "round trip FAILED (%d)\n", failures);
    return failures == 0 ? 0 : 1;
}
