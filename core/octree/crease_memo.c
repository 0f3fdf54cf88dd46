/* crease_memo.c — the per-thread memo of mixed edges' crease points (see crease_memo.h). */
#include "core/octree/crease_memo.h"

#include <stdlib.h>
#include <string.h>

#include "core/util/zeroed.h"

ism_crease_memo *ism_crease_memo_new(ism_pool *pool, int n, ism_par_cost *cost)
{
    return ism_zeroed_alloc(pool, n > 0 ? (size_t)n : 1, sizeof(ism_crease_memo), cost);
}

void ism_crease_memo_free(ism_crease_memo *m)
{
    free(m);
}

ism_crease_entry *ism_crease_memo_slot(ism_crease_memo *m, const double p[3], const double q[3])
{
    uint64_t b[6], h = 0;
    memcpy(b, p, 3 * sizeof *p);
    memcpy(b + 3, q, 3 * sizeof *q);
    for (int k = 0; k < 6; k++) /* odd multipliers mix every bit of the six coordinates */
        h = (h ^ b[k]) * 0x9e3779b97f4a7c15u;
    return &m->e[(h >> 32) & (((uint64_t)1 << ISM_CREASE_MEMO_BITS) - 1)];
}

bool ism_crease_memo_holds(const ism_crease_entry *e, const double p[3], const double q[3],
                           ism_piece lo, ism_piece hi)
{
    return e->lo == lo && e->hi == hi && lo != hi && !memcmp(e->p, p, sizeof e->p) &&
           !memcmp(e->q, q, sizeof e->q);
}
