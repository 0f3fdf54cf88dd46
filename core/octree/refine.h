/* refine.h — the a-posteriori half of the max_error bound: the distance to f = 0 of the
 * triangles a leaf really emitted (its polygons depend on its neighbours' tiles, which the
 * octree's estimate cannot see), and the set of nodes the next round of the octree must
 * split because their triangles were measured farther than the bound. */
#ifndef ISM_REFINE_H
#define ISM_REFINE_H

#include <math.h>
#include <stddef.h>
#include <stdint.h>
#include <stdbool.h>
#include "core/octree/cell_types.h"
#include "core/octree/octree.h"
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
 * d1 = |f| / |∇f| (ism_first_order_dist) outside the band ism_first_order_unsure
 * (core/util/dist_bound.h: above e/2, within e); in it, d1 + |f(x)| / |∇f(x)| for x Newton's
 * step from p (ism_newton_foot), where d1 alone falls short by its curvature term (∇f(p) in
 * place of ∇f(x) does too: the ring torus's 1.00006 E midpoint read 0.9996 E so). INFINITY
 * where the residual has no estimate (ism_sample_dist). The dual mesher's measures and the
 * polygoniser's (ism_sample_dist_between, ism_emitted_error) both take it. */
double ism_plain_dist(ism_sampler *s, const double p[3], double f, const double g[3],
                      double e);

/* ism_plain_dist of the n points p[0..n) (f, g: f and ∇f there) into out, the second steps'
 * gradients in batches (ism_sample_grad_batch, ISM_GRAD_BATCH at a time): the same values,
 * for callers that measure points in batches. */
void ism_plain_dists(ism_sampler *s, const double (*p)[3], const double *f,
                     const double (*g)[3], double e, double *out, size_t n);

/* d (p's estimate: ism_plain_dist's under s->dist_above) lowered by ism_dist_capped when it
 * is finite and beyond dist_above; d itself otherwise. */
static inline double ism_dist_beyond(ism_sampler *s, const double p[3], double d,
                                     const double *const *v, int n)
{
    return d > s->dist_above && isfinite(d) ? ism_dist_capped(s, p, d, v, n) : d;
}
static inline double ism_sample_dist_between(ism_sampler *s, const double p[3],
                                             const double *const *v, int n)
{
    double g[3];
    double f = ism_sample_grad(s, p, g);
    return ism_dist_beyond(s, p, ism_plain_dist(s, p, f, g, s->dist_above), v, n);
}

/* The largest distance (ism_sample_dist_between) at the centroids and edge midpoints of out's
 * triangles from first_tri on: +inf when one of them has no estimate (∇f vanishing where f
 * is not 0, or f not finite), so that leaf is split again. The measuring stops at the first
 * point beyond bound (its distance is returned): whether the triangles meet bound is the
 * same; INFINITY measures them all. */
double ism_emitted_error(ism_sampler *s, const ism_cell_out *out, size_t first_tri,
                         double bound);
/* The same, and with bound INFINITY each triangle's centroid gradient (the measuring's own)
 * into centroid_g[t - first_tri] (out->ntris - first_tri rows; NULL: none kept), for
 * ism_crease_unresolved's turned test. */
double ism_emitted_error_kept(ism_sampler *s, const ism_cell_out *out, size_t first_tri,
                              double bound, double (*centroid_g)[3]);

/* A node's identity across rounds (its level and lattice origin). */
uint64_t ism_node_key(const ism_node *nd);

/* Nodes to split whatever the flatness test says: keys sorted ascending. */
typedef struct ism_split_set {
    uint64_t *keys;
    size_t n, cap;
} ism_split_set;

bool ism_split_set_add(ism_split_set *s, uint64_t key);
void ism_split_set_sort(ism_split_set *s);          /* after adding, before lookups */
bool ism_split_set_has(const ism_split_set *s, uint64_t key);
void ism_split_set_free(ism_split_set *s);

#endif
