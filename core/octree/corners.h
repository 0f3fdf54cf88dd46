/* corners.h — a node's 8 corners with f and ∇f there, and how its 12 edges and 6 faces are
 * numbered (corners.c). Shared by the flatness test and the error measure of a node. */
#ifndef ISM_CORNERS_H
#define ISM_CORNERS_H

#include <stdint.h>

struct ism_node_memo;

/* f and ∇f at a node's 8 corners (corner c: bit 0 = x, bit 1 = y, bit 2 = z), the corners'
 * lattice keys (grid.h's ism_lattice_key) and the thread's memo of what the flatness test
 * finds at lattice points and on lattice edges (cell_cache.h's ism_node_memo; NULL: none,
 * keys unused). */
typedef struct ism_corners {
    double p[8][3], f[8], g[8][3];
    uint64_t key[8];
    const struct ism_node_memo *memo;
} ism_corners;

/* Edge e (0..11) of a node: its corners c0 -> c1 (c1 one step along axis e / 4) and the two
 * faces it lies on (face = axis * 2 + side). */
void ism_cube_edge(int e, int *c0, int *c1, int faces[2]);

#endif
