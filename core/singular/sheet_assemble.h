/* sheet_assemble.h — turns the double-sheet triangles (on crossing indices) into mesh
 * triangles: one connected sheet after another, each a contiguous range with its area. */
#ifndef ISM_SHEET_ASSEMBLE_H
#define ISM_SHEET_ASSEMBLE_H

#include <stdbool.h>
#include "core/mesh/mesh.h"
#include "core/singular/locus.h"
#include "core/singular/sheet_mesh.h"
#include "core/singular/key_map.h"

/* Appends the used crossings as vertices and the triangles of t to mesh, grouped by
 * connected component (triangles sharing a vertex), in order of each component's first
 * triangle; records each component in io->sheets. Scraps — components with a boundary
 * and an area below min_area — are left out. False when out of memory. */
bool ism_sheet_assemble(const ism_sheet_tris *t, double min_area, ism_mesh *mesh,
                        ism_locus *io);

#endif
