/* refine.h — the a-posteriori half of the max_error bound: the distance to f = 0 of the
 * triangles a leaf really emitted (its polygons depend on its neighbours' tiles, which the
 * octree's estimate cannot see), and the set of nodes the next round of the octree must
 * split because their triangles were measured farther than the bound. */
#ifndef ISM_REFINE_H
#define ISM_REFINE_H

#include <stddef.h>
#include <stdint.h>
#include <stdbool.h>
#include "core/octree/cell_types.h"
#include "core/octree/octree.h"
#include "core/octree/sampler.h"

/* The largest distance (ism_sample_dist_between, sample_dist.h) at the centroids and edge
 * midpoints of out's triangles from first_tri on: +inf when one of them has no estimate (∇f
 * vanishing where f is not 0, or f not finite), so that leaf is split again. The measuring
 * stops at the first point beyond bound (its distance is returned): whether the triangles
 * meet bound is the same; INFINITY measures them all. */
double ism_emitted_error(ism_sampler *s, const ism_cell_out *out, size_t first_tri,
                         double bound);
/* The same, and with bound INFINITY each triangle's centroid gradient (the measuring's own)
 * into centroid_g[t - first_tri] (out->ntris - first_tri rows; NULL: none kept), for
 * ism_crease_unresolved's turned test. */
double ism_emitted_error_kept(ism_sampler *s, const ism_cell_out *out, size_t first_tri,
                              double bound, double (*centroid_g)[3]);

/* A node's identity across rounds (its level and lattice origin). */
uint64_t ism_node_key(const ism_node *nd);
/* The key's node: its lattice origin into org, its level returned. */
int ism_node_key_decode(uint64_t key, int32_t org[3]);

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
