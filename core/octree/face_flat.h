/* face_flat.h — polygons and triangles that lie in one of a node's faces. The node across
 * that face sees the same lines there and would emit the same polygon: a surface piece
 * thinner than the nodes (a tube centred on the lattice plane) would come out as a flat,
 * doubly covered ribbon. Such a polygon is lifted instead: each node fans it from the
 * surface point found above its centroid on its own side, so the two nodes' fans close the
 * tube between them; and no node triangulates a polygon into a triangle lying in a face.
 *
 *        node above            the polygon a—b lies in the face; each node fans it
 *      ┌──────────┐            from the point of f = 0 straight above (below) its
 *      │   ╭─t─╮  │            centroid on its own side: t above, t' below. Without
 *      ├──a──────b┤  face      it both nodes emit the flat a—b polygon (two copies,
 *      │   ╰─t'╯  │            every edge non-manifold).
 *      └──────────┘
 *        node below                                                                  */
#ifndef ISM_FACE_FLAT_H
#define ISM_FACE_FLAT_H

#include <stdbool.h>
#include <stddef.h>
#include "core/octree/cell_types.h"
#include "core/octree/sampler.h"

/* The face (2 × axis + side, side 1 = the upper face) of the node box (lo xyz, hi xyz)
 * whose plane holds every point of p[0..n), or -1. */
int ism_face_plane(const double node[6], const ism_fpoint *p, size_t n);

/* The faces of the node box whose planes hold p[i], into mask[i] (i < n): bit `face` set
 * for each. Points lie in the plane of one face together when their masks share a bit. */
void ism_face_masks(const double node[6], const ism_fpoint *p, size_t n, uint8_t *mask);

/* The point of f = 0 on the segment from the centroid of p[0..n) (all in face `face`)
 * straight into the node, up to its far side: the first sign change of f along it, by
 * samples and regula falsi. False when f keeps its sign there (nothing of the surface
 * bulges into this node above the polygon). */
bool ism_lift_point(ism_sampler *s, const ism_fpoint *p, size_t n, const double node[6],
                    int face, ism_fpoint *top);

/* A face line a—b whose ends lie on one side of its tile, a chord along the tile's edge
 * (p[axis] equal for both): the tile on the edge's other side may hold the same chord for
 * another arc of the surface (a tube cut by the lattice plane: its upper and lower arcs both
 * end at the two roots of one edge). The arc's point of f = 0 on the way from the chord's
 * middle across the tile along `axis` to the coordinate `to` (the tile's other side): the
 * line becomes a—mid—b. Depends only on the tile, so both nodes sharing it agree. */
bool ism_lift_chord(ism_sampler *s, const ism_fpoint *a, const ism_fpoint *b, int axis,
                    double to, ism_fpoint *mid);

#endif
