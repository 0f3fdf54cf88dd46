/* dual_sides.h — the dual mesher's last round mended by cutting sides, not leaves: where
 * every miss of a round is a side a few E off, the sides are cut instead of a round of split
 * leaves (a sphere-like surface's last round was often a whole level of leaves split for a
 * few chords a hair too long). */
#ifndef ISM_DUAL_SIDES_H
#define ISM_DUAL_SIDES_H

#include <stdbool.h>
#include <stdint.h>
#include "core/octree/dual_tree.h"

/* The round's misses (miss: ism_dual_measure_triangles' masks of every triangle) mended
 * without splitting a leaf, where they are all near sides (missed_sides): each side's two
 * triangles cut in two at a vertex on the side's midpoint's foot (side_vertices), the new
 * triangles measured like any. True when every one meets E (then they stand in the mesh for
 * the missed ones, and the round is the last: nothing to mark); false otherwise, the
 * triangles as they were: the new vertices stay unused (dual.c's to_mesh drops them) and
 * kept in d->sides for a retry of the same side, the halves that passed keep their keys in
 * d->passed (read again only by a retry's halves, over the same vertices: the same answer).
 * Not when the halves would take the triangles past max_triangles (the round's leaves split
 * instead, and the next round's count stops the mesher), nor with a crease, the grown box's
 * clip or isolated points' balls, whose own passes read the round's triangles. Out of memory
 * for its own buffers it falls back silently (false, d->nomem unset: the round marks the
 * missed triangles' leaves as without it); the measure running out sets d->nomem as
 * everywhere else. */
bool ism_dual_split_sides(dual *d, const uint8_t *miss);

#endif
