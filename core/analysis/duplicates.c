/* duplicates.c — triangles that repeat another triangle's three vertices (in any order or
 * orientation). A repeated triangle turns its three edges non-manifold and splits cones of
 * faces, so the count says whether non-manifold figures come from the surface or from a
 * mesher's duplicate output. Found edge by edge: two triangles with the same vertices share
 * all three edges and have the same opposite vertex on each; each triangle is looked at only
 * on its lowest-numbered edge, where its group's opposite vertices are sorted. */
#include "core/analysis/duplicates.h"

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

bool ism_an_count_duplicates(const ism_mesh *m, const ism_an_edge_table *et, ism_analysis *a)
{
    for (uint32_t e = 0; e < et->nedges; e++)
        if (ism_an_edge_count(et, e) >= 2 &&
            !duplicates_on_edge(m, et, e, &a->duplicate_triangles))
            return false;
    return true;
}
