#include <stdio.h>

#include "hystcomp.h"

int main(void) {
    HystcompCompensator *ihc = NULL; /* desired um in, command V out */
    HystcompMpim *plant = NULL;      /* command V in, um out */
    if (hystcomp_compensator_from_model_file("models/table1-plant.json", "ihc", 0.0, 0.0, 0,
                                             &ihc) != HYSTCOMP_STATUS_OK ||
        hystcomp_mpim_from_model_file("models/table1-plant.json", &plant) != HYSTCOMP_STATUS_OK) {
        fprintf(stderr, "hystcomp: %s\n", hystcomp_last_error_message());
        return 1;
    }
    double volts = 0.0, reached_um = 0.0;
    hystcomp_compensator_step(ihc, 40.0, &volts); /* within [0, 10] V, never NaN */
    hystcomp_mpim_step(plant, volts, &reached_um); /* P[C[y_d]] = y_d */
    printf("40 um -> %.4f V -> %.6f um\n", volts, reached_um);
    hystcomp_compensator_free(ihc);
    hystcomp_mpim_free(plant);
    return 0;
}
