/* duplicates.c — triangles that repeat another triangle's three vertices (in any order or
 * orientation). A repeated triangle turns its three edges non-manifold and splits cones of
 * faces, so the count says whether non-manifold figures come from the surface or from a
 * mesher's duplicate output. Found edge by edge: two triangles with the same vertices share
 * all three edges and have the same opposite vertex on each; each triangle is looked at only
 * on its lowest-numbered edge, where its group's opposite vertices are sorted. Edges are
 * independent: blocks of them run on the analysis's threads, their counts added after. */
#include "core/analysis/duplicates.h"
#include "core/analysis/blocks.h"
#include "core/util/parallel.h"

#include <stdlib.h>

#define SMALL 32

static uint32_t lowest_edge(const ism_an_edge_table *et, uint32_t t)
{
    uint32_t a = et->he_edge[3 * t], b = et->he_edge[3 * t + 1], c = et->he_edge[3 * t + 2];
    uint32_t m = a < b ? a : b;
    return m < c ? m : c;
}

static void insertion_sort(uint32_t *v, uint32_t n)
{
    for (uint32_t i = 1; i < n; i++) {
        uint32_t x = v[i], j = i;
        for (; j > 0 && v[j - 1] > x; j--)
            v[j] = v[j - 1];
        v[j] = x;
    }
}

static int cmp_u32(const void *x, const void *y)
{
    uint32_t a = *(const uint32_t *)x, b = *(const uint32_t *)y;
    return (a > b) - (a < b);
}

/* Duplicates among the triangles of edge e that have e as their lowest edge. */
static bool duplicates_on_edge(const ism_mesh *m, const ism_an_edge_table *et, uint32_t e,
                               size_t *count)
{
    uint32_t n = ism_an_edge_count(et, e), small[SMALL], k = 0;
    const uint32_t *he = et->edge_he + et->edge_start[e];
    uint32_t *opposite = n <= SMALL ? small : malloc(n * sizeof *opposite);
    if (!opposite)
        return false;
    for (uint32_t i = 0; i < n; i++)
        if (lowest_edge(et, he[i] / 3) == e)
            opposite[k++] = m->tri[ism_an_he_prev(he[i])];
    if (k <= SMALL)
        insertion_sort(opposite, k);
    else
        qsort(opposite, k, sizeof *opposite, cmp_u32);
    for (uint32_t i = 1; i < k; i++)
        *count += opposite[i] == opposite[i - 1];
    if (opposite != small)
        free(opposite);
    return true;
}

typedef struct dup_pass {
    const ism_mesh *m;
    const ism_an_edge_table *et;
    size_t *count; /* per block; SIZE_MAX: out of memory */
} dup_pass;

static void dup_block(void *ctx, size_t blk, int thread)
{
    (void)thread;
    dup_pass *d = ctx;
    size_t n = 0, end = ism_block_end(blk, ISM_AN_TRI_BLOCK, d->et->nedges);
    for (size_t e = blk * ISM_AN_TRI_BLOCK; e < end; e++)
        if (ism_an_edge_count(d->et, (uint32_t)e) >= 2 &&
            !duplicates_on_edge(d->m, d->et, (uint32_t)e, &n)) {
            n = SIZE_MAX;
            break;
        }
    d->count[blk] = n;
}

bool ism_an_count_duplicates(const ism_mesh *m, const ism_an_edge_table *et, ism_pool *pool,
                             ism_analysis *a)
{
    size_t nblocks = ism_blocks(et->nedges, ISM_AN_TRI_BLOCK);
    dup_pass d = {m, et, malloc((nblocks ? nblocks : 1) * sizeof *d.count)};
    if (!d.count)
        return false;
    ism_pool_for(pool, nblocks, dup_block, &d, NULL);
    bool ok = true;
    for (size_t b = 0; b < nblocks; b++) {
        ok = ok && d.count[b] != SIZE_MAX;
        a->duplicate_triangles += ok ? d.count[b] : 0;
    }
    free(d.count);
    return ok;
}
