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

/* A leaf among those ism_emitted_errors measures together: its triangles out->tris[3 t0 ..
 * 3 t1), the sampler's leaf while it was polygonised; and what was measured: err (what
 * ism_emitted_error_kept gives under INFINITY) and its triangles' centroid gradients, rows
 * cg0 .. cg0 + t1 - t0 of the scratch's cg. */
typedef struct ism_leaf_span {
    size_t t0, t1;
    ism_sampler_leaf leaf;
    size_t cg0;
    double err;
    size_t p0, p1; /* its points in the scratch (ism_emitted_errors' own) */
} ism_leaf_span;

/* ism_emitted_errors' arrays, kept between calls (ism_measure_scratch_free); zeroed: none. */
typedef struct ism_measure_scratch {
    struct ism_measured *m;
    double (*p)[3], (*g)[3], (*x)[3], (*gx)[3], (*cg)[3], *f, *fx, *plain;
    const ism_tape **tape;
    size_t *step;
    size_t cap;
} ism_measure_scratch;

/* ism_emitted_error_kept(s, out viewed up to leaf[k].t1, leaf[k].t0, INFINITY, its rows of
 * w->cg) of every leaf k < n into leaf[k].err: the same figures bit for bit, the points of
 * all n leaves evaluated together (ism_sample_grad_tapes: each on its own leaf's tape, fuller
 * passes of the batched evaluator than one leaf's ~9 points make). The sampler's leaf is
 * left as the last one's. False when out of memory. */
bool ism_emitted_errors(ism_sampler *s, const ism_cell_out *out, ism_leaf_span *leaf,
                        size_t n, ism_measure_scratch *w);
void ism_measure_scratch_free(ism_measure_scratch *w);

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
