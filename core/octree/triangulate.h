/* triangulate.h — a stitched polygon into triangles whose normals agree with ∇f, and the
 * growable per-node output (surface points, triangles, one-edge polygons) they go into. */
#ifndef ISM_TRIANGULATE_H
#define ISM_TRIANGULATE_H

#include <stddef.h>
#include <stdbool.h>
#include "core/octree/cell_types.h"
#include "core/octree/sampler.h"

/* Triangulates the closed polygon pts[0..n) (n >= 3) into out. reach bounds how far the
 * polygon's centre may move when projected onto the surface; node (lo xyz, hi xyz; NULL for
 * no bound) is the box the projected centre must stay in, and no triangle lies in one of
 * its faces unless the polygon leaves no other choice (face_flat.h: the node across that
 * face could emit the same triangle). max_error > 0: a polygon of five or more corners is
 * fanned from a corner, without a centre, when that fan's centroids and diagonals' middles
 * lie within max_error of f = 0 (0: always from the centre). */
bool ism_triangulate_loop(ism_sampler *s, const ism_fpoint *pts, size_t n, double reach,
                          const double node[6], double max_error, ism_cell_out *out);

/* Is the closed polygon pts[0..n) wound against ∇f (ism_triangulate_loop reverses it)? Its
 * Newell normal against the mean unit gradient at its points, or, where those split the vote
 * and node is given, against the node's corners' signs. */
bool ism_loop_reversed(ism_sampler *s, const double node[6], const ism_fpoint *pts, size_t n);

/* ism_triangulate_loop with the winding decided by the caller: pts taken in reverse order
 * when flip. */
bool ism_triangulate_wound(ism_sampler *s, const ism_fpoint *pts, size_t n, double reach,
                           const double node[6], double max_error, bool flip, ism_cell_out *out);

/* Newell's normal of the closed polygon p[0..n) into nrm: twice its vector area, the
 * polygon running counterclockwise round it (its inside on the left of each edge seen from
 * the normal's tip). */
void ism_newell(const ism_fpoint *p, size_t n, double nrm[3]);

/* Triangulates the closed polygon pts[0..n) (n >= 2) as a fan around apex, a point inside
 * the node where the polygon's sheet meets other sheets. */
bool ism_triangulate_fan(const ism_fpoint *pts, size_t n, const ism_fpoint *apex,
                         ism_cell_out *out);

/* Triangulates the closed polygon pts[0..n) (n >= 3), lying in a face of its node, as a
 * fan around apex, a point of f = 0 off that face (face_flat.h: a tent over the polygon),
 * wound so that the fan's triangles agree with ∇f. */
bool ism_triangulate_tent(const ism_fpoint *pts, size_t n, const ism_fpoint *apex,
                          ism_cell_out *out);

/* Appends a point (its index in *idx) or a triangle of point indices; false when out of
 * memory. */
bool ism_cell_out_vert(ism_cell_out *o, const ism_fpoint *p, uint32_t *idx);
bool ism_cell_out_tri(ism_cell_out *o, uint32_t a, uint32_t b, uint32_t c);

/* Appends a one-edge (degenerate) polygon. */
bool ism_cell_out_segment(ism_cell_out *out, const ism_fpoint *a, const ism_fpoint *b);

#endif
