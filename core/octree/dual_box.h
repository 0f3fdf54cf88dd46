/* dual_box.h — the dual mesh (dual.h) of a surface that the request's box cuts: the mesh is
 * made in a slightly larger box and clipped by the six planes of the given one.
 *
 *      grown box (the lattice the dual mesher builds)
 *     +-------------------------------------------+
 *     | margin: one cell of level ISM_DUAL_BOX_LEVEL; surface leaves touching the grown box
 *     |  +-------------------------------------+  |  are split below that level, so they
 *     |  | the given box (its faces on lattice |  |  and their vertices lie in the margin's
 *  ~~~~~~~~x planes of the grown box)          |  |  outer half: the dual mesh's own open
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
 * a piece beyond E and makes the mesh again, as for its own misses (dual.c). A cut point
 * Newton cannot settle, or a dual vertex of a margin leaf inside the given box, declines
 * (the caller polygonises as before). */
#ifndef ISM_DUAL_BOX_H
#define ISM_DUAL_BOX_H

#include <stdbool.h>
#include "core/mesh/mesh.h"
#include "core/octree/sampler.h"

/* The margin's level: the given box lies one cell of this level inside the grown box on
 * every side (a ±3 box grows to ±3.43). Surface leaves touching the grown box are split to
 * the next level at least. Kummer-16 (±3) at E 1e-2 keeps leaves of levels 4-6 near its
 * faces: a coarser margin would force nothing, and meshes up to 14% more of the funnels'
 * surface beyond the faces. */
#define ISM_DUAL_BOX_LEVEL 4

/* Vertices nearer a plane than this share of E are settled onto it and onto f = 0 before
 * the cut: a cut point moves up to about E off its chord onto f = 0, so a corner nearer
 * than that is what turns a sliver over (a sphere of radius 0.09 poking through a face at
 * E 2e-3: 6 of 48 cut triangles turned without). The triangles with such a corner are
 * measured with the cut ones. */
#define ISM_DUAL_BOX_SNAP 1.0

/* The grown box of box: each axis widened so that box's faces are the lattice planes 1 and
 * 2^level - 1 of level `level`. */
void ism_dual_box_grow(const double box[6], int level, double grown[6]);

/* Does f change sign (or vanish) among the points of box's faces on the lattice of level
 * `level`? A first look: true proves the box cuts the surface; false does not prove it
 * does not. */
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
