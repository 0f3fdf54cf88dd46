/* remesh.h — the quality pass (issue 15 item 4): better-shaped triangles on the same surface,
 * the mesh saying the same things. Within each manifold patch it flips edges toward Delaunay
 * (Lawson) and relaxes vertices in the tangent plane (towards the area-weighted centroid of
 * their triangles), putting every moved vertex back on f = 0 by Newton along ∇f. Protected,
 * never flipped or moved: boundary and non-manifold edges, edges between differently
 * labelled triangles or given as locked (curves), crease edges (a sharp dihedral that is no
 * fold), vertices on any of them, vertices where several cones meet, where ∇f vanishes, and
 * the vertex at each given point (singular points). Needles and caps that flips and moves
 * cannot mend lose an edge by collapse (a free vertex merged into a neighbour, where the
 * link condition holds: the topology is kept; a locked vertex only along a crease or a curve
 * of zeros of ∇f, into a crowding neighbour: rm_collapse.c), and the mesh is renumbered
 * after; thin tubes ending at a given point (the horn cyclide's horns), where needles lie on
 * them, are merged into the point's vertex tip first (rm_horn.c); each triangle keeps its
 * label, features keep their vertices, so χ, components,
 * non-manifold edges and points and boundary loops cannot change. */
#ifndef ISM_REMESH_H
#define ISM_REMESH_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>
#include "core/expr/expr.h"
#include "core/mesh/mesh.h"
#include "core/remesh/remesh_types.h"

/* Frees ren's maps and zeroes it (a zeroed one may be freed again). */
void ism_remesh_renumber_free(ism_remesh_renumber *ren);

/* Runs the pass on m in place: positions, normals and the triangles' corners change, and
 * collapses remove vertices and triangles (the segments are renumbered with them); ren (may
 * be NULL) gets the renumbering. False with err set when out of memory or f is missing; m is
 * then still a valid mesh of the surface (possibly partly improved), and ren says how it was
 * renumbered. */
bool ism_remesh_quality(ism_mesh *m, const ism_remesh_options *o, ism_remesh_stats *st,
                        ism_remesh_renumber *ren, ism_error *err);

/* The smallest angle (degrees) over m's non-degenerate triangles; 90 for none. */
double ism_remesh_min_angle(const ism_mesh *m);

#endif
