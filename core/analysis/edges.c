/* edges.c — the edge table of a triangle mesh: every distinct vertex pair of the triangles,
 * numbered in (smaller, larger) order, with the half-edges that lie on it. Built in linear
 * time by bucketing the half-edges on their smaller vertex (a counting sort) and sorting each
 * small bucket on the larger vertex; only a vertex of huge degree costs a real sort. Every
 * step runs in blocks on a pool's threads (counts and bucket places by atomic increments;
 * a bucket's sort on (larger vertex, half-edge) makes its order the same whoever filled it;
 * edges numbered per block from prefix sums), so the table is the same on any number. */
#include "core/analysis/edges.h"
#include "core/analysis/blocks.h"
#include "core/util/parallel.h"

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

/* Work per task of the build's loops (over triangles: blocks.h's ISM_AN_TRI_BLOCK): fixed
 * sizes, so the table never depends on the number of threads (it would not anyway: every
 * step below writes a result that is the same whichever thread made it). A few thousand
 * items: a task is tens of microseconds, far above what handing it out costs. */
#define VERT_BLOCK 2048
#define HE_BLOCK 16384

typedef struct builder {
    const ism_mesh *m;
    ism_an_edge_table *et;
    uint32_t *start;  /* nverts + 1: bucket v is edge_he[start[v] .. start[v + 1]) */
    uint32_t *cursor; /* nverts: the next free place in each bucket while filling */
    size_t total;     /* half-edges in the buckets */
    size_t *runs;     /* per block of half-edges: edges starting in it, then their offsets */
    int failed;       /* a bucket's sort found no memory */
} builder;

/* Bucket sizes: the half-edges of non-collapsed triangles counted on their smaller vertex
 * (start[v + 1]); the collapsed triangles' half-edges get no edge. */
static void count_block(void *ctx, size_t blk, int thread)
{
    (void)thread;
    builder *w = ctx;
    const uint32_t *tri = w->m->tri;
    size_t lo = blk * ISM_AN_TRI_BLOCK, hi = ism_block_end(blk, ISM_AN_TRI_BLOCK, w->m->ntris);
    for (size_t t = lo; t < hi; t++) {
        if (ism_an_tri_collapsed(tri, t)) {
            for (size_t h = 3 * t; h < 3 * t + 3; h++)
                w->et->he_edge[h] = ISM_AN_NONE;
            continue;
        }
        for (uint32_t h = (uint32_t)(3 * t); h < 3 * t + 3; h++)
            __atomic_fetch_add(&w->start[he_lo(tri, h) + 1], 1, __ATOMIC_RELAXED);
    }
}

/* Each half-edge into its bucket, at a place the bucket's cursor hands out (the order inside
 * a bucket is whatever the threads made: the bucket's sort fixes it). */
static void fill_block(void *ctx, size_t blk, int thread)
{
    (void)thread;
    builder *w = ctx;
    const uint32_t *tri = w->m->tri;
    size_t lo = blk * ISM_AN_TRI_BLOCK, hi = ism_block_end(blk, ISM_AN_TRI_BLOCK, w->m->ntris);
    for (size_t t = lo; t < hi; t++)
        if (!ism_an_tri_collapsed(tri, t))
            for (uint32_t h = (uint32_t)(3 * t); h < 3 * t + 3; h++)
                w->et->edge_he[__atomic_fetch_add(&w->cursor[he_lo(tri, h)], 1,
                                                  __ATOMIC_RELAXED)] = h;
}

static void sort_block(void *ctx, size_t blk, int thread)
{
    (void)thread;
    builder *w = ctx;
    size_t lo = blk * VERT_BLOCK, hi = ism_block_end(blk, VERT_BLOCK, w->m->nverts);
    for (size_t v = lo; v < hi; v++)
        if (!sort_bucket(w->m->tri, w->et->edge_he + w->start[v], w->start[v + 1] - w->start[v]))
            __atomic_store_n(&w->failed, 1, __ATOMIC_RELAXED);
}

/* Half-edge i of the sorted buckets starts a run of equal (lo, hi): a new edge. */
static bool starts_edge(const uint32_t *tri, const uint32_t *edge_he, size_t i)
{
    return i == 0 || he_lo(tri, edge_he[i]) != he_lo(tri, edge_he[i - 1]) ||
           he_hi(tri, edge_he[i]) != he_hi(tri, edge_he[i - 1]);
}

static void count_runs(void *ctx, size_t blk, int thread)
{
    (void)thread;
    builder *w = ctx;
    size_t lo = blk * HE_BLOCK, hi = ism_block_end(blk, HE_BLOCK, w->total), n = 0;
    for (size_t i = lo; i < hi; i++)
        n += starts_edge(w->m->tri, w->et->edge_he, i);
    w->runs[blk] = n;
}

/* The block's edges numbered from the count of those before it. */
static void number_runs(void *ctx, size_t blk, int thread)
{
    (void)thread;
    builder *w = ctx;
    ism_an_edge_table *et = w->et;
    size_t lo = blk * HE_BLOCK, hi = ism_block_end(blk, HE_BLOCK, w->total);
    uint32_t e = (uint32_t)w->runs[blk] - 1; /* the edge running into the block (wraps at 0) */
    for (size_t i = lo; i < hi; i++) {
        uint32_t h = et->edge_he[i];
        if (starts_edge(w->m->tri, et->edge_he, i))
            et->edge_start[++e] = (uint32_t)i;
        et->he_edge[h] = e;
    }
}

/* Buckets of half-edges on their smaller vertex (a counting sort), each sorted on the larger
 * vertex, runs of equal pairs numbered as edges: every step a loop over blocks on pool. */
static bool build_table(builder *w, ism_pool *pool)
{
    const ism_mesh *m = w->m;
    ism_an_edge_table *et = w->et;
    size_t nv = m->nverts, tblocks = ism_blocks(m->ntris, ISM_AN_TRI_BLOCK);
    memset(w->start, 0, (nv + 1) * sizeof *w->start);
    ism_pool_for(pool, tblocks, count_block, w, NULL);
    for (size_t v = 0; v < nv; v++)
        w->start[v + 1] += w->start[v];
    w->total = w->start[nv];
    memcpy(w->cursor, w->start, (nv ? nv : 1) * sizeof *w->cursor);
    ism_pool_for(pool, tblocks, fill_block, w, NULL);
    ism_pool_for(pool, ism_blocks(nv, VERT_BLOCK), sort_block, w, NULL);
    size_t hblocks = ism_blocks(w->total, HE_BLOCK);
    if (w->failed || !(w->runs = malloc((hblocks ? hblocks : 1) * sizeof *w->runs)))
        return false;
    ism_pool_for(pool, hblocks, count_runs, w, NULL);
    et->nedges = ism_counts_to_offsets(w->runs, hblocks);
    if (!(et->edge_start = malloc((et->nedges + 1) * sizeof *et->edge_start)))
        return false;
    ism_pool_for(pool, hblocks, number_runs, w, NULL);
    et->edge_start[et->nedges] = (uint32_t)w->total;
    return true;
}

bool ism_an_edge_table_build_on(const ism_mesh *m, ism_pool *pool, ism_an_edge_table *et)
{
    memset(et, 0, sizeof *et);
    size_t nh = 3 * m->ntris;
    builder w = {.m = m, .et = et};
    w.start = malloc((m->nverts + 1) * sizeof *w.start);
    w.cursor = malloc((m->nverts ? m->nverts : 1) * sizeof *w.cursor);
    et->edge_he = malloc((nh ? nh : 1) * sizeof *et->edge_he);
    et->he_edge = malloc((nh ? nh : 1) * sizeof *et->he_edge);
    bool ok = w.start && w.cursor && et->edge_he && et->he_edge && build_table(&w, pool);
    free(w.start);
    free(w.cursor);
    free(w.runs);
    if (!ok)
        ism_an_edge_table_free(et);
    return ok;
}

bool ism_an_edge_table_build(const ism_mesh *m, ism_an_edge_table *et)
{
    return ism_an_edge_table_build_on(m, NULL, et);
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
