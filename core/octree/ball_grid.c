/* ball_grid.c — balls sorted by the cell of their centre (see ball_grid.h); a cell's entries
 * are found by binary search. */
#include "core/octree/ball_grid.h"

#include <math.h>
#include <stdlib.h>

/* Cell coordinates are kept in 10 bits an axis (cells are at least as large as the largest
 * radius; beyond 1024 cells an axis the grid wraps, which only puts more balls in a cell). */
#define AXIS_BITS 10
#define AXIS_MASK ((1u << AXIS_BITS) - 1)

static uint32_t cell_key(const int64_t c[3])
{
    return (uint32_t)(((uint64_t)c[0] & AXIS_MASK) << (2 * AXIS_BITS) |
                      ((uint64_t)c[1] & AXIS_MASK) << AXIS_BITS | ((uint64_t)c[2] & AXIS_MASK));
}

void ism_ball_grid_cell_of(const ism_ball_grid *g, const double p[3], int64_t c[3])
{
    for (int a = 0; a < 3; a++)
        c[a] = (int64_t)floor((p[a] - g->origin[a]) / g->cell);
}

static int cmp_u64(const void *a, const void *b)
{
    uint64_t x = *(const uint64_t *)a, y = *(const uint64_t *)b;
    return (x > y) - (x < y);
}

bool ism_ball_grid_init(ism_ball_grid *g, const double *ball, size_t stride, size_t radius,
                        size_t n)
{
    *g = (ism_ball_grid){.n = 0, .key = NULL, .cell = 0};
    if (n == 0 || n > UINT32_MAX)
        return true;
    g->key = malloc(n * sizeof *g->key);
    if (!g->key)
        return false;
    for (int a = 0; a < 3; a++)
        g->origin[a] = ball[a];
    for (size_t i = 0; i < n; i++) {
        const double *b = ball + i * stride;
        g->cell = fmax(g->cell, b[radius]);
        for (int a = 0; a < 3; a++)
            g->origin[a] = fmin(g->origin[a], b[a]);
    }
    if (!(g->cell > 0) || !isfinite(g->cell)) {
        free(g->key);
        g->key = NULL;
        return true;
    }
    for (size_t i = 0; i < n; i++) {
        int64_t c[3];
        ism_ball_grid_cell_of(g, ball + i * stride, c);
        g->key[i] = (uint64_t)cell_key(c) << 32 | (uint64_t)i;
    }
    qsort(g->key, n, sizeof *g->key, cmp_u64);
    g->n = n;
    return true;
}

void ism_ball_grid_free(ism_ball_grid *g)
{
    free(g->key);
    g->key = NULL;
    g->n = 0;
}

/* The first entry from a on whose key is at least k. */
static size_t lower_bound(const ism_ball_grid *g, size_t a, uint64_t k)
{
    size_t b = g->n;
    while (a < b) {
        size_t m = a + (b - a) / 2;
        if (g->key[m] < k)
            a = m + 1;
        else
            b = m;
    }
    return a;
}

/* Cells z .. z1 of one column are read as runs whose masked z coordinates do not wrap: the
 * keys of a run are consecutive. A run's search starts after the last run's entries when
 * its keys come later (no axis wrapped in between). */
bool ism_ball_grid_any(const ism_ball_grid *g, const int64_t c0[3], const int64_t c1[3],
                       bool (*hit)(uint32_t ball, const void *arg), const void *arg)
{
    size_t from = 0;
    uint64_t last = 0; /* the last run's last cell key + 1 (0: none read yet) */
    for (int64_t x = c0[0]; x <= c1[0]; x++)
        for (int64_t y = c0[1]; y <= c1[1]; y++)
            for (int64_t z = c0[2]; z <= c1[2];) {
                int64_t end = z + (int64_t)(AXIS_MASK - ((uint64_t)z & AXIS_MASK));
                end = end < c1[2] ? end : c1[2];
                int64_t a[3] = {x, y, z}, b[3] = {x, y, end};
                uint64_t ka = cell_key(a), kb = cell_key(b);
                if (ka < last)
                    from = 0;
                size_t i = lower_bound(g, from, ka << 32);
                for (; i < g->n && g->key[i] >> 32 <= kb; i++)
                    if (hit((uint32_t)(g->key[i] & UINT32_MAX), arg))
                        return true;
                from = i;
                last = kb + 1;
                z = end + 1;
            }
    return false;
}
