/* conform_curve.c — a singular curve's polyline as the conformance pass queries it: the
 * arclength parameter of each point, and the nearest point of the polyline to a query point
 * (distance, parameter, foot) through a uniform grid of its segments. */
#include "core/singular/conform_internal.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

/* Grid cells per axis at most (the cell grows beyond the asked step for long curves; the
 * grid's memory stays bounded by about 1 MiB of counts). */
#define GRID_MAX_DIM 64
/* Queries reaching at most this many grid cells are answered in one search. */
#define NEAR_STEPS 4

static size_t nseg(const cf_polyline *pl)
{
    return pl->closed ? pl->n : pl->n - 1;
}

static const double *pt(const cf_polyline *pl, size_t i)
{
    return pl->p + 3 * (i % pl->n);
}

static void cell_range(const cf_polyline *pl, const double lo[3], const double hi[3],
                       int a[3], int b[3])
{
    for (int k = 0; k < 3; k++) {
        double x = floor((lo[k] - pl->lo[k]) / pl->step), y = floor((hi[k] - pl->lo[k]) / pl->step);
        a[k] = x < 0 ? 0 : x >= pl->dim[k] ? pl->dim[k] - 1 : (int)x;
        b[k] = y < 0 ? 0 : y >= pl->dim[k] ? pl->dim[k] - 1 : (int)y;
    }
}

static size_t cell_index(const cf_polyline *pl, int i, int j, int k)
{
    return ((size_t)k * (size_t)pl->dim[1] + (size_t)j) * (size_t)pl->dim[0] + (size_t)i;
}

static void seg_box(const cf_polyline *pl, size_t s, double lo[3], double hi[3])
{
    const double *a = pt(pl, s), *b = pt(pl, s + 1);
    for (int k = 0; k < 3; k++) {
        lo[k] = fmin(a[k], b[k]);
        hi[k] = fmax(a[k], b[k]);
    }
}

/* Visits the grid cells of every segment: counts (fill == false) or fills the CSR lists. */
static void grid_pass(cf_polyline *pl, bool fill)
{
    for (size_t s = 0; s < nseg(pl); s++) {
        double lo[3], hi[3];
        int a[3], b[3];
        seg_box(pl, s, lo, hi);
        cell_range(pl, lo, hi, a, b);
        for (int k = a[2]; k <= b[2]; k++)
            for (int j = a[1]; j <= b[1]; j++)
                for (int i = a[0]; i <= b[0]; i++) {
                    size_t c = cell_index(pl, i, j, k);
                    if (fill)
                        pl->g_seg[pl->g_start[c]++] = (uint32_t)s;
                    else
                        pl->g_start[c + 1]++;
                }
    }
}

bool cf_polyline_init(cf_polyline *pl, const double *p, size_t n, bool closed, double step)
{
    memset(pl, 0, sizeof *pl);
    if (n < 2 || !(step > 0))
        return false;
    pl->p = p;
    pl->n = n;
    pl->closed = closed;
    pl->s = malloc((n + 1) * sizeof *pl->s);
    if (!pl->s)
        return false;
    double lo[3] = {p[0], p[1], p[2]}, hi[3] = {p[0], p[1], p[2]};
    pl->s[0] = 0;
    for (size_t i = 1; i <= n; i++) {
        const double *a = pt(pl, i - 1), *b = pt(pl, i);
        pl->s[i] = pl->s[i - 1] + sqrt((a[0] - b[0]) * (a[0] - b[0]) +
                                       (a[1] - b[1]) * (a[1] - b[1]) +
                                       (a[2] - b[2]) * (a[2] - b[2]));
        for (int k = 0; k < 3; k++) {
            lo[k] = fmin(lo[k], b[k]);
            hi[k] = fmax(hi[k], b[k]);
        }
    }
    pl->length = closed ? pl->s[n] : pl->s[n - 1];
    for (int k = 0; k < 3; k++)
        pl->hi[k] = hi[k];
    double ext = fmax(hi[0] - lo[0], fmax(hi[1] - lo[1], hi[2] - lo[2]));
    pl->step = fmax(step, ext / (GRID_MAX_DIM - 1));
    size_t cells = 1;
    for (int k = 0; k < 3; k++) {
        pl->lo[k] = lo[k];
        pl->dim[k] = (int)floor((hi[k] - lo[k]) / pl->step) + 1;
        cells *= (size_t)pl->dim[k];
    }
    pl->g_start = calloc(cells + 1, sizeof *pl->g_start);
    if (!pl->g_start)
        return false;
    grid_pass(pl, false);
    for (size_t c = 0; c < cells; c++)
        pl->g_start[c + 1] += pl->g_start[c];
    pl->g_seg = malloc((pl->g_start[cells] + 1) * sizeof *pl->g_seg);
    if (!pl->g_seg)
        return false;
    grid_pass(pl, true);
    for (size_t c = cells; c > 0; c--)
        pl->g_start[c] = pl->g_start[c - 1];
    pl->g_start[0] = 0;
    return true;
}

void cf_polyline_free(cf_polyline *pl)
{
    free(pl->s);
    free(pl->g_start);
    free(pl->g_seg);
    memset(pl, 0, sizeof *pl);
}

/* The nearest point of the segments filed in the cells within `within` of q (INFINITY when
 * none lies that close). */
static double nearest_within(const cf_polyline *pl, const double q[3], double within, double *s,
                             double foot[3])
{
    double lo[3], hi[3];
    for (int k = 0; k < 3; k++) {
        lo[k] = q[k] - within;
        hi[k] = q[k] + within;
        if (hi[k] < pl->lo[k] || lo[k] > pl->lo[k] + pl->dim[k] * pl->step)
            return INFINITY;
    }
    int a[3], b[3];
    cell_range(pl, lo, hi, a, b);
    double best = INFINITY;
    for (int k = a[2]; k <= b[2]; k++)
        for (int j = a[1]; j <= b[1]; j++)
            for (int i = a[0]; i <= b[0]; i++) {
                size_t c = cell_index(pl, i, j, k);
                for (uint32_t x = pl->g_start[c]; x < pl->g_start[c + 1]; x++) {
                    size_t sg = pl->g_seg[x];
                    const double *p0 = pt(pl, sg), *p1 = pt(pl, sg + 1);
                    double d[3], w[3], dd = 0, dw = 0;
                    for (int m = 0; m < 3; m++) {
                        d[m] = p1[m] - p0[m];
                        w[m] = q[m] - p0[m];
                        dd += d[m] * d[m];
                        dw += d[m] * w[m];
                    }
                    double t = dd > 0 ? fmin(1, fmax(0, dw / dd)) : 0, e = 0, f[3];
                    for (int m = 0; m < 3; m++) {
                        f[m] = p0[m] + t * d[m];
                        e += (q[m] - f[m]) * (q[m] - f[m]);
                    }
                    if (e < best) {
                        best = e;
                        if (s)
                            *s = pl->s[sg] + t * (pl->s[sg + 1] - pl->s[sg]);
                        if (foot)
                            for (int m = 0; m < 3; m++)
                                foot[m] = f[m];
                    }
                }
            }
    best = sqrt(best);
    return best <= within ? best : INFINITY;
}

double cf_polyline_box_distance(const cf_polyline *pl, const double q[3])
{
    double d2 = 0;
    for (int k = 0; k < 3; k++) {
        double e = fmax(0, fmax(pl->lo[k] - q[k], q[k] - pl->hi[k]));
        d2 += e * e;
    }
    return sqrt(d2);
}

double cf_polyline_nearest(const cf_polyline *pl, const double q[3], double within, double *s,
                           double foot[3])
{
    /* every segment lies in the points' box: one farther than within (by more than the
     * rounding of the distances below) has nothing within reach */
    double mag = fmax(fabs(q[0]), fmax(fabs(q[1]), fabs(q[2])));
    if (cf_polyline_box_distance(pl, q) > within + CF_QUERY_SLACK * (within + mag))
        return INFINITY;
    /* widening searches: a point found within w is the nearest of all (every segment within
     * w was seen), so a far `within` costs little where something is near; a near `within`
     * is searched at once (a miss would pay for every widening) */
    if (within <= NEAR_STEPS * pl->step)
        return nearest_within(pl, q, within, s, foot);
    for (double w = pl->step; w < within; w *= 2) {
        double d = nearest_within(pl, q, w, s, foot);
        if (isfinite(d))
            return d;
    }
    return nearest_within(pl, q, within, s, foot);
}
