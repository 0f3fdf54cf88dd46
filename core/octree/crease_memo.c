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

/* Is a before b: the first coordinate where they differ smaller? */
static bool before(const double *a, const double *b)
{
    for (int k = 0; k < 3; k++)
        if (a[k] != b[k])
            return a[k] < b[k];
    return false;
}

void ism_edge_key_set(ism_edge_key *k, const double a[3], const double b[3], ism_piece lo,
                      ism_piece hi)
{
    bool swap = before(b, a);
    memcpy(k->p, swap ? b : a, sizeof k->p);
    memcpy(k->q, swap ? a : b, sizeof k->q);
    k->lo = lo, k->hi = hi;
}

bool ism_edge_key_same(const ism_edge_key *a, const ism_edge_key *b)
{
    return a->lo != a->hi && !memcmp(a, b, sizeof *a);
}

ism_crease_entry *ism_crease_memo_slot(ism_crease_memo *m, const ism_edge_key *k)
{
    uint64_t b[6], h = 0;
    memcpy(b, k->p, sizeof k->p);
    memcpy(b + 3, k->q, sizeof k->q);
    for (int i = 0; i < 6; i++) /* odd multipliers mix every bit of the six coordinates */
        h = (h ^ b[i]) * 0x9e3779b97f4a7c15u;
    return &m->e[(h >> 32) & (((uint64_t)1 << ISM_CREASE_MEMO_BITS) - 1)];
}
