/* polyline_thin.h — which vertices of a mesh polyline the features JSON prints when the
 * polyline only has to be drawn within a tolerance (the crease arcs: features.h's digits
 * table): Douglas-Peucker over the chain's own vertices, so every printed point is a vertex of
 * the chain and every dropped vertex lies within tol of the polyline through the kept ones. */
#ifndef ISM_POLYLINE_THIN_H
#define ISM_POLYLINE_THIN_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

/* The chain's n vertices are pos[3 idx[i] ..] (idx NULL: pos[3 i ..], a chain that is never
 * taken as closed). Sets keep[i] (n bytes) to 1 for the vertices
 * to keep, 0 for the others: the first and the last always (a closed chain, first == last,
 * keeps at least one more, the farthest from its first), and each dropped vertex i within
 * tol of the segment between the kept vertices on either side of it. Returns the number
 * kept; 0 when out of memory (keep then unset) or n is 0. tol <= 0 keeps every vertex. */
size_t ism_polyline_thin(const double *pos, const uint32_t *idx, size_t n, double tol,
                         uint8_t *keep);

#endif
