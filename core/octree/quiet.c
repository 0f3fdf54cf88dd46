/* quiet.c — a uniform grid over balls (see quiet.h): entries sorted by cell, a query does a
 * binary search in each of the 27 cells around the box's centre. */
#include "core/octree/quiet.h"

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

static void cell_of(const ism_quiet *q, const double p[3], int64_t c[3])
{
    for (int a = 0; a < 3; a++)
        c[a] = (int64_t)floor((p[a] - q->origin[a]) / q->cell);
}

static int cmp_u64(const void *a, const void *b)
{
    uint64_t x = *(const uint64_t *)a, y = *(const uint64_t *)b;
    return (x > y) - (x < y);
}

bool ism_quiet_init(ism_quiet *q, const double (*ball)[4], size_t n)
{
    *q = (ism_quiet){.ball = ball, .n = 0, .key = NULL, .cell = 0};
    if (n == 0 || n > UINT32_MAX)
        return true;
    q->key = malloc(n * sizeof *q->key);
    if (!q->key)
        return false;
    for (int a = 0; a < 3; a++)
        q->origin[a] = ball[0][a];
    for (size_t i = 0; i < n; i++) {
        q->cell = fmax(q->cell, ball[i][3]);
        for (int a = 0; a < 3; a++)
            q->origin[a] = fmin(q->origin[a], ball[i][a]);
    }
    if (!(q->cell > 0) || !isfinite(q->cell)) {
        free(q->key);
        q->key = NULL;
        return true;
    }
    for (size_t i = 0; i < n; i++) {
        int64_t c[3];
        cell_of(q, ball[i], c);
        q->key[i] = (uint64_t)cell_key(c) << 32 | (uint64_t)i;
    }
    qsort(q->key, n, sizeof *q->key, cmp_u64);
    q->n = n;
    return true;
}

void ism_quiet_free(ism_quiet *q)
{
    free(q->key);
    q->key = NULL;
    q->n = 0;
}

static bool inside(const double *b, const double lo[3], const double hi[3])
{
    double far = 0;
    for (int a = 0; a < 3; a++) {
        double d = fmax(fabs(lo[a] - b[a]), fabs(hi[a] - b[a]));
        far += d * d;
    }
    return far < b[3] * b[3];
}

bool ism_quiet_holds(const ism_quiet *q, const double lo[3], const double hi[3])
{
    if (q->n == 0)
        return false;
    double mid[3];
    for (int a = 0; a < 3; a++) {
        mid[a] = 0.5 * (lo[a] + hi[a]);
        if (hi[a] - lo[a] > 2 * q->cell)
            return false; /* larger than any ball */
    }
    int64_t c0[3];
    cell_of(q, mid, c0);
    for (int d = 0; d < 27; d++) {
        int64_t c[3] = {c0[0] + d % 3 - 1, c0[1] + d / 3 % 3 - 1, c0[2] + d / 9 - 1};
        uint64_t k = (uint64_t)cell_key(c) << 32;
        size_t a = 0, b = q->n; /* first entry >= k */
        while (a < b) {
            size_t m = a + (b - a) / 2;
            if (q->key[m] < k)
                a = m + 1;
            else
                b = m;
        }
        for (; a < q->n && q->key[a] >> 32 == k >> 32; a++)
            if (inside(q->ball[q->key[a] & UINT32_MAX], lo, hi))
                return true;
    }
    return false;
}
