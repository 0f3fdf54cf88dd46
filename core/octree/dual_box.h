/* dual_box.h — the dual mesh (dual.h) of a surface that the request's box cuts: the mesh is
 * made in a slightly larger box and clipped by the six planes of the given one.
 *
 *      grown box (the lattice the dual mesher builds)
 *     +-------------------------------------------+
 *     | margin: over a cell of level ISM_DUAL_BOX_LEVEL; surface leaves touching the grown
 *     |  +-------------------------------------+  |  box are no larger than such a cell,
 *     |  | the given box                       |  |  so they and their vertices lie beyond
 *  ~~~~~~~~x                                   |  |  the given box: the mesh's own open
 *     |  |  \                                  |  |  edges (no quad across the grown box's
 *     |  |   \  dual mesh, closed and within E |  |  faces) lie outside the given box
 *     |  |    \ inside the given box           |  |
 *     |  +-----x-------------------------------+  |  x: a cut point, on the face plane AND on
 *     |         \                                 |     f = 0 (Newton in the plane; on a box
 *     +-------------------------------------------+     edge, along the edge's line)
 *
 * Every triangle is clipped plane after plane (Sutherland-Hodgman): kept when inside, dropped
 * when outside, cut where it crosses; a cut point starts where the triangle's edge crosses the
 * plane and is moved onto f = 0 by Newton with the coordinates of every plane it lies on held
 * (its edge's ends' common planes and this one), so two triangles sharing an edge share its
 * cut point, the new edges along a face lie in its plane, and a point where two planes cut
 * lies on the box's edge. The edges in the box's faces are then the mesh's boundary loops:
 * f = 0 ∩ the faces (the tests count them from f's signs on the faces). The cut triangles
 * are measured as the dual mesh's own (centroid and edge midpoints within E, facing along
 * ∇f); the dual mesher clips each round's mesh so, splits the leaves of every triangle with
 * a piece beyond E and makes the mesh again, as for its own misses (dual_measure.c). A cut point
 * Newton cannot settle, or a dual vertex of a margin leaf inside the given box, declines
 * (the caller polygonises as before). */
#ifndef ISM_DUAL_BOX_H
#define ISM_DUAL_BOX_H

#include <stdbool.h>
#include "core/mesh/mesh.h"
#include "core/octree/sampler.h"

/* The margin's level: the grown box reaches 1.15-1.39 cells of this level (of the grown box)
 * beyond the given one on every side, and surface leaves touching it are split to this
 * level at least (the default minimum depth 3 already does), so they lie 0.15-0.39 of such a
 * cell beyond the given box. Whole runs at 2e-3 of the box (callgrind instructions, raw
 * triangles; all dual, χ and loops the primal path's) for margin level / split level 4 / 5,
 * 4 / 4 and 3 / 3: hyperboloid 63.7M / 33.9M / 25.6M (1,328 / 1,171 / 992 triangles),
 * catenoid 81.8M / 63.0M / 67.9M, Scherk 136.5M / 86.1M / 94.8M, helicoid 66.0M / 40.8M /
 * 25.6M (1,416 / 1,303 / 775), Clebsch cubic 183.4M / 144.6M / 138.0M; level 2 (wider
 * margins) 30.7M, 92.0M, 186.5M, 45.4M, 185.5M. */
#define ISM_DUAL_BOX_LEVEL 3

/* Vertices are snapped onto a plane (and onto f = 0) before the cut when nearer it than
 * twice the farthest move of a cut point on their edges, and never farther than this share
 * of E (dual_box.c snap_to); the triangles with such a corner are measured with the cut
 * ones, and the dual mesher's probe takes every triangle with a corner this near a plane. */
#define ISM_DUAL_BOX_SNAP 1.0

/* The grown box of box: each axis widened on either side by 1.15-1.39 cells of level
 * `level` of the grown box (off any simple fraction of the given box: dual_box.c), so that a
 * leaf of that level touching the grown box lies beyond the given one. */
void ism_dual_box_grow(const double box[6], int level, double grown[6]);

/* The first look's lattice on the box's faces: 6 × 17² points (1,734 evaluations, taken
 * LOOK_CHUNK at a time in batches: dual_box.c), unless the faces' interval proof spares
 * them. */
#define ISM_DUAL_BOX_LOOK 4

/* Does f change sign (or vanish) among the points of box's faces on the lattice of level
 * `level`? A first look: true proves the box cuts the surface; false does not prove it
 * does not. First f's natural interval over tiles of the faces, down to that lattice's
 * cells, may show f free of 0 on them: then false without the points (the tiles counted
 * in s->n_interval, the points in s->n_point). */
bool ism_dual_box_seen_cut(ism_sampler *s, const double box[6], int level);

enum ism_box_clip_status {
    ISM_BOX_CLIP_OK = 0,
    ISM_BOX_CLIP_MISS,      /* a cut triangle beyond E or turned against ∇f */
    ISM_BOX_CLIP_BAD,       /* a cut point Newton could not put on f = 0 in its planes */
    ISM_BOX_CLIP_NO_MEMORY,
};

typedef struct ism_box_clip_stats {
    size_t cut;    /* triangles with a corner on a plane (made by the cuts) */
    size_t missed; /* of them, beyond E or turned against ∇f */
} ism_box_clip_stats;

/* m (a dual mesh of a larger box whose open edges all lie outside box) clipped by box's six
 * planes; the new triangles measured against max_error with s. Unused vertices dropped.
 * miss (NULL, or m->ntris entries on entry): 1 for each triangle of m a piece of which
 * misses E (the dual mesher splits its leaves and clips again). On anything but OK and MISS,
 * m is left in an unspecified state. A cut point depends on its edge's two end points only
 * (not on their numbering), a piece on its triangle's corners only. */
enum ism_box_clip_status ism_dual_box_clip(ism_mesh *m, ism_sampler *s, const double box[6],
                                           double max_error, uint8_t *miss,
                                           ism_box_clip_stats *st);

#endif
