/* corner_split.h — splits a mesh's vertices where a per-triangle label changes (the
 * arrangement's cell id, the double-sheet flag) or a corner's normal is not its vertex's (a
 * crease side), so that labels and normals can travel as per-vertex attributes in formats
 * that reorder triangles (Draco, glb): each point is one vertex seen from triangles of one
 * label pair and one normal, and every triangle's three points carry its labels and its
 * corners' normals. The positions stay shared through point_vertex (Draco keeps the
 * connectivity and encodes the changes as seams). */
#ifndef ISM_CORNER_SPLIT_H
#define ISM_CORNER_SPLIT_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>
#include "proto/wire_mesh.h"

typedef struct ism_corner_split {
    size_t npoints;
    uint32_t *tri;           /* 3 per triangle: point indices */
    uint32_t *point_vertex;  /* per point: the mesh vertex it copies */
    uint32_t *point_cell;    /* per point: the cell of its triangles (NULL when no cells) */
    uint8_t *point_sheet;    /* per point: the sheet flag of its triangles (NULL when none) */
    float *point_normal;     /* 3 per point: its corners' normal (NULL when w has no corner
                                normals: then the vertex's) */
} ism_corner_split;

/* Whether w has anything that needs the split (labels, or corner normals sent). */
bool ism_corner_split_needed(const ism_wire_mesh *w);

/* Splits w's triangles by its labels tri_cell / tri_sheet and its corner normals (any may
 * be absent, not all). Points are numbered in order of first use; a vertex whose corners
 * all agree becomes one point. O(corners × points of a vertex). False when out of memory
 * or nothing to split by (out is then empty). */
bool ism_corner_split_build(const ism_wire_mesh *w, ism_corner_split *out);

void ism_corner_split_free(ism_corner_split *s);

#endif
