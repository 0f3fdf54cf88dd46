/* dist_bound.h — the distance to f = 0 at a point between a mesh element's corners (a
 * triangle's centroid, an edge's midpoint) bounded through those corners: a corner v whose
 * own distance to f = 0 is dv puts the surface within |p − v| + dv of p (the triangle
 * inequality). The first-order estimate |f| / |∇f| that the polygoniser and the analysis
 * measure with grows without bound where ∇f vanishes off the surface — on a thin tube's core
 * line, beside a singular point — while the surface is near: the horn cyclide's tube (radius
 * y² / 96 beside its point (10, 0, 0)) gave 0.0623 at an edge midpoint that lies 0.0137 from
 * the surface by the canal form (an edge across the tube, half as long as it is 0.0158), and
 * its default bound 0.0554 read "not met". The smaller of the two figures is kept: the bound
 * is a proof, the estimate the usual figure; so a measurement never grows and only an
 * estimate shown too large by the bound shrinks. The polygoniser (octree/refine.h) and the
 * analysis (accuracy.c) both measure this way. */
#ifndef ISM_DIST_BOUND_H
#define ISM_DIST_BOUND_H

#include <math.h>
#include "core/util/vec3.h"

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

#endif
