/* cell.h — the polygonisation of one plotting node (cell.c): its per-thread context
 * (cell_ctx.h) and what it emits (cell_types.h). The top of core/octree's cell steps: cell.c
 * includes face_lines.h, singular.h, stitch.h and triangulate.h, and none of them includes
 * this. */
#ifndef ISM_CELL_H
#define ISM_CELL_H

#include <stddef.h>
#include <stdint.h>
#include <stdbool.h>
#include "core/octree/cell_ctx.h"
#include "core/octree/cell_types.h"

/* Releases the context's scratch arrays (not the sampler, octree or breaks it points to;
 * the memo is released separately with ism_cell_cache_free). */
void ism_cell_ctx_free(ism_cell_ctx *cx);

/* Polygonises leaf `node`: face lines of all its tiles, stitched into polygons,
 * triangulated into out. False only when out of memory. */
bool ism_cell_polygonise(ism_cell_ctx *cx, int32_t node, ism_cell_out *out);

/* Releases what a node emitted and empties o. */
void ism_cell_out_free(ism_cell_out *o);

#endif
