/* breaks.h — where lattice lines are cut by the corners of the plotting-candidate leaves.
 * A node's edge is processed as the sequence of the smallest segments that any leaf sharing
 * that line uses there, so every node touching an edge finds the same roots on it, bit for
 * bit, however coarse or fine each node is: the mechanism behind crack-free output. */
#ifndef ISM_BREAKS_H
#define ISM_BREAKS_H

#include <stddef.h>
#include <stdint.h>
#include <stdbool.h>
#include "core/octree/octree.h"

typedef struct ism_breaks {
    uint64_t *keys;  /* sorted, unique: line (axis and the two other coordinates) + position */
    size_t n;
    uint32_t *line_first; /* open-addressing table: line -> index of its first key (+1) */
    size_t line_mask;
    int cbits;            /* bits per lattice coordinate in a key */
} ism_breaks;

/* Collects the corners of every non-empty leaf on the three lattice lines through them. */
bool ism_breaks_build(ism_breaks *b, const ism_octree *t);
void ism_breaks_free(ism_breaks *b);

/* A growable list of lattice coordinates. */
typedef struct ism_coords {
    int32_t *v;
    size_t n, cap;
} ism_coords;

/* Replaces out with the break points on the lattice line along `axis` through point p
 * (p[axis] is ignored) that lie in [lo, hi], ascending; lo and hi are always included. */
bool ism_breaks_on(const ism_breaks *b, int axis, const int32_t p[3], int32_t lo, int32_t hi,
                   ism_coords *out);

void ism_coords_free(ism_coords *c);

#endif
