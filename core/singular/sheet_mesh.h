/* sheet_mesh.h — the triangles of a double sheet inside the lattice cells that hold it:
 * marching tetrahedra on ψ (sheet_field.h) over each cell's six Kuhn tetrahedra, every
 * crossing of ψ on a lattice edge (or at a lattice vertex where ψ = 0) moved onto the sheet
 * by sheet_project.h. A crossing belongs to its edge, so neighbouring cells share it and the
 * surface has no cracks; a cell emits its triangles only when every one of its crossings
 * landed on f = 0. Triangles face the side where ψ > 0. */
#ifndef ISM_SHEET_MESH_H
#define ISM_SHEET_MESH_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>
#include "core/singular/sheet_field.h"

typedef struct ism_sheet_crossing {
    double p[3];      /* on the sheet when ok */
    float n[3];       /* the Hessian's direction there, oriented like the edge's vertex */
    uint32_t a, b;    /* lattice vertices of the edge, a == b for a crossing at a vertex */
    bool ok;          /* projected onto f = 0 */
} ism_sheet_crossing;

typedef struct ism_sheet_tris {
    ism_key_map xmap;          /* edge key -> crossing index */
    ism_sheet_crossing *x;
    size_t cap_x;
    uint32_t *tri;             /* 3 crossing indices per triangle */
    size_t ntris, cap_tris;
    uint64_t cells_meshed, cells_refused, crossings_refused;
} ism_sheet_tris;

void ism_sheet_tris_init(ism_sheet_tris *t);
void ism_sheet_tris_free(ism_sheet_tris *t);

/* Cells that may hold a sheet, each as its 8 corner vertex indices (corner c at offset
 * (c & 1, c >> 1 & 1, c >> 2 & 1)), all oriented (ISM_SF_ORIENTED). cell is the finest
 * cell's diagonal. Appends their triangles to t; when emitted is not NULL, sets emitted[i]
 * to 1 for each cell that gave triangles (0 for the others). False when out of memory. */
bool ism_sheet_mesh_cells(const ism_sheet_field *sf, const uint32_t (*corners)[8], size_t n,
                          double cell, ism_sheet_tris *t, uint8_t *emitted);

#endif
