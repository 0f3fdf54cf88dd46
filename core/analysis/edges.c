/* edges.c — the edge table of a triangle mesh: every distinct vertex pair of the triangles,
 * numbered in (smaller, larger) order, with the half-edges that lie on it. Built in linear
 * time by bucketing the half-edges on their smaller vertex (a counting sort) and sorting each
 * small bucket on the larger vertex; only a vertex of huge degree costs a real sort. */
#include "core/analysis/edges.h"

#include <stdlib.h>
#include <string.h>

#define SMALL_BUCKET 48

static uint32_t he_lo(const uint32_t *tri, uint32_t h)
{
    uint32_t a = tri[h], b = tri[ism_an_he_next(h)];
    return a < b ? a : b;
}

static uint32_t he_hi(const uint32_t *tri, uint32_t h)
{
    uint32_t a = tri[h], b = tri[ism_an_he_next(h)];
    return a < b ? b : a;
}

static int cmp_u64(const void *x, const void *y)
{
    uint64_t a = *(const uint64_t *)x, b = *(const uint64_t *)y;
    return (a > b) - (a < b);
}

static void insertion_sort_u64(uint64_t *k, size_t n)
{
    for (size_t i = 1; i < n; i++) {
        uint64_t v = k[i];
        size_t j = i;
        while (j > 0 && k[j - 1] > v) {
            k[j] = k[j - 1];
            j--;
        }
        k[j] = v;
    }
}

/* Sorts the half-edges of one bucket by (larger vertex, half-edge index). */
static bool sort_bucket(const uint32_t *tri, uint32_t *he, size_t n)
{
    uint64_t small[SMALL_BUCKET];
    uint64_t *key = n <= SMALL_BUCKET ? small : malloc(n * sizeof *key);
    if (!key)
        return false;
    for (size_t i = 0; i < n; i++)
        key[i] = (uint64_t)he_hi(tri, he[i]) << 32 | he[i];
    if (n <= SMALL_BUCKET)
        insertion_sort_u64(key, n);
    else
        qsort(key, n, sizeof *key, cmp_u64);
    for (size_t i = 0; i < n; i++)
        he[i] = (uint32_t)key[i];
    if (key != small)
        free(key);
    return true;
}

/* Counting sort of the half-edges of non-collapsed triangles on their smaller vertex.
 * Returns the number of half-edges placed; bucket v is edge_he[start[v] .. start[v + 1]). */
static size_t bucket_half_edges(const ism_mesh *m, uint32_t *start, uint32_t *edge_he)
{
    size_t nv = m->nverts, nt = m->ntris;
    memset(start, 0, (nv + 1) * sizeof *start);
    for (size_t t = 0; t < nt; t++)
        if (!ism_an_tri_collapsed(m->tri, t))
            for (uint32_t h = (uint32_t)(3 * t); h < 3 * t + 3; h++)
                start[he_lo(m->tri, h) + 1]++;
    for (size_t v = 0; v < nv; v++)
        start[v + 1] += start[v];
    size_t total = start[nv];
    /* fill using start[v] as a cursor, then shift back */
    for (size_t t = 0; t < nt; t++)
        if (!ism_an_tri_collapsed(m->tri, t))
            for (uint32_t h = (uint32_t)(3 * t); h < 3 * t + 3; h++)
                edge_he[start[he_lo(m->tri, h)]++] = h;
    memmove(start + 1, start, nv * sizeof *start);
    start[0] = 0;
    return total;
}

/* Numbers the runs of equal (lo, hi) in the bucketed, sorted half-edges. */
static bool number_edges(const ism_mesh *m, size_t total, ism_an_edge_table *et)
{
    size_t n = 0;
    for (size_t i = 0; i < total; i++)
        if (i == 0 || he_lo(m->tri, et->edge_he[i]) != he_lo(m->tri, et->edge_he[i - 1]) ||
            he_hi(m->tri, et->edge_he[i]) != he_hi(m->tri, et->edge_he[i - 1]))
            n++;
    et->nedges = n;
    et->edge_start = malloc((n + 1) * sizeof *et->edge_start);
    if (!et->edge_start)
        return false;
    uint32_t e = ISM_AN_NONE;
    for (size_t i = 0; i < total; i++) {
        uint32_t h = et->edge_he[i];
        if (i == 0 || he_lo(m->tri, h) != he_lo(m->tri, et->edge_he[i - 1]) ||
            he_hi(m->tri, h) != he_hi(m->tri, et->edge_he[i - 1]))
            et->edge_start[++e] = (uint32_t)i;
        et->he_edge[h] = e;
    }
    et->edge_start[n] = (uint32_t)total;
    return true;
}

bool ism_an_edge_table_build(const ism_mesh *m, ism_an_edge_table *et)
{
    memset(et, 0, sizeof *et);
    size_t nh = 3 * m->ntris;
    uint32_t *start = malloc((m->nverts + 1) * sizeof *start);
    et->edge_he = malloc((nh ? nh : 1) * sizeof *et->edge_he);
    et->he_edge = malloc((nh ? nh : 1) * sizeof *et->he_edge);
    if (!start || !et->edge_he || !et->he_edge)
        goto fail;
    for (size_t h = 0; h < nh; h++)
        et->he_edge[h] = ISM_AN_NONE;
    size_t total = bucket_half_edges(m, start, et->edge_he);
    for (size_t v = 0; v < m->nverts; v++)
        if (!sort_bucket(m->tri, et->edge_he + start[v], start[v + 1] - start[v]))
            goto fail;
    if (!number_edges(m, total, et))
        goto fail;
    free(start);
    return true;
fail:
    free(start);
    ism_an_edge_table_free(et);
    return false;
}

void ism_an_edge_table_free(ism_an_edge_table *et)
{
    free(et->he_edge);
    free(et->edge_start);
    free(et->edge_he);
    memset(et, 0, sizeof *et);
}

void ism_an_edge_ends(const ism_mesh *m, const ism_an_edge_table *et, uint32_t e, uint32_t *lo,
                      uint32_t *hi)
{
    uint32_t h = et->edge_he[et->edge_start[e]];
    *lo = he_lo(m->tri, h);
    *hi = he_hi(m->tri, h);
}
