/* breaks_near.h — which leaves a later max_error round registers: those near the leaves it
 * polygonises again, so that the smaller break-point registry (breaks.h) answers their
 * queries as the whole tree's would. */
#ifndef ISM_BREAKS_NEAR_H
#define ISM_BREAKS_NEAR_H

#include <stddef.h>
#include <stdint.h>
#include <stdbool.h>
#include "core/octree/octree.h"

/* The leaves whose corners the queries of the leaves to polygonise can see, into take (one
 * per node; leaves[k] is leaf k's node, polygonised unless reuse[k] >= 0): a superset of
 * those whose closed box touches a polygonised leaf's. A leaf's queries walk the sides of the
 * tiles on its faces, which lie in its closed box and begin at a corner of a leaf having
 * that side as an edge (face_lines.c tile_side); every registered point inside that box is
 * a corner of a leaf touching it, and a successor at or past a side's end ends the walk
 * whichever it is. So a registry of these leaves answers those queries as the whole tree's
 * does. False when out of memory. */
bool ism_breaks_near(const ism_octree *t, const int32_t *leaves, size_t nleaves,
                     const int32_t *reuse, uint8_t *take);

#endif
