/* crease_snap.h — before the crease is cut, a vertex lying a small fraction of an edge from
 * the crease is moved onto it, so the cut does not split its edges there into slivers (whose
 * flat normals and orientation are noise: at depth 7 the gyroid ball's crease had triangles
 * with angles of 0.01° beside it, their flat normals 30–40° off their branch's). */
#ifndef ISM_CREASE_SNAP_H
#define ISM_CREASE_SNAP_H

#include <stddef.h>
#include <stdint.h>
#include "core/curves/cut_internal.h"

/* Each vertex v of s->m on branch label[v] (branches b) whose neighbours take one other
 * branch B, whose star is a closed fan and which lies within CREASE_SNAP_FRACTION of its
 * shortest edge of the crease point Newton finds from it, is put there when none of its
 * triangles turns over; its label becomes ISM_BRANCH_NONE (a vertex on the crease, cut as a
 * tie) and its normal ∇f there. *moved counts them. False when out of memory. */
bool cut_crease_snap(cut_state *s, ism_branches *b, uint32_t *label, size_t *moved);

#endif
