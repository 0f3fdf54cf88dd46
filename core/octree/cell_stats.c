/* cell_stats.c — counter arithmetic over ism_cell_stats, counter by counter. */
#include "core/octree/cell_stats.h"

#include <stdint.h>
#include <string.h>

_Static_assert(sizeof(ism_cell_stats) % sizeof(uint64_t) == 0,
               "ism_cell_stats holds uint64_t counters only");

#define NCOUNTERS (sizeof(ism_cell_stats) / sizeof(uint64_t))

ism_cell_stats ism_cell_stats_minus(const ism_cell_stats *after, const ism_cell_stats *before)
{
    uint64_t a[NCOUNTERS], b[NCOUNTERS];
    memcpy(a, after, sizeof a);
    memcpy(b, before, sizeof b);
    for (size_t k = 0; k < NCOUNTERS; k++)
        a[k] -= b[k];
    ism_cell_stats d;
    memcpy(&d, a, sizeof d);
    return d;
}

void ism_cell_stats_add(ism_cell_stats *st, const ism_cell_stats *d)
{
    uint64_t sum[NCOUNTERS], add[NCOUNTERS];
    memcpy(sum, st, sizeof sum);
    memcpy(add, d, sizeof add);
    for (size_t k = 0; k < NCOUNTERS; k++)
        sum[k] += add[k];
    memcpy(st, sum, sizeof sum);
}
