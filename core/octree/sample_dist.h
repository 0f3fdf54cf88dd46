/* sample_dist.h — the polygoniser's distance from a point to f = 0, measured through its
 * sampler: the estimate (the first-order |f| / |∇f|, one Newton step further just within the
 * bound: core/util/dist_bound.h's rule), and that estimate lowered where it passes the bound
 * (the bound through the corners of the point's element, the surface searched for near it).
 * The octree's acceptance (refine.c, cell_error.c, triangulate.c) and the dual mesher's
 * measures (dual.c, dual_balls.c, dual_crease.c) all take these. */
#ifndef ISM_SAMPLE_DIST_H
#define ISM_SAMPLE_DIST_H

#include <math.h>
#include <stddef.h>
#include "core/octree/sampler.h"

/* ism_sample_dist at p, a point between the corners v[0..n) (n <= ISM_DIST_CORNERS) of a
 * triangle or an edge the polygoniser would emit, where the estimate is finite and passes
 * s->dist_above (> 0: the polygoniser's max_error) measured again: first capped by the bound
 * through those corners (core/util/dist_bound.h; their own distances are evaluated only where
 * the estimate also passes the nearest corner, which near a smooth surface it never does: a
 * chord sags far less than its length), then, if still beyond dist_above, by the surface
 * found near p (core/analysis/nearest.h: Newton's foot, and rays where s->rays_below says),
 * the analysis' own search. Each only lowers the figure, and every point either finds lies
 * on f = 0, so the figure stays an upper bound of the distance wherever it was lowered. */
double ism_dist_capped(ism_sampler *s, const double p[3], double d, const double *const *v,
                       int n);

/* The distance from p to f = 0 to decide "within e", from f and g = ∇f at p: the first-order
 * d1 = |f| / |∇f| (ism_first_order_dist) outside the band ism_first_order_unsure (above e/2,
 * within e); in it, ism_stepped_dist: d1 plus the first-order distance at Newton's foot x
 * (ism_newton_foot), INFINITY where x has none (core/util/dist_bound.h). */
double ism_plain_dist(ism_sampler *s, const double p[3], double f, const double g[3],
                      double e);

/* ism_plain_dist of the n points p[0..n) (f, g: f and ∇f there) into out, the second steps'
 * gradients gathered ISM_GRAD_BATCH at a time (ism_sample_grad_batch, which evaluates them in
 * passes of ISM_GRAD_UNROLLED: sampler.c): the same values bit for bit
 * (tests/unit/core/test_stepped_dist.c), for callers that measure points in batches. */
void ism_plain_dists(ism_sampler *s, const double (*p)[3], const double *f,
                     const double (*g)[3], double e, double *out, size_t n);

/* d (p's estimate: ism_plain_dist's under s->dist_above) lowered by ism_dist_capped when it
 * is finite and beyond dist_above; d itself otherwise (INFINITY, no estimate, stays: the
 * node is split again). */
static inline double ism_dist_beyond(ism_sampler *s, const double p[3], double d,
                                     const double *const *v, int n)
{
    return d > s->dist_above && isfinite(d) ? ism_dist_capped(s, p, d, v, n) : d;
}

/* The distance at p between the corners v[0..n): f and ∇f evaluated at p, ism_plain_dist
 * under s->dist_above, then ism_dist_beyond. */
static inline double ism_sample_dist_between(ism_sampler *s, const double p[3],
                                             const double *const *v, int n)
{
    double g[3];
    double f = ism_sample_grad(s, p, g);
    return ism_dist_beyond(s, p, ism_plain_dist(s, p, f, g, s->dist_above), v, n);
}

#endif
