/* weld.h — joins the per-node outputs into one indexed mesh. A surface point shared by
 * several nodes was computed bit-identically by each of them, so welding is an exact match
 * on position; a point's index is given by its first occurrence in piece order, so the mesh
 * never depends on how many threads made the pieces or weld them. */
#ifndef ISM_WELD_H
#define ISM_WELD_H

#include "core/mesh/mesh.h"
#include <stddef.h>
#include <stdint.h>
#include <stdbool.h>
#include "core/octree/cell_types.h"
#include "core/util/parallel.h"

typedef struct ism_weld_stats {
    uint64_t zero_vertices, touch_vertices, pair_vertices, many_vertices;
    uint64_t dropped_triangles;  /* triangles that collapsed to an edge when welded */
} ism_weld_stats;

/* Appends the pieces, in order, to mesh (which must be empty), working on the threads of
 * pool (NULL: the calling thread alone; what their loops cost is added to *cost when not
 * NULL); the mesh is the same byte for byte for any thread count. False when out of memory or when the pieces hold 2^30
 * vertices or more. */
bool ism_weld(const ism_cell_out *pieces, size_t npieces, ism_pool *pool, ism_mesh *mesh,
              ism_weld_stats *st, ism_par_cost *cost);

#endif
