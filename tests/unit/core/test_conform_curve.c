/* test_conform_curve.c — the conformance pass's nearest-point queries on a curve's polyline
 * (core/singular/conform_curve.c), which read only the grid cells whose box of segments may
 * hold something nearer than the nearest found so far. Against a brute-force minimum over
 * every segment (written here): on a circle, a helix, a straight segment along an axis (the
 * grid one cell thick, as for Steiner's axes) and a random walk, at queries near the curve,
 * far from it, outside its grid and on it, with small and large reaches. The distance must be
 * the minimum over all segments, INFINITY exactly when that exceeds the reach, and the foot
 * and arclength parameter must name a point of the polyline at that distance. */
#include <criterion/criterion.h>
#include <math.h>
#include <stdlib.h>

#include "core/singular/conform_internal.h"

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
static void check_queries(const double *p, size_t n, bool closed, double step)
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
    cr_assert(hits > NQUERY / 10 && misses > NQUERY / 20, "hits %zu misses %zu", hits, misses);
    cf_polyline_free(&pl);
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
    check_queries(p, NPTS, true, 0.03);
    for (int i = 0; i < NPTS; i++) { /* a helix, three turns */
        double a = 6 * M_PI * i / NPTS;
        p[3 * i] = 0.5 * cos(a);
        p[3 * i + 1] = 0.5 * sin(a);
        p[3 * i + 2] = -1 + 2.0 * i / NPTS;
    }
    check_queries(p, NPTS, false, 0.02);
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
    check_queries(p, NPTS, false, 0.0195);
    p[0] = p[1] = p[2] = 0;
    for (int i = 1; i < NPTS; i++) /* a random walk, steps up to 0.02 */
        for (int k = 0; k < 3; k++)
            p[3 * i + k] = p[3 * (i - 1) + k] + 0.02 * (urand() - 0.5);
    check_queries(p, NPTS, false, 0.01);
}
