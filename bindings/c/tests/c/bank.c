/*
 * The C ABI's compensator bank (issue 16), called from C as a multi-axis controller would: a
 * bank from a model set and a bank from models in memory, stepped tick by tick and processed
 * as a whole signal (also in place), every channel checked bit for bit against its own
 * compensator; per-channel limits and diagnostics read back (a NaN position counted on its
 * channel only, a position beyond reach counted as saturated); a refused channel named by
 * its index; bad arguments refused with their status; every handle freed. Compiled with -Wall
 * -Wextra -Werror -pedantic and run by bindings/c/tests/c_example.rs (also under valgrind);
 * prints "bank OK" and exits 0 when every check passes.
 *
 * usage: bank MODEL_SET PLANT_MODEL INVERSE_MODEL
 *        (models/table1-xyz-set.json models/table1-plant.json models/table2-inverse.json)
 */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "check.h"
#include "hystcomp.h"

#define CHANNELS 4
#define TICKS 500

static const char *const METHODS[] = {"ihc", "ihc-guarded", "wihc", "wihc-guarded"};

/* Whether the last error message begins with `prefix`. */
static int message_starts_with(const char *prefix) {
    const char *message = hystcomp_last_error_message();
    return message != NULL && strncmp(message, prefix, strlen(prefix)) == 0;
}

/* Desired position of channel `c` at tick `k`, um: each channel its own phase and amplitude,
 * within the stroke of Table 1's model (0 .. 75 um) except channel 3, which asks for 20 %
 * more than the stroke at its peaks (saturated there). */
static double desired_um(size_t c, size_t k) {
    double pi = acos(-1.0);
    double t = (double)k / TICKS;
    double amplitude = c == 3 ? 50.0 : 20.0 + 5.0 * (double)c;
    return 40.0 + amplitude * sin(2.0 * pi * 3.0 * t + 0.7 * (double)c) * (1.0 - exp(-20.0 * t));
}

/* One method: a bank of CHANNELS copies of `model`, each with its own limits, against
 * CHANNELS compensators made from the same model and limits. */
static void bank_equals_its_compensators(const HystcompModel *model, const char *method) {
    static double y_d[TICKS][CHANNELS], v[TICKS][CHANNELS], whole[TICKS][CHANNELS];
    const HystcompModel *models[CHANNELS];
    double limits[2 * CHANNELS] = {0.0, 10.0, 0.5, 9.5, 1.0, 8.0, 0.0, 10.0};
    HystcompCompensator *single[CHANNELS] = {NULL};
    HystcompBank *bank = NULL;
    size_t c, k, channels = 0;
    uint64_t saturated = 0, loop_saturated = 0, non_finite = 0, single_saturated = 0,
             single_non_finite = 0;
    double lo = 0.0, hi = 0.0, expected = 0.0;
    int status;

    for (c = 0; c < CHANNELS; c++) {
        models[c] = model;
        CHECK(hystcomp_compensator_from_model(model, method, limits[2 * c], limits[2 * c + 1], 1,
                                              &single[c]) == HYSTCOMP_STATUS_OK);
    }
    CHECK(hystcomp_bank_from_models(models, CHANNELS, method, limits, CHANNELS, 0, &bank) ==
          HYSTCOMP_STATUS_OK);
    if (bank == NULL) {
        failures++;
        for (c = 0; c < CHANNELS; c++) {
            hystcomp_compensator_free(single[c]);
        }
        return;
    }
    CHECK(hystcomp_bank_channels(bank, &channels) == HYSTCOMP_STATUS_OK && channels == CHANNELS);
    for (k = 0; k < TICKS; k++) {
        for (c = 0; c < CHANNELS; c++) {
            y_d[k][c] = desired_um(c, k);
        }
    }
    /* A NaN on channel 1 at tick 100: that channel holds its drive, the others go on. */
    y_d[100][1] = NAN;
    for (k = 0; k < TICKS; k++) {
        status = hystcomp_bank_step(bank, y_d[k], v[k], CHANNELS);
        CHECK(status == (k == 100 ? HYSTCOMP_STATUS_NON_FINITE_INPUT : HYSTCOMP_STATUS_OK));
        for (c = 0; c < CHANNELS; c++) {
            status = hystcomp_compensator_step(single[c], y_d[k][c], &expected);
            CHECK(status == ((k == 100 && c == 1) ? HYSTCOMP_STATUS_NON_FINITE_INPUT
                                                  : HYSTCOMP_STATUS_OK));
            /* Bit for bit: the same double, not merely close. */
            if (memcmp(&v[k][c], &expected, sizeof expected) != 0) {
                fprintf(stderr, "%s: channel %zu tick %zu: bank %.17g, compensator %.17g\n",
                        method, c, k, v[k][c], expected);
                failures++;
            }
            CHECK(v[k][c] >= limits[2 * c] && v[k][c] <= limits[2 * c + 1]);
        }
    }
    CHECK(v[100][1] == v[99][1]);
    for (c = 0; c < CHANNELS; c++) {
        CHECK(hystcomp_bank_limits(bank, c, &lo, &hi) == HYSTCOMP_STATUS_OK);
        CHECK(lo == limits[2 * c] && hi == limits[2 * c + 1]);
        CHECK(hystcomp_bank_diagnostics(bank, c, &saturated, &loop_saturated, &non_finite) ==
              HYSTCOMP_STATUS_OK);
        CHECK(hystcomp_compensator_diagnostics(single[c], &single_saturated,
                                               &single_non_finite) == HYSTCOMP_STATUS_OK);
        CHECK(saturated == single_saturated && non_finite == single_non_finite);
        CHECK(non_finite == (c == 1 ? 1u : 0u));
        /* Channel 3 asks for more than the stroke at its peaks; 1 .. 8 V cuts channel 2's. */
        if (c == 3 || c == 2) {
            CHECK(saturated > 0);
        }
        if (c == 0) {
            CHECK(saturated == 0);
        }
        CHECK(loop_saturated == 0);
    }
    /* Any pointer may be NULL when its counter is not wanted. */
    CHECK(hystcomp_bank_diagnostics(bank, 0, NULL, NULL, &non_finite) == HYSTCOMP_STATUS_OK);

    /* The whole signal at once, then in place: the same drives as tick by tick. */
    CHECK(hystcomp_bank_reset(bank) == HYSTCOMP_STATUS_OK);
    CHECK(hystcomp_bank_process(bank, &y_d[0][0], &whole[0][0], TICKS, CHANNELS) ==
          HYSTCOMP_STATUS_NON_FINITE_INPUT);
    CHECK(memcmp(whole, v, sizeof whole) == 0);
    CHECK(hystcomp_bank_reset(bank) == HYSTCOMP_STATUS_OK);
    memcpy(whole, y_d, sizeof whole);
    CHECK(hystcomp_bank_process(bank, &whole[0][0], &whole[0][0], TICKS, CHANNELS) ==
          HYSTCOMP_STATUS_NON_FINITE_INPUT);
    CHECK(memcmp(whole, v, sizeof whole) == 0);
    CHECK(hystcomp_bank_diagnostics(bank, 1, NULL, NULL, &non_finite) == HYSTCOMP_STATUS_OK &&
          non_finite == 1);

    /* Bad arguments: a channel beyond the last, another channel count, NULL arrays. */
    CHECK(hystcomp_bank_limits(bank, CHANNELS, &lo, &hi) == HYSTCOMP_STATUS_INVALID_ARGUMENT);
    CHECK(hystcomp_bank_diagnostics(bank, CHANNELS, &saturated, NULL, NULL) ==
          HYSTCOMP_STATUS_INVALID_ARGUMENT);
    CHECK(hystcomp_bank_step(bank, y_d[0], v[0], CHANNELS - 1) ==
          HYSTCOMP_STATUS_INVALID_ARGUMENT);
    CHECK(hystcomp_bank_step(bank, NULL, v[0], CHANNELS) == HYSTCOMP_STATUS_NULL_POINTER);
    CHECK(hystcomp_bank_process(bank, &y_d[0][0], NULL, TICKS, CHANNELS) ==
          HYSTCOMP_STATUS_NULL_POINTER);
    CHECK(hystcomp_bank_limits(bank, 0, NULL, &hi) == HYSTCOMP_STATUS_NULL_POINTER);

    hystcomp_bank_free(bank);
    for (c = 0; c < CHANNELS; c++) {
        hystcomp_compensator_free(single[c]);
    }
}

int main(int argc, char **argv) {
    HystcompModel *plant = NULL, *inverse = NULL;
    const HystcompModel *mixed[3];
    HystcompBank *bank = NULL;
    double y_d[3] = {10.0, 20.0, 30.0}, v[3] = {0.0, 0.0, 0.0};
    double bad_limits[6] = {0.0, 10.0, 5.0, 1.0, 0.0, 10.0};
    size_t m, channels = 0;

    if (argc != 4) {
        fprintf(stderr, "usage: %s MODEL_SET PLANT_MODEL INVERSE_MODEL\n", argv[0]);
        return 2;
    }

    /* A model set: three axes, each channel's identified range; one tick of every channel. */
    CHECK(hystcomp_bank_from_model_set(argv[1], "ihc", NULL, 0, 0, &bank) ==
          HYSTCOMP_STATUS_OK);
    CHECK(hystcomp_bank_channels(bank, &channels) == HYSTCOMP_STATUS_OK && channels == 3);
    CHECK(hystcomp_bank_step(bank, y_d, v, 3) == HYSTCOMP_STATUS_OK);
    CHECK(v[0] > 0.0 && v[1] > 0.0 && v[2] > 0.0);
    hystcomp_bank_free(bank);
    bank = NULL;

    /* Refused channels are named by their index (and name, in a set). */
    CHECK(hystcomp_bank_from_model_set(argv[1], "dihc", NULL, 0, 0, &bank) ==
          HYSTCOMP_STATUS_WRONG_DIRECTION);
    CHECK(bank == NULL && message_starts_with("channel 0 (x): "));
    CHECK(hystcomp_bank_from_model_set(argv[1], "ihc", bad_limits, 3, 0, &bank) ==
          HYSTCOMP_STATUS_INVALID_ARGUMENT);
    CHECK(bank == NULL && message_starts_with("channel 1 (y): "));
    CHECK(hystcomp_model_load(argv[2], &plant) == HYSTCOMP_STATUS_OK);
    CHECK(hystcomp_model_load(argv[3], &inverse) == HYSTCOMP_STATUS_OK);
    if (failures) {
        hystcomp_model_free(plant);
        hystcomp_model_free(inverse);
        return 1;
    }
    mixed[0] = plant;
    mixed[1] = plant;
    mixed[2] = inverse;
    CHECK(hystcomp_bank_from_models(mixed, 3, "ihc", NULL, 0, 0, &bank) ==
          HYSTCOMP_STATUS_WRONG_DIRECTION);
    CHECK(bank == NULL && message_starts_with("channel 2 (channel_2): "));
    CHECK(hystcomp_bank_from_models(mixed, 0, "ihc", NULL, 0, 0, &bank) ==
          HYSTCOMP_STATUS_INVALID_ARGUMENT);
    CHECK(hystcomp_bank_from_models(NULL, 2, "ihc", NULL, 0, 0, &bank) ==
          HYSTCOMP_STATUS_NULL_POINTER);
    CHECK(bank == NULL);

    /* Every method of a plant model: each channel its own compensator, bit for bit. */
    for (m = 0; m < sizeof METHODS / sizeof METHODS[0]; m++) {
        bank_equals_its_compensators(plant, METHODS[m]);
    }

    /* NULL handles. */
    CHECK(hystcomp_bank_step(NULL, y_d, v, 3) == HYSTCOMP_STATUS_NULL_POINTER);
    CHECK(hystcomp_bank_channels(NULL, &channels) == HYSTCOMP_STATUS_NULL_POINTER);
    hystcomp_bank_free(NULL);

    hystcomp_model_free(plant);
    hystcomp_model_free(inverse);
    if (failures) {
        fprintf(stderr, "%d check(s) failed\n", failures);
        return 1;
    }
    printf("bank OK\n");
    return 0;
}
