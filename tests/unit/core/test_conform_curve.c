/* test_conform_curve.c — the conformance pass's nearest-point queries on a curve's polyline
 * (core/singular/conform_curve.c), which read only the grid cells whose box of segments may
 * hold something nearer than the nearest found so far. Against a brute-force minimum over
 * every segment (written here): on a circle, a helix, a straight segment along an axis (the
 * grid one cell thick, as for Steiner's axes) and a random walk, at queries near the curve,
 * far from it, outside its grid and on it, with small and large reaches. The distance must be
 * the minimum over all segments, INFINITY exactly when that exceeds the reach, and the foot
 * and arclength parameter must name a point of the polyline at that distance.
 * The tube's corner bound (cf_far_by_corners, conform_tube.c), which spares a triangle's
 * midpoints and centroid their queries, is checked against the same brute force: a point it
 * calls farther than r must be so, also where every corner is beyond r and a midpoint within
 * it (a triangle straddling the curve), in the three placements. */
#include <criterion/criterion.h>
#include <math.h>
#include <stdlib.h>

#include "core/singular/conform_internal.h"
#include "tests/unit/placements.h"

#define NPTS 400
#define NQUERY 3000

/* Distance from q to segment ab and the foot's fraction along it (the test's own formula). */
static double seg_distance(const double *a, const double *b, const double q[3], double *t)
{
    double ab[3], aq[3], l2 = 0, dot = 0;
    for (int k = 0; k < 3; k++) {
        ab[k] = b[k] - a[k];
        aq[k] = q[k] - a[k];
        l2 += ab[k] * ab[k];
        dot += ab[k] * aq[k];
    }
    *t = l2 > 0 ? fmin(1.0, fmax(0.0, dot / l2)) : 0.0;
    double d2 = 0;
    for (int k = 0; k < 3; k++) {
        double e = aq[k] - *t * ab[k];
        d2 += e * e;
    }
    return sqrt(d2);
}

/* Brute force: the nearest distance over every segment and the arclength of its foot. */
static double brute(const double *p, size_t n, bool closed, const double q[3], double *s)
{
    double best = INFINITY, len = 0;
    size_t segs = closed ? n : n - 1;
    for (size_t i = 0; i < segs; i++) {
        const double *a = p + 3 * i, *b = p + 3 * ((i + 1) % n);
        double t, d = seg_distance(a, b, q, &t), l = 0;
        for (int k = 0; k < 3; k++)
            l += (b[k] - a[k]) * (b[k] - a[k]);
        l = sqrt(l);
        if (d < best) {
            best = d;
            *s = len + t * l;
        }
        len += l;
    }
    return best;
}

static double urand(void) { return (double)rand() / RAND_MAX; }

/* Queries round the curve's box (and beyond it) against the brute force, for reaches from a
 * fraction of the grid's cell to most of the curve. */
static void check_queries(const double *p, size_t n, bool closed, double step, bool misses_too)
{
    cf_polyline pl;
    cr_assert(cf_polyline_init(&pl, p, n, closed, step));
    double lo[3], hi[3];
    for (int k = 0; k < 3; k++) {
        lo[k] = pl.lo[k] - 0.3;
        hi[k] = pl.hi[k] + 0.3;
    }
    const double reach[] = { 0.3 * step, step, 3.5 * step, 9 * step, 2.0 };
    size_t hits = 0, misses = 0;
    for (int i = 0; i < NQUERY; i++) {
        double q[3];
        if (i % 5 == 0) { /* on the polyline itself */
            size_t j = (size_t)rand() % (n - 1);
            double t = urand();
            for (int k = 0; k < 3; k++)
                q[k] = p[3 * j + k] + t * (p[3 * j + 3 + k] - p[3 * j + k]);
        } else {
            for (int k = 0; k < 3; k++)
                q[k] = lo[k] + urand() * (hi[k] - lo[k]);
        }
        double s_true, d_true = brute(p, n, closed, q, &s_true);
        double w = reach[i % 5];
        if (fabs(d_true - w) < 1e-9)
            continue; /* at the reach itself either answer is right */
        double d1 = cf_polyline_nearest(&pl, q, w, NULL, NULL);
        double s2, foot[3], d2 = cf_polyline_nearest(&pl, q, w, &s2, foot);
        if (d_true > w) {
            cr_assert(isinf(d1) && isinf(d2), "query %d: %g and %g for a curve %g away, reach %g",
                      i, d1, d2, d_true, w);
            misses++;
            continue;
        }
        hits++;
        cr_assert(fabs(d1 - d_true) <= 1e-12 * (1 + d_true), "query %d: %.17g, brute %.17g", i,
                  d1, d_true);
        cr_assert(d1 == d2, "query %d: the distance alone %.17g, with the foot %.17g", i, d1, d2);
        double fq = 0;
        for (int k = 0; k < 3; k++)
            fq += (foot[k] - q[k]) * (foot[k] - q[k]);
        cr_assert(fabs(sqrt(fq) - d_true) <= 1e-9 * (1 + d_true), "query %d: foot at %g, not %g", i,
                  sqrt(fq), d_true);
        /* the parameter names the foot's place on the polyline (unless two places tie) */
        double s_foot, d_foot = brute(p, n, closed, foot, &s_foot);
        cr_assert(d_foot <= 1e-9, "query %d: the foot is %g off the polyline", i, d_foot);
        cr_assert(fabs(s2 - s_foot) <= 1e-9 || fabs(s2 - s_true) <= 1e-9,
                  "query %d: parameter %.12g, the foot's %.12g", i, s2, s_foot);
    }
    cr_assert(hits > NQUERY / 10 && (!misses_too || misses > NQUERY / 20), "hits %zu misses %zu",
              hits, misses);
    cf_polyline_free(&pl);
}

/* The n points p moved into placement sh (tests/unit/placements.h): their own, by PF_OFF_*,
 * or by PF_IRR_* of a step. */
static void place(const double *p, size_t n, int sh, double step, double *moved)
{
    const double shift[3][3] = {{0, 0, 0},
                                {PF_OFF_X, PF_OFF_Y, PF_OFF_Z},
                                {PF_IRR_X * step, PF_IRR_Y * step, PF_IRR_Z * step}};
    for (size_t i = 0; i < n; i++)
        for (int k = 0; k < 3; k++)
            moved[3 * i + k] = p[3 * i + k] + shift[sh][k];
}

/* check_queries in the three placements (tests/unit/placements.h): the curve moved by
 * PF_OFF_* and by PF_IRR_* of a step, where the slack of the bounds (seg_low2's, the cells'
 * sides) scales with the coordinates' magnitude. */
static void check_placed(const double *p, size_t n, bool closed, double step, bool misses_too)
{
    static double moved[3 * NPTS];
    cr_assert(n <= NPTS);
    for (int sh = 0; sh < 3; sh++) {
        place(p, n, sh, step, moved);
        check_queries(moved, n, closed, step, misses_too);
    }
}

/* A random walk of NPTS points from the origin, steps up to 0.01 along each axis (seed). */
static void random_walk(double *p, unsigned seed)
{
    srand(seed);
    p[0] = p[1] = p[2] = 0;
    for (int i = 1; i < NPTS; i++)
        for (int k = 0; k < 3; k++)
            p[3 * i + k] = p[3 * (i - 1) + k] + 0.02 * (urand() - 0.5);
}

Test(conform_curve, circle_and_helix)
{
    static double p[3 * NPTS];
    srand(7);
    for (int i = 0; i < NPTS; i++) { /* a circle off the origin, tilted */
        double a = 2 * M_PI * i / NPTS;
        p[3 * i] = 0.1 + 0.8 * cos(a);
        p[3 * i + 1] = -0.2 + 0.8 * sin(a) * 0.6;
        p[3 * i + 2] = 0.8 * sin(a) * 0.8;
    }
    check_placed(p, NPTS, true, 0.03, true);
    for (int i = 0; i < NPTS; i++) { /* a helix, three turns */
        double a = 6 * M_PI * i / NPTS;
        p[3 * i] = 0.5 * cos(a);
        p[3 * i + 1] = 0.5 * sin(a);
        p[3 * i + 2] = -1 + 2.0 * i / NPTS;
    }
    check_placed(p, NPTS, false, 0.02, true);
}

Test(conform_curve, axis_and_random_walk)
{
    static double p[3 * NPTS];
    srand(11);
    for (int i = 0; i < NPTS; i++) { /* a straight half-axis: the grid is 1 x 1 x n cells */
        p[3 * i] = 0;
        p[3 * i + 1] = 0;
        p[3 * i + 2] = 0.5 * i / (NPTS - 1);
    }
    check_placed(p, NPTS, false, 0.0195, true);
    p[0] = p[1] = p[2] = 0;
    for (int i = 1; i < NPTS; i++) /* a random walk, steps up to 0.02 */
        for (int k = 0; k < 3; k++)
            p[3 * i + k] = p[3 * (i - 1) + k] + 0.02 * (urand() - 0.5);
    check_placed(p, NPTS, false, 0.01, true);
}

/* Cells holding hundreds of segments, read in runs of EST_RUN (conform_curve.c): the circle
 * at a step of 1 (a 2 x 2 x 2 grid: about a hundred segments a cell), the random walk at a
 * step of 100 (one cell, 399 segments). Reaches are multiples of the step, so nearly every
 * query finds the curve (misses are not required). */
Test(conform_curve, crowded_cells)
{
    static double p[3 * NPTS];
    srand(17);
    for (int i = 0; i < NPTS; i++) {
        double a = 2 * M_PI * i / NPTS;
        p[3 * i] = 0.1 + 0.8 * cos(a);
        p[3 * i + 1] = -0.2 + 0.8 * sin(a) * 0.6;
        p[3 * i + 2] = 0.8 * sin(a) * 0.8;
    }
    check_placed(p, NPTS, true, 1.0, false);
    p[0] = p[1] = p[2] = 0;
    for (int i = 1; i < NPTS; i++)
        for (int k = 0; k < 3; k++)
            p[3 * i + k] = p[3 * (i - 1) + k] + 0.02 * (urand() - 0.5);
    check_placed(p, NPTS, false, 100, false);
}

/* Exact ties: a walk of unit steps along the axes on the integer lattice, kept in a 4-cube
 * so that it passes the same edges and corners again and again, in one grid cell (step 100:
 * hundreds of segments, read in runs of EST_RUN), queried at points of the half-integer
 * lattice. Every coordinate, foot and squared distance is then exact (halves and quarters of
 * small integers, also moved by 1024 or by -325000), so a tie is a tie in the test's formula
 * and in the code's. Within one cell the segments are read in their index order, and the
 * parameter must be exactly the brute force's: the first segment in index order at the
 * minimum (brute's `d < best`), also where the segment whose midpoint is nearest q
 * (measured first) comes later. */
Test(conform_curve, exact_ties_first_segment)
{
    enum { NW = 300 };
    static double p[3 * NW];
    const double offset[] = {0, 1024, -325000};
    for (int o = 0; o < 3; o++) {
        srand(23);
        int at[3] = {0, 0, 0};
        for (int i = 0; i < NW; i++) {
            if (i > 0) {
                int k = rand() % 3, d = rand() % 2 ? 1 : -1;
                if (abs(at[k] + d) > 2)
                    d = -d;
                at[k] += d;
            }
            for (int k = 0; k < 3; k++)
                p[3 * i + k] = offset[o] + at[k];
        }
        cf_polyline pl;
        cr_assert(cf_polyline_init(&pl, p, NW, false, 100));
        int distinct_ties = 0;
        for (int i = 0; i < 2000; i++) {
            double q[3];
            for (int k = 0; k < 3; k++)
                q[k] = offset[o] + 0.5 * (rand() % 13 - 6);
            double s_true, d_true = brute(p, NW, false, q, &s_true);
            /* whether another segment at the minimum lies elsewhere on the walk */
            double len = 0;
            for (int g = 0; g + 1 < NW; g++) {
                double t, sg = seg_distance(p + 3 * g, p + 3 * g + 3, q, &t);
                distinct_ties += sg == d_true && len + t != s_true;
                len += 1;
            }
            const double reach[] = {INFINITY, 1.5, 0.75};
            double w = reach[i % 3];
            double s, foot[3], d = cf_polyline_nearest(&pl, q, w, &s, foot);
            if (d_true > w) {
                cr_assert(isinf(d), "query %d: %g for a walk %g away", i, d, d_true);
                continue;
            }
            cr_assert(d == d_true, "offset %g query %d: %.17g, brute %.17g", offset[o], i, d,
                      d_true);
            cr_assert(s == s_true, "offset %g query %d at %g %g %g: parameter %.17g, the first "
                      "segment's %.17g", offset[o], i, q[0], q[1], q[2], s, s_true);
        }
        cr_assert(distinct_ties > 1000, "offset %g: %d ties elsewhere on the walk", offset[o],
                  distinct_ties);
        cf_polyline_free(&pl);
    }
}

/* The distance alone (the ring search, which starts from its reach's bound and skips blocks
 * of CF_SEG_BLOCK segments by their boxes) at the reach's very edge: with the reach set to the
 * distance the foot search finds (d, unbounded), it must answer d bit for bit; one ulp below,
 * INFINITY. The foot search, which starts from the same bound, likewise, with the very foot
 * and parameter it found unbounded. A walk of about 400 segments in cells of about 30 (the
 * tube's Klein bottle fills its cells with about 24), queried near it and off it, in the
 * three placements. */
Test(conform_curve, distance_alone_at_the_reach)
{
    static double p[3 * NPTS], moved[3 * NPTS];
    random_walk(p, 29);
    const double step = 0.04;
    for (int sh = 0; sh < 3; sh++) {
        place(p, NPTS, sh, step, moved);
        cf_polyline pl;
        cr_assert(cf_polyline_init(&pl, moved, NPTS, false, step));
        size_t cells = (size_t)pl.dim[0] * (size_t)pl.dim[1] * (size_t)pl.dim[2], most = 0;
        for (size_t c = 0; c < cells; c++)
            if (pl.g_start[c + 1] - pl.g_start[c] > most)
                most = pl.g_start[c + 1] - pl.g_start[c];
        cr_assert(most > 3 * CF_SEG_BLOCK, "a cell of %zu segments at most", most);
        for (int i = 0; i < 2000; i++) {
            double q[3], s, foot[3];
            size_t j = (size_t)rand() % (NPTS - 1);
            double spread = i % 2 ? 0.01 : 0.1; /* beside the walk, or cells away */
            for (int k = 0; k < 3; k++)
                q[k] = moved[3 * j + k] + spread * (2 * urand() - 1);
            double d = cf_polyline_nearest(&pl, q, INFINITY, &s, foot);
            cr_assert(isfinite(d) && d > 0);
            double at = cf_polyline_nearest(&pl, q, d, NULL, NULL);
            double below = cf_polyline_nearest(&pl, q, nextafter(d, 0), NULL, NULL);
            cr_assert(at == d, "placement %d query %d: %.17g at its own distance %.17g", sh, i,
                      at, d);
            cr_assert(isinf(below), "placement %d query %d: %.17g an ulp inside %.17g", sh, i,
                      below, d);
            /* the foot search too: the same foot, bit for bit, at its own distance */
            double s2, foot2[3], at2 = cf_polyline_nearest(&pl, q, d, &s2, foot2);
            cr_assert(at2 == d && s2 == s, "placement %d query %d: %.17g at %.17g, parameter "
                      "%.17g for %.17g", sh, i, at2, d, s2, s);
            for (int k = 0; k < 3; k++)
                cr_assert(foot2[k] == foot[k]);
            cr_assert(isinf(cf_polyline_nearest(&pl, q, nextafter(d, 0), &s2, foot2)));
        }
        cf_polyline_free(&pl);
    }
}

/* The points tri_in_tube may spare (the edge midpoints and the centroid) of the triangle c,
 * with its corners' distances as vertex_distance gives them (not finite beyond r + reach):
 * each one cf_far_by_corners calls far must be farther than r by the brute force. Returns
 * how many it called far; *straddles counts those within r while every corner is beyond. */
static int check_far(const double *p, size_t n, const double c[3][3], double r, double reach,
                     int *straddles)
{
    double vd[3], s;
    bool corners_out = true;
    for (int k = 0; k < 3; k++) {
        vd[k] = brute(p, n, false, c[k], &s);
        corners_out = corners_out && vd[k] > r;
        if (vd[k] > r + reach)
            vd[k] = INFINITY;
    }
    double q[4][3];
    for (int k = 0; k < 3; k++) {
        q[0][k] = (c[0][k] + c[1][k]) / 2;
        q[1][k] = (c[1][k] + c[2][k]) / 2;
        q[2][k] = (c[2][k] + c[0][k]) / 2;
        q[3][k] = (c[0][k] + c[1][k] + c[2][k]) / 3;
    }
    const double *corner[3] = {c[0], c[1], c[2]};
    int far = 0;
    for (int j = 0; j < 4; j++) {
        double d = brute(p, n, false, q[j], &s);
        *straddles += corners_out && d <= r;
        if (!cf_far_by_corners(q[j], corner, vd, r, reach))
            continue;
        far++;
        cr_assert(d > r, "point %d called farther than r %g, but %.17g from the curve", j, r, d);
    }
    return far;
}

Test(conform_curve, far_by_corners)
{
    enum { NP = 60, NTRI = 4000 };
    const double cell = 0.02, r = 2.5 * cell; /* a tube of CF_RHO_CELLS cells */
    const double shift[3][3] = {{0, 0, 0},
                                {PF_OFF_X, PF_OFF_Y, PF_OFF_Z},
                                {PF_IRR_X * cell, PF_IRR_Y * cell, PF_IRR_Z * cell}};
    for (int sh = 0; sh < 3; sh++) {
        const double *o = shift[sh];
        /* a straight curve along x: corners 1.05 r, 1.049 r and 1.123 r from it; the midpoints
         * of the first two edges 0.668 r and 0.832 r, the centroid 0.793 r, the third
         * midpoint 1.069 r (closed forms: the distance to the x axis is sqrt(y^2 + z^2)) */
        double p[3 * NP];
        for (int i = 0; i < NP; i++) {
            p[3 * i] = o[0] - 1 + 2.0 * i / (NP - 1);
            p[3 * i + 1] = o[1];
            p[3 * i + 2] = o[2];
        }
        const double c[3][3] = {{o[0], o[1] + 1.05 * r, o[2]},
                                {o[0] + 0.3 * r, o[1] - 0.2 * r, o[2] + 1.03 * r},
                                {o[0] - 0.3 * r, o[1] + 1.05 * r, o[2] + 0.4 * r}};
        int straddles = 0;
        check_far(p, NP, c, r, r, &straddles);
        cr_assert_eq(straddles, 3, "shift %d: the points within r", sh);
        /* a helix, triangles of sides up to 4 r round points near it: both answers occur,
         * and straddling triangles among them */
        srand(13 + sh);
        for (int i = 0; i < NP; i++) {
            double a = 2 * M_PI * i / NP;
            p[3 * i] = o[0] + 0.4 * cos(a);
            p[3 * i + 1] = o[1] + 0.4 * sin(a);
            p[3 * i + 2] = o[2] + 0.5 * i / NP;
        }
        int far = 0;
        straddles = 0;
        for (int t = 0; t < NTRI; t++) {
            size_t i = (size_t)rand() % (NP - 1);
            double centre[3], tri[3][3];
            for (int k = 0; k < 3; k++)
                centre[k] = p[3 * i + k] + 3 * r * (urand() - 0.5);
            for (int v = 0; v < 3; v++)
                for (int k = 0; k < 3; k++)
                    tri[v][k] = centre[k] + 2 * r * (urand() - 0.5);
            far += check_far(p, NP, tri, r, t % 2 ? r : 0.5 * r, &straddles);
        }
        cr_assert(far > NTRI / 4 && far < 3 * NTRI, "shift %d: %d points called far", sh, far);
        cr_assert(straddles > 20, "shift %d: %d straddling points", sh, straddles);
    }
}

/* Reaches so small that their square underflows (below about 1.5e-154): a query at one of the
 * polyline's own points is at distance 0, within any reach, and must be answered 0 with the
 * point itself as its foot, by the distance alone and by the foot search; a query off the
 * curve, INFINITY. The walk of distance_alone_at_the_reach, in the three placements. */
Test(conform_curve, tiny_reach_on_the_curve)
{
    static double p[3 * NPTS], moved[3 * NPTS];
    random_walk(p, 31);
    const double step = 0.04, tiny[] = {1e-160, 1e-170, 1e-200, 1e-300, 0x1p-1074};
    for (int sh = 0; sh < 3; sh++) {
        place(p, NPTS, sh, step, moved);
        cf_polyline pl;
        cr_assert(cf_polyline_init(&pl, moved, NPTS, false, step));
        for (size_t j = 0; j + 1 < NPTS; j += 7) { /* a segment's first point: its foot */
            const double *q = moved + 3 * j;
            for (size_t w = 0; w < sizeof tiny / sizeof *tiny; w++) {
                double s, foot[3];
                double d = cf_polyline_nearest(&pl, q, tiny[w], NULL, NULL);
                double d2 = cf_polyline_nearest(&pl, q, tiny[w], &s, foot);
                cr_assert(d == 0 && d2 == 0, "placement %d point %zu reach %g: %g and %g", sh, j,
                          tiny[w], d, d2);
                for (int k = 0; k < 3; k++)
                    cr_assert(foot[k] == q[k], "placement %d point %zu: foot off the point", sh,
                              j);
                cr_assert(fabs(s - pl.s[j]) <= 1e-12, "placement %d point %zu: parameter %.17g, "
                          "the point's %.17g", sh, j, s, pl.s[j]);
                double off[3] = {q[0] + 1e-3, q[1] - 1e-3, q[2] + 1e-3};
                cr_assert(isinf(cf_polyline_nearest(&pl, off, tiny[w], NULL, NULL)) &&
                          isinf(cf_polyline_nearest(&pl, off, tiny[w], &s, foot)));
            }
        }
        cf_polyline_free(&pl);
    }
}
