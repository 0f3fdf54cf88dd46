/* crease_micro.h — before the crease is snapped and cut, the polygoniser's micro clusters
 * beside it welded into one vertex: where the surface passes within a hair of a lattice
 * corner, the roots on the corner's edges are a few 1e-5 apart, their tiny triangles fix
 * each vertex's shortest edge (so the snap's reach) at that hair, and the crease passing
 * beside them is cut into slivers that neither the relaxation nor the refinement can mend
 * (the gyroid ball d7 0.37 cell off the lattice: a 0.11° sliver, its crease edge 2.45° off
 * the gradients' angle). */
#ifndef ISM_CREASE_MICRO_H
#define ISM_CREASE_MICRO_H

#include <stddef.h>
#include <stdint.h>
#include "core/curves/cut_internal.h"

/* Each set of vertices of one branch (label, ISM_BRANCH_NONE for ties) joined by edges
 * shorter than CREASE_MICRO_FRACTION of their ends' longest edge, one of them with a
 * neighbour of another branch, on no curve and no segment, becomes its lowest vertex: its
 * triangles renamed, those left with a repeated corner dropped (s->m->tri and s->parent
 * compacted), when the welded vertex's star is a closed fan of distinct triangles none of
 * which turns more than 60° from its own normal before. *welded counts the vertices gone. False when out of
 * memory. */
bool cut_crease_weld_micro(cut_state *s, const uint32_t *label, size_t *welded);

#endif
