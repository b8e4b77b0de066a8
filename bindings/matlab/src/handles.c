/*
 * The compensator handle table of the hystcomp MEX gateway.
 *
 * MATLAB holds an id (uint64) made of the table's epoch (16 bits, different for each load of the
 * MEX file), a slot (16 bits) and the slot's generation (32 bits). Freeing a compensator gives
 * its slot a new generation, so that an id that was freed, copied from another session or made
 * up is refused (hystcomp:invalidHandle) and never dereferenced. While compensators live the
 * MEX file is locked in memory (mexLock: `clear mex` cannot unload it under them), and
 * mexAtExit frees what is left when MATLAB exits.
 */
#include <stdlib.h>
#include <time.h>

#include "gateway.h"

#define MAX_HANDLES 65536u

typedef struct {
    HystcompCompensator *compensator; /* NULL when the slot is free */
    uint32_t generation;
} Slot;

static Slot *slots = NULL;
static uint32_t slot_count = 0;
static uint32_t live_handles = 0;
static uint16_t epoch = 0;

static void free_all_handles(void) {
    uint32_t k;
    for (k = 0; k < slot_count; k++) {
        hystcomp_compensator_free(slots[k].compensator);
        slots[k].compensator = NULL;
    }
    free(slots);
    slots = NULL;
    slot_count = 0;
    live_handles = 0;
}

static void start_table(void) {
    if (epoch == 0) {
        /* Differs between loads of the MEX file, so that ids from an earlier load are
         * refused. */
        uintptr_t mix = (uintptr_t)&slots ^ (uintptr_t)time(NULL) ^ ((uintptr_t)clock() << 16);
        epoch = (uint16_t)((mix ^ (mix >> 16) ^ (mix >> 31)) & 0xffffu);
        if (epoch == 0) {
            epoch = 1;
        }
        mexAtExit(free_all_handles);
    }
}

uint64_t handle_store(HystcompCompensator *c) {
    uint32_t k;
    start_table();
    for (k = 0; k < slot_count; k++) {
        if (slots[k].compensator == NULL) {
            break;
        }
    }
    if (k == slot_count) {
        Slot *grown;
        if (slot_count == MAX_HANDLES) {
            hystcomp_compensator_free(c);
            fail("hystcomp:tooManyHandles", "%u compensators are alive; delete some first",
                 MAX_HANDLES);
        }
        grown = (Slot *)realloc(slots, (slot_count + 1) * sizeof *slots);
        if (grown == NULL) {
            hystcomp_compensator_free(c);
            fail("hystcomp:outOfMemory", "no memory for another compensator");
        }
        slots = grown;
        /* Each slot's generations start at a different value, from the epoch. */
        slots[slot_count].generation = (uint32_t)epoch * 2654435761u + slot_count;
        slots[slot_count].compensator = NULL;
        slot_count++;
    }
    slots[k].compensator = c;
    if (live_handles++ == 0) {
        mexLock();
    }
    return ((uint64_t)epoch << 48) | ((uint64_t)k << 32) | slots[k].generation;
}

/* The slot of a live id, or -1. */
static long find(const mxArray *a) {
    uint64_t id;
    uint32_t slot;
    if (!mxIsUint64(a) || mxIsComplex(a) || mxGetNumberOfElements(a) != 1 || epoch == 0) {
        return -1;
    }
    id = *(const uint64_t *)mxGetData(a);
    slot = (uint32_t)((id >> 32) & 0xffffu);
    if ((id >> 48) != epoch || slot >= slot_count || slots[slot].compensator == NULL ||
        slots[slot].generation != (uint32_t)id) {
        return -1;
    }
    return (long)slot;
}

HystcompCompensator *handle_get(const mxArray *a) {
    long slot;
    if (!mxIsUint64(a) || mxIsComplex(a) || mxGetNumberOfElements(a) != 1) {
        fail("hystcomp:invalidHandle", "a compensator handle is a uint64 scalar made by "
             "hystcomp.Compensator, not %s", mxGetClassName(a));
    }
    slot = find(a);
    if (slot < 0) {
        fail("hystcomp:invalidHandle", "the compensator handle is not alive: it was deleted, "
             "or it comes from another session; create a new hystcomp.Compensator");
    }
    return slots[slot].compensator;
}

int handle_free(const mxArray *a) {
    long slot = find(a);
    if (slot < 0) {
        return 0;
    }
    hystcomp_compensator_free(slots[slot].compensator);
    slots[slot].compensator = NULL;
    slots[slot].generation++;
    if (--live_handles == 0) {
        mexUnlock();
    }
    return 1;
}

unsigned handle_count(void) {
    return live_handles;
}
