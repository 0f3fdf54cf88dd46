/* conform_curve.c — a singular curve's polyline as the conformance pass queries it: the
 * arclength parameter of each point, and the nearest point of the polyline to a query point
 * (distance, parameter, foot) through a uniform grid of its segments. Each grid cell also
 * keeps the box of its segments' parts inside it: a cell whose box is farther than the
 * nearest segment found so far is not read (a segment's nearest point to q lies in one of
 * the cells it is filed in, inside that cell's box). */
#include "core/singular/conform_internal.h"
#include "core/util/vec3.h"

#include <float.h>
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

/* The grid cell of coordinate offset u (in steps) along an axis of dim cells (every query
 * asks two per axis). */
static inline int cell_of(double u, int dim)
{
    return (int)cf_floor_clamped(u, dim);
}

static void cell_range(const cf_polyline *pl, const double lo[3], const double hi[3],
                       int a[3], int b[3])
{
    for (int k = 0; k < 3; k++) {
        a[k] = cell_of((lo[k] - pl->lo[k]) / pl->step, pl->dim[k]);
        b[k] = cell_of((hi[k] - pl->lo[k]) / pl->step, pl->dim[k]);
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

/* The passes over the grid cells of every segment: count them, file the segments, then
 * grow each cell's box by the part of the segment's box inside the cell. */
enum { GRID_COUNT, GRID_FILL, GRID_BOX };

/* The box of segment s within cell (i, j, k) grown by pad (unbounded past the grid's outer
 * faces, where cell_range clamps) merged into the cell's box. */
static void clip_into(cf_polyline *pl, size_t c, const int ijk[3], const double lo[3],
                      const double hi[3], double pad)
{
    double *b = pl->g_box[pl->g_start[c]];
    for (int k = 0; k < 3; k++) {
        double clo = ijk[k] == 0 ? -INFINITY : pl->lo[k] + ijk[k] * pl->step - pad;
        double chi =
            ijk[k] == pl->dim[k] - 1 ? INFINITY : pl->lo[k] + (ijk[k] + 1) * pl->step + pad;
        b[k] = fmin(b[k], fmax(lo[k], clo));
        b[3 + k] = fmax(b[3 + k], fmin(hi[k], chi));
    }
}

static void grid_pass(cf_polyline *pl, int pass, double pad)
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
                    if (pass == GRID_FILL)
                        pl->g_seg[pl->g_start[c]++] = (uint32_t)s;
                    else if (pass == GRID_COUNT)
                        pl->g_start[c + 1]++;
                    else
                        clip_into(pl, c, (const int[3]){ i, j, k }, lo, hi, pad);
                }
    }
}

/* The box of each block of CF_SEG_BLOCK entries of every cell (g_blk): the union of its
 * segments' boxes, the points' own coordinates (a segment's nearest point to q lies in its
 * box up to the rounding of the foot, far below the query's slack, near_bound). False when
 * out of memory. */
static bool block_boxes(cf_polyline *pl, size_t cells)
{
    pl->g_blk = malloc((pl->g_start[cells] + 1) * sizeof *pl->g_blk);
    if (!pl->g_blk)
        return false;
    for (size_t c = 0; c < cells; c++)
        for (uint32_t x0 = pl->g_start[c]; x0 < pl->g_start[c + 1]; x0 += CF_SEG_BLOCK) {
            double *b = pl->g_blk[x0];
            for (int k = 0; k < 3; k++) {
                b[k] = INFINITY;
                b[3 + k] = -INFINITY;
            }
            for (uint32_t x = x0; x < pl->g_start[c + 1] && x < x0 + CF_SEG_BLOCK; x++) {
                double lo[3], hi[3];
                seg_box(pl, pl->g_seg[x], lo, hi);
                for (int k = 0; k < 3; k++) {
                    b[k] = cf_min2(b[k], lo[k]);
                    b[3 + k] = cf_max2(b[3 + k], hi[k]);
                }
            }
        }
    return true;
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
    pl->ball = malloc(nseg(pl) * sizeof *pl->ball);
    pl->line = malloc(nseg(pl) * sizeof *pl->line);
    if (!pl->ball || !pl->line)
        return false;
    /* each ball grown by more than the rounding of its midpoint, its radius and seg_beyond's
     * comparison, which scale with the segment's coordinates and length: the query's slack
     * (near_bound) scales with the query only */
    for (size_t i = 0; i < nseg(pl); i++) {
        const double *a = pt(pl, i), *b = pt(pl, i + 1);
        double mag = 0;
        for (int k = 0; k < 3; k++) {
            pl->ball[i][k] = 0.5 * (a[k] + b[k]);
            mag = fmax(mag, fmax(fabs(a[k]), fabs(b[k])));
        }
        double h = 0.5 * ism_dist3(a, b);
        pl->ball[i][3] = h + CF_QUERY_SLACK * (h + mag);
        double *ln = pl->line[i];
        for (int k = 0; k < 3; k++) {
            ln[k] = pl->ball[i][k];
            ln[4 + k] = h > 0 ? 0.5 * (b[k] - a[k]) / h : 0;
        }
        ln[3] = h;
        ln[7] = mag;
    }
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
    grid_pass(pl, GRID_COUNT, 0);
    for (size_t c = 0; c < cells; c++)
        pl->g_start[c + 1] += pl->g_start[c];
    pl->g_seg = malloc((pl->g_start[cells] + 1) * sizeof *pl->g_seg);
    pl->g_box = malloc((pl->g_start[cells] + 1) * sizeof *pl->g_box);
    if (!pl->g_seg || !pl->g_box)
        return false;
    grid_pass(pl, GRID_FILL, 0);
    for (size_t c = cells; c > 0; c--)
        pl->g_start[c] = pl->g_start[c - 1];
    pl->g_start[0] = 0;
    for (size_t c = 0; c < cells; c++)
        for (int k = 0; k < 3; k++) {
            pl->g_box[pl->g_start[c]][k] = INFINITY;
            pl->g_box[pl->g_start[c]][3 + k] = -INFINITY;
        }
    /* the cells' own sides are computed, not the floor() that filed the segments: grown by
     * far more than their rounding */
    double mag = fmax(fmax(fabs(lo[0]), fabs(hi[0])),
                      fmax(fmax(fabs(lo[1]), fabs(hi[1])), fmax(fabs(lo[2]), fabs(hi[2]))));
    grid_pass(pl, GRID_BOX, CF_QUERY_SLACK * (pl->step + mag));
    return block_boxes(pl, cells);
}

void cf_polyline_free(cf_polyline *pl)
{
    free(pl->s);
    free(pl->g_start);
    free(pl->g_seg);
    free(pl->g_box);
    free(pl->g_blk);
    free(pl->ball);
    free(pl->line);
    memset(pl, 0, sizeof *pl);
}

/* Squared distance from q to segment sg of the polyline, its parameter t on the segment and
 * the foot f = p0 + t (p1 - p0) (each when not NULL: the ring search asks the distance
 * alone, inlined without them). */
static inline __attribute__((always_inline)) double seg_dist2(const cf_polyline *pl, size_t sg,
                                                            const double q[3], double *t_out,
                                                            double *f)
{
    const double *p0 = pt(pl, sg), *p1 = pt(pl, sg + 1);
    double d[3], w[3], dd = 0, dw = 0;
    for (int m = 0; m < 3; m++) {
        d[m] = p1[m] - p0[m];
        w[m] = q[m] - p0[m];
        dd += d[m] * d[m];
        dw += d[m] * w[m];
    }
    double t = dd > 0 ? cf_min2(1, cf_max2(0, dw / dd)) : 0, e = 0;
    for (int m = 0; m < 3; m++) {
        double fm = p0[m] + t * d[m];
        if (f)
            f[m] = fm;
        e += (q[m] - fm) * (q[m] - fm);
    }
    if (t_out)
        *t_out = t;
    return e;
}

/* An upper bound of sqrt(best), a squared distance, grown by more than the rounding of the
 * distances (INFINITY for INFINITY). */
static inline double near_bound(double best, double mag)
{
    double r = sqrt(best);
    return r + CF_QUERY_SLACK * (r + mag);
}

/* Whether cell c's segments may hold one nearer to q than best (a squared distance): its
 * box is no farther than *r, best's near_bound (set when the cell holds segments: the
 * bound its segments are read with). */
static inline __attribute__((always_inline)) bool cell_may_hold(const cf_polyline *pl, size_t c,
                                                              const double q[3], double best,
                                                              double mag, double *r)
{
    if (pl->g_start[c] == pl->g_start[c + 1])
        return false;
    *r = near_bound(best, mag);
    if (!(best < INFINITY))
        return true;
    const double *b = pl->g_box[pl->g_start[c]];
    return ism_sqdist_box3(q, b, b + 3) <= *r * *r;
}

/* Whether segment sg lies farther than r from q (d2: the squared distance from q to its
 * midpoint): its ball (midpoint, half its length, grown by its rounding) does. With r a
 * near_bound of the nearest so far, its distance exceeds that nearest's, so it could replace
 * it neither as nearer nor as an equal: not read (the segments of the cells a query reads
 * run along the curve, most of them well beyond the nearest). */
static inline __attribute__((always_inline)) bool seg_beyond(const cf_polyline *pl, size_t sg,
                                                           double d2, double r)
{
    double rr = r + pl->ball[sg][3];
    return d2 > rr * rr;
}

/* Segments of a cell read together (the midpoint distances' buffer of cell_min2 and
 * nearest_within; a cell holding more is read in runs of this many, each run's nearest
 * midpoint first). 32: 256 bytes of stack, several times what a cell holds. The tube's grid
 * cell is its radius (CF_RHO_CELLS = 2.5 mesh cells) and its curves are thinned to points at
 * least CURVE_MIN_SPACING = 0.5 cell apart, so a branch passing a cell files about 5
 * segments there (a few more where it bends, a few branches' worth where they cross). A
 * longer run would only widen the buffer, a shorter one split more cells; the answers are
 * the same either way (the first of equals is kept across runs). Not measured per preset. */
#define EST_RUN 32

/* A lower bound of seg_dist2(sg, q), the squared distance as seg_dist2 computes it: the
 * same distance from the segment's midpoint, unit direction and half length (line), cheaper
 * (no division, no modulo), less the bound of the two computations' difference. Both round
 * the coordinates (ε of their magnitude M, the segment's and q's) and sums of terms no larger
 * than (D + h)² (D = |q − midpoint|): a few ε · (D + h)(D + h + M) at most, grown to
 * CF_QUERY_SLACK times that, a million times more. */
static inline __attribute__((always_inline)) double seg_low2(const cf_polyline *pl, size_t sg,
                                                           const double q[3], double mag)
{
    const double *ln = pl->line[sg];
    double w[3] = {q[0] - ln[0], q[1] - ln[1], q[2] - ln[2]};
    double d2 = w[0] * w[0] + w[1] * w[1] + w[2] * w[2];
    double a = w[0] * ln[4] + w[1] * ln[5] + w[2] * ln[6], h = ln[3];
    double s = cf_min2(h, cf_max2(-h, a)), dh = sqrt(d2) + h;
    return d2 - 2 * s * a + s * s - CF_QUERY_SLACK * dh * (dh + mag + ln[7]);
}

/* The squared distances from q to the midpoints of the n segments sg[0..n) into d2; returns
 * the position of the nearest (0 when none is finite). */
static inline __attribute__((always_inline)) uint32_t mid_nearest(const cf_polyline *pl,
                                                                const uint32_t *sg, uint32_t n,
                                                                const double q[3], double *d2)
{
    double dmin = INFINITY;
    uint32_t arg = 0;
    for (uint32_t m = 0; m < n; m++) {
        const double *b = pl->ball[sg[m]];
        double w[3] = {q[0] - b[0], q[1] - b[1], q[2] - b[2]};
        d2[m] = w[0] * w[0] + w[1] * w[1] + w[2] * w[2];
        if (d2[m] < dmin) {
            dmin = d2[m];
            arg = m;
        }
    }
    return arg;
}

/* The order a run of segments is measured in: the one whose midpoint is nearest q (arg)
 * first, then the others (the first in arg's place). */
static inline uint32_t arg_first(uint32_t o, uint32_t arg)
{
    return o == 0 ? arg : o == arg ? 0 : o;
}

/* The nearest segment nearest_within holds: which, and its foot (the parameter t on it and
 * the point). */
typedef struct {
    size_t sg;
    double t, f[3];
} near_hit;

/* The segments filed in cell c measured against best (a squared distance; returned lowered
 * to the nearest found), r its near_bound, *hit naming the nearest. Each run of EST_RUN is
 * read the nearest midpoint first (arg_first), then of the others only those the ball test
 * (seg_beyond) passes and whose bound (seg_low2) is at most best: any other is farther. An
 * equal one is taken when it comes earlier in the run than the one held from this run
 * (measured first only for its midpoint), so *hit names the first of equals in the cell's
 * order, as reading every segment in order with `<` would keep. (The distance alone,
 * which needs no order, reads a cell by cell_min2.) */
static inline __attribute__((always_inline)) double cell_runs(const cf_polyline *pl, size_t c,
                                                            const double q[3], double mag,
                                                            double best, double r,
                                                            near_hit *hit)
{
    for (uint32_t x0 = pl->g_start[c]; x0 < pl->g_start[c + 1]; x0 += EST_RUN) {
        uint32_t n = pl->g_start[c + 1] - x0 < EST_RUN ? pl->g_start[c + 1] - x0 : EST_RUN;
        const uint32_t *sg = pl->g_seg + x0;
        double d2[EST_RUN];
        uint32_t arg = mid_nearest(pl, sg, n, q, d2), held = EST_RUN;
        for (uint32_t o = 0; o < n; o++) {
            uint32_t m = arg_first(o, arg);
            if (seg_beyond(pl, sg[m], d2[m], r) || !(seg_low2(pl, sg[m], q, mag) <= best))
                continue; /* farther than best */
            double t = 0, f[3] = {0, 0, 0};
            double e = seg_dist2(pl, sg[m], q, &t, f);
            if (e < best || (e == best && m < held && held < EST_RUN)) {
                best = e;
                r = near_bound(best, mag);
                held = m;
                hit->sg = sg[m];
                hit->t = t;
                for (int u = 0; u < 3; u++)
                    hit->f[u] = f[u];
            }
        }
    }
    return best;
}

/* A squared distance every segment within `within` of a query lies below (INFINITY for an
 * unbounded reach): a computed distance d <= within has d * d <= within * within within a few
 * ulps, which the factor exceeds a million times over. */
static inline double reach_bound(double within)
{
    /* at least DBL_MIN: below a reach of about 1.5e-154 the square underflows (to 0, which
     * would answer INFINITY even on the curve); a larger bound only reads more, the callers'
     * last test (sqrt(best) <= within) still decides */
    return within > 0 && within < INFINITY
               ? cf_max2(within * within * (1 + CF_QUERY_SLACK), DBL_MIN)
               : INFINITY;
}

/* The nearest point of the segments filed in the cells within `within` of q (INFINITY when
 * none lies that close). A cell whose box is farther than the nearest so far is skipped:
 * none of its segments would have replaced it (the first of equals is kept), so the answer
 * is the one of reading them all, the first of equals in the cells' and runs' order
 * (cell_runs; Klein bottle at E 0.00327: the zip's 2,168 queries 15.4M before). */
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
    /* from the reach's bound (reach_bound): a cell or segment beyond it is not read (one
     * tied with the nearest never is: the tests keep equals), and nothing found below it is
     * INFINITY, as a nearest beyond within was (its foot is not written then; no caller
     * reads a foot it was answered INFINITY for) */
    double cap = reach_bound(within), best = cap;
    double mag = cf_max2(fabs(q[0]), cf_max2(fabs(q[1]), fabs(q[2])));
    near_hit hit = {0, 0, {0, 0, 0}};
    for (int k = a[2]; k <= b[2]; k++)
        for (int j = a[1]; j <= b[1]; j++)
            for (int i = a[0]; i <= b[0]; i++) {
                size_t c = cell_index(pl, i, j, k);
                double r;
                if (cell_may_hold(pl, c, q, best, mag, &r))
                    best = cell_runs(pl, c, q, mag, best, r, &hit);
            }
    if (!(best < cap))
        return INFINITY;
    if (s)
        *s = pl->s[hit.sg] + hit.t * (pl->s[hit.sg + 1] - pl->s[hit.sg]);
    if (foot)
        for (int u = 0; u < 3; u++)
            foot[u] = hit.f[u];
    best = sqrt(best);
    return best <= within ? best : INFINITY;
}

/* The smallest squared distance to the segments filed in cell (i, j, k), below best (finite
 * for a finite positive reach: nearest_distance starts from its reach's bound). Inlined
 * with the distance: the ring search reads a dozen cells per query, most of them empty
 * (crossing-spheres' tube: 178k calls, callgrind). Ties need no order (the distance alone
 * is asked), so the cell's entries are read by blocks (CF_SEG_BLOCK): one beyond the bound
 * by its box is skipped whole; the others are read as cell_runs reads a run, the nearest
 * midpoint first (in the cell's order best came down slowly, a segment measured at each
 * step along the curve), each segment past the ball test (seg_beyond) and the estimate
 * (seg_low2). Reading every midpoint of the cell (cell_runs) cost the Klein bottle at
 * E 0.00327 about 1,800 instructions a query (66 midpoints: its cells hold about 24
 * segments). */
static inline __attribute__((always_inline)) double cell_min2(const cf_polyline *pl, int i,
                                                            int j, int k, const double q[3],
                                                            double best, double mag)
{
    size_t c = cell_index(pl, i, j, k);
    uint32_t x1 = pl->g_start[c + 1];
    if (pl->g_start[c] == x1)
        return best;
    double r = near_bound(best, mag);
    const double *cb = pl->g_box[pl->g_start[c]];
    if (!(ism_sqdist_box3(q, cb, cb + 3) <= r * r))
        return best;
    for (uint32_t x0 = pl->g_start[c]; x0 < x1; x0 += CF_SEG_BLOCK) {
        const double *bb = pl->g_blk[x0];
        if (!(ism_sqdist_box3(q, bb, bb + 3) <= r * r))
            continue; /* every segment of the block farther than best */
        uint32_t n = x1 - x0 < CF_SEG_BLOCK ? x1 - x0 : CF_SEG_BLOCK;
        const uint32_t *sg = pl->g_seg + x0;
        double d2[CF_SEG_BLOCK];
        uint32_t arg = mid_nearest(pl, sg, n, q, d2);
        for (uint32_t o = 0; o < n; o++) {
            uint32_t m = arg_first(o, arg);
            if (seg_beyond(pl, sg[m], d2[m], r) || !(seg_low2(pl, sg[m], q, mag) < best))
                continue; /* no nearer */
            double e = seg_dist2(pl, sg[m], q, NULL, NULL);
            if (e < best) {
                best = e;
                r = near_bound(best, mag);
            }
        }
    }
    return best;
}

/* The cells at Chebyshev distance ring (in cells) from cell c, within the grid: the smallest
 * squared distance of their segments to q, below best. */
static double ring_min2(const cf_polyline *pl, const int c[3], int ring, const double q[3],
                        double best, double mag)
{
    int a[3], b[3];
    for (int k = 0; k < 3; k++) {
        a[k] = c[k] - ring < 0 ? 0 : c[k] - ring;
        b[k] = c[k] + ring >= pl->dim[k] ? pl->dim[k] - 1 : c[k] + ring;
    }
    /* inside the shell's rows only the cells c[0] ± ring are the ring's: none when both lie
     * off the grid (a flat grid, a curve in a lattice plane), and then those rows are
     * stepped over (the same cells read, in the same order) */
    bool sides = c[0] - ring >= 0 || (ring > 0 && c[0] + ring < pl->dim[0]);
    for (int k = a[2]; k <= b[2]; k++) {
        bool k_shell = abs(k - c[2]) == ring;
        for (int j = a[1]; j <= b[1]; j++) {
            if (k_shell || abs(j - c[1]) == ring) {
                for (int i = a[0]; i <= b[0]; i++)
                    best = cell_min2(pl, i, j, k, q, best, mag);
            } else if (!sides) {
                /* on to the shell's row c[1] + ring (past j here), or done with this k */
                if (c[1] + ring > b[1])
                    break;
                j = c[1] + ring - 1;
            } else {
                if (c[0] - ring >= 0)
                    best = cell_min2(pl, c[0] - ring, j, k, q, best, mag);
                if (ring > 0 && c[0] + ring < pl->dim[0])
                    best = cell_min2(pl, c[0] + ring, j, k, q, best, mag);
            }
        }
    }
    return best;
}

/* The distance alone (no parameter or foot asked): the cells are read in rings round q's
 * own, nearest first. A segment's nearest point to q lies in a cell the segment is filed in;
 * one in ring k + 1 or beyond lies past a face of the block of rings 0..k, so once the
 * nearest found is no farther than that face (by more than the rounding of the cell sides)
 * the rest cannot be nearer. The answer
 * is the same minimum over every segment within `within` as nearest_within's. */
static double nearest_distance(const cf_polyline *pl, const double q[3], double within)
{
    double mag = cf_max2(fabs(q[0]), cf_max2(fabs(q[1]), fabs(q[2])));
    int c[3], rings = 0;
    cell_range(pl, q, q, c, c);
    for (int k = 0; k < 3; k++)
        rings = pl->dim[k] > rings ? pl->dim[k] : rings;
    /* the search starts from the reach's bound: a segment at least that far is answered
     * INFINITY either way, so every cell, block and segment beyond it is skipped (from the
     * first cell on: most of the tube's queries find nothing within reach) */
    double cap = reach_bound(within), best = cap;
    for (int ring = 0; ring < rings; ring++) {
        best = ring_min2(pl, c, ring, q, best, mag);
        /* the cells not read lie past the faces of the block of rings read, on the sides
         * where the grid goes on: q's distance to the nearest such face (at least ring
         * cells, more by q's place in its own cell) */
        double gap = INFINITY;
        for (int k = 0; k < 3; k++) {
            if (c[k] - ring > 0)
                gap = cf_min2(gap, q[k] - (pl->lo[k] + (c[k] - ring) * pl->step));
            if (c[k] + ring + 1 < pl->dim[k])
                gap = cf_min2(gap, pl->lo[k] + (c[k] + ring + 1) * pl->step - q[k]);
        }
        if (gap == INFINITY)
            break; /* every cell read */
        double clear = gap - CF_QUERY_SLACK * (fabs(gap) + pl->step + mag);
        if (clear > within || (clear > 0 && best <= clear * clear))
            break;
    }
    if (!(best < cap))
        return INFINITY; /* nothing nearer than the bound: beyond within */
    best = sqrt(best);
    return best <= within ? best : INFINITY;
}

double cf_polyline_box_distance(const cf_polyline *pl, const double q[3])
{
    return sqrt(ism_sqdist_box3(q, pl->lo, pl->hi));
}

double cf_polyline_nearest(const cf_polyline *pl, const double q[3], double within, double *s,
                           double foot[3])
{
    /* every segment lies in the points' box: one farther than within (by more than the
     * rounding of the distances below) has nothing within reach */
    double mag = cf_max2(fabs(q[0]), cf_max2(fabs(q[1]), fabs(q[2])));
    if (cf_polyline_box_distance(pl, q) > within + CF_QUERY_SLACK * (within + mag))
        return INFINITY;
    /* widening searches: a point found within w is the nearest of all (every segment within
     * w was seen), so a far `within` costs little where something is near; a near `within`
     * is searched at once (a miss would pay for every widening) */
    if (!s && !foot)
        return nearest_distance(pl, q, within);
    if (within <= NEAR_STEPS * pl->step)
        return nearest_within(pl, q, within, s, foot);
    for (double w = pl->step; w < within; w *= 2) {
        double d = nearest_within(pl, q, w, s, foot);
        if (isfinite(d))
            return d;
    }
    return nearest_within(pl, q, within, s, foot);
}
