/* corner_split.h — splits a mesh's vertices where a per-triangle label changes (the
 * arrangement's cell id, the double-sheet flag), so that the label can travel as a
 * per-vertex attribute in formats that reorder triangles (Draco, glb): each point is one
 * vertex seen from triangles of one label pair, and every triangle's three points carry its
 * labels. The positions stay shared through point_vertex (Draco keeps the connectivity and
 * encodes the label changes as seams). */
#ifndef ISM_CORNER_SPLIT_H
#define ISM_CORNER_SPLIT_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

typedef struct ism_corner_split {
    size_t npoints;
    uint32_t *tri;           /* 3 per triangle: point indices */
    uint32_t *point_vertex;  /* per point: the mesh vertex it copies */
    uint32_t *point_cell;    /* per point: the cell of its triangles (NULL when no cells) */
    uint8_t *point_sheet;    /* per point: the sheet flag of its triangles (NULL when none) */
} ism_corner_split;

/* Splits tri (ntris triangles over nverts vertices) by the labels tri_cell and tri_sheet
 * (per triangle; either may be NULL, not both). Points are numbered in order of first use;
 * a vertex whose triangles all share labels becomes one point. O(corners × labels met at a
 * vertex). False when out of memory (out is then empty). */
bool ism_corner_split_build(const uint32_t *tri, size_t ntris, size_t nverts,
                            const uint32_t *tri_cell, const uint8_t *tri_sheet,
                            ism_corner_split *out);

void ism_corner_split_free(ism_corner_split *s);

#endif
