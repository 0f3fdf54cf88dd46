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
/* d (p's first-order estimate) lowered by ism_dist_capped when it is finite and beyond
 * dist_above; d itself otherwise. */
static inline double ism_dist_beyond(ism_sampler *s, const double p[3], double d,
                                     const double *const *v, int n)
{
    return d > s->dist_above && isfinite(d) ? ism_dist_capped(s, p, d, v, n) : d;
}
static inline double ism_sample_dist_between(ism_sampler *s, const double p[3],
                                             const double *const *v, int n)
{
    return ism_dist_beyond(s, p, ism_sample_dist(s, p), v, n);
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
