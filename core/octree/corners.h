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

/* Corner c where f is exactly 0 (a lattice point on the surface, its gradient not zero): the
 * faces (bit face) the surface enters there, those whose two edges at c lead to corners of
 * opposite signs (f ≈ ∇f · (q − c) near c: where both lead to one sign the face's quadrant
 * lies on that side and the surface only touches it at c), so 0 or 2 of them. A neighbour
 * also on f = 0 (the edge between lies in the surface, or is a chord of it) reads as on the
 * positive side, as if f were raised by an infinitesimal: of the nodes on both sides of a
 * lattice plane of the surface the negative one takes the plane's polygon, and a node the
 * surface only touches along an edge (the Whitney umbrella's fold line x = 0 on z = 0, from
 * below) has none. f: the 8 values. */
unsigned ism_zero_corner_faces(const double f[8], int c);

#endif
