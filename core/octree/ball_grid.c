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

size_t ism_ball_grid_first(const ism_ball_grid *g, const int64_t c[3])
{
    uint64_t k = (uint64_t)cell_key(c) << 32;
    size_t a = 0, b = g->n; /* first entry >= k */
    while (a < b) {
        size_t m = a + (b - a) / 2;
        if (g->key[m] < k)
            a = m + 1;
        else
            b = m;
    }
    return a;
}

bool ism_ball_grid_in(const ism_ball_grid *g, size_t i, const int64_t c[3])
{
    return i < g->n && g->key[i] >> 32 == cell_key(c);
}
