/* dist_bound.h — the distance to f = 0 at a point between a mesh element's corners (a
 * triangle's centroid, an edge's midpoint), the one set of rules the polygoniser
 * (octree/sample_dist.h) and the analysis (accuracy.c) measure it by: the first-order
 * estimate |f| / |∇f| (ism_first_order_dist); one Newton step further where that estimate is
 * just within a bound E (ism_first_order_unsure, ism_newton_foot, ism_stepped_dist), since
 * it can fall short by its curvature term; and the bound through the corners
 * (ism_dist_through_corners): a corner v whose own distance to f = 0 is dv puts the surface
 * within |p − v| + dv of p (the triangle inequality).
 * The estimate grows without bound where ∇f vanishes off the surface — on a thin tube's core
 * line, beside a singular point — while the surface is near: the horn cyclide's tube (radius
 * y² / 96 beside its point (10, 0, 0)) gave 0.0623 at an edge midpoint that lies 0.0137 from
 * the surface by the canal form (an edge across the tube, half as long as it is 0.0158), and
 * its default bound 0.0554 read "not met". The smaller of the estimate and the corners' bound
 * is kept: the bound is a proof, the estimate the usual figure; so a measurement never grows
 * and only an estimate shown too large by the bound shrinks. */
#ifndef ISM_DIST_BOUND_H
#define ISM_DIST_BOUND_H

#include <math.h>
#include <stdbool.h>
#include "core/util/vec3.h"

/* |f| / |∇f| from f and ∇f at a point: the first-order distance to f = 0. 0 where f is
 * exactly 0 (on the surface, even where ∇f vanishes: a cone's apex); +inf where there is no
 * estimate: f or ∇f not finite, or ∇f vanishing where f is not 0 (a critical point of f off
 * the surface is not on it, however small f). */
static inline double ism_first_order_dist(double f, const double g[3])
{
    if (f == 0)
        return 0;
    double gl = ism_norm3(g);
    if (!isfinite(f) || !isfinite(gl) || !(gl > 0))
        return INFINITY;
    return fabs(f) / gl;
}

/* Corners an element has at most (a triangle). */
#define ISM_DIST_CORNERS 3

/* The squared distance from p to the nearest of v[0..n): the estimate at p can only be
 * beaten by the bound through a corner where it passes this (the corners' own distances
 * add to it). */
static inline double ism_nearest_corner_sq(const double p[3], const double *const *v, int n)
{
    double r2 = INFINITY;
    for (int k = 0; k < n; k++)
        r2 = fmin(r2, ism_sqdist3(p, v[k]));
    return r2;
}

/* min(est, min over k of |p − v[k]| + dv[k]): the estimate est at p, capped by the bound
 * through each corner whose own distance dv[k] is known (a NaN or infinite dv[k] gives no
 * bound). est may be NaN or infinite (no estimate at p): then the bound alone, INFINITY when
 * no corner gives one. */
static inline double ism_dist_through_corners(double est, const double p[3],
                                              const double *const *v, const double *dv, int n)
{
    double d = isnan(est) ? INFINITY : est;
    for (int k = 0; k < n; k++)
        if (isfinite(dv[k]))
            d = fmin(d, ism_dist3(p, v[k]) + dv[k]);
    return d;
}

/* A first-order distance d1 = |f| / |∇f| within a bound e but above this share of it is
 * measured one Newton step further (ism_stepped_dist: the polygoniser's ism_plain_dist,
 * octree/sample_dist.h, and the analysis, accuracy.c): d1 is off by the factor
 * 1 − f_nn d / (2 |∇f|) to second order (f_nn: f's second derivative along ∇f, d the
 * distance), which has either sign. The two cases found on meshes, stated here only (the
 * tests name the points): the ring torus (R = 1, r = 0.3) at E = 1e-2 in the irrational box,
 * dual mesher, a midpoint 1.00006 E from the tube (closed form) read d1 = 0.985 E, and one
 * step with ∇f(p) in place of ∇f(x) still 0.9996 E: hence the foot's own gradient
 * (test_dual.c coarse_bound_within_and_small); the gyroid ball at E = 1e-3 in its own box,
 * primal polygons, six midpoints 1.00006 E from f = 0 read d1 = 0.99999 E
 * (test_polygonise_accuracy.c gyroid_ball_within_1e_3_by_its_pieces). Both now measure
 * beyond E and are split. Below half of e only a gradient changing by its own size within d
 * could put the point beyond e. */
#define ISM_FIRST_ORDER_SURE 0.5

/* Is d1 in the band (ISM_FIRST_ORDER_SURE e, e] where it needs the second step? Never when e
 * is 0 (no bound). */
static inline bool ism_first_order_unsure(double d1, double e)
{
    return d1 > ISM_FIRST_ORDER_SURE * e && d1 <= e;
}

/* Newton's step from p onto f = 0 (f and g = ∇f at p, |g| > 0): x = p − f ∇f / |∇f|², d1
 * from p. The distance from p is then at most d1 + x's own distance (the triangle
 * inequality), x's measured to first order again: its error is second order in the
 * residual (the torus case of ISM_FIRST_ORDER_SURE at E = 1e-2: a residual of 0.0246 E, the
 * sum still 1.5e-5 E short, 6e-4 of the residual). */
static inline void ism_newton_foot(const double p[3], double f, const double g[3], double x[3])
{
    double gg = ism_dot3(g, g);
    for (int a = 0; a < 3; a++)
        x[a] = p[a] - f * g[a] / gg;
}

/* The band's distance (ism_first_order_unsure: ism_plain_dist, octree/sample_dist.h, and the
 * analysis, accuracy.c, take it from here): d1 at p plus the first-order distance at x,
 * Newton's foot from p (ism_newton_foot), from fx and gx = f and ∇f at x — an upper bound of
 * p's distance through x to the first order of x's residual. INFINITY where x has no estimate
 * (ism_first_order_dist: f or ∇f not finite there, or ∇f vanishing where f is not 0): the
 * step's length alone falls short by the same curvature term the step is for, so such a
 * point counts as beyond the bound (the polygoniser splits its node; the analysis lowers it
 * only by a proof, the corners' bound or a point of the surface found). */
static inline double ism_stepped_dist(double d1, double fx, const double gx[3])
{
    double rest = ism_first_order_dist(fx, gx);
    return isfinite(rest) ? d1 + rest : INFINITY;
}

#endif
