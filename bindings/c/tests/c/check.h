/*
 * What every C test program here shares: CHECK(condition) counts a failed check in `failures`
 * and prints where it failed with the library's last error message; main returns nonzero when
 * `failures` is. Included once, by the program's own file.
 */
#ifndef HYSTCOMP_TESTS_CHECK_H
#define HYSTCOMP_TESTS_CHECK_H

#include <stdio.h>

#include "hystcomp.h"

static int failures = 0;

#define CHECK(condition)                                                                      \
    do {                                                                                      \
        if (!(condition)) {                                                                   \
            fprintf(stderr, "%s:%d: check failed: %s (last error: %s)\n", __FILE__, __LINE__, \
                    #condition, hystcomp_last_error_message());                               \
            failures++;                                                                       \
        }                                                                                     \
    } while (0)

#endif
