/* sheet_groups.h — one normal per half-sheet at a vertex on the singular locus (issue 13).
 * ism_wire_corner_normals gives each corner at a locus vertex (a double curve's, a node's, a
 * pinch or triple point's: ∇f = 0 there) its own triangle's sheet normal; sent as it is,
 * every such corner becomes a point of its own in drc/glb (+4–17.5% Draco bytes on the locus
 * presets). The triangles round such a vertex fall into half-sheets: the fan of one sheet on
 * one side of the curve (the two sides of a sheet across a double curve are two: the
 * viewer shades each side by its own normal), a node's nappe, a pinch point's fan. Corners of
 * one half-sheet share one normal, the normalised sum of their triangles' sheet normals, so
 * they share one point. */
#ifndef ISM_SHEET_GROUPS_H
#define ISM_SHEET_GROUPS_H

#include <stdbool.h>
#include <stdint.h>
#include "core/mesh/mesh.h"

/* A shared normal stays within this angle (radians) of every member's own sheet normal: the
 * corners' normals are interpolated over their triangles, and tests/cli/
 * test_double_curve_normals.py counts a corner as a tooth beyond 30° from its face; 20°
 * keeps 10° for the sheet normal's own distance from the face's (the chord against the
 * tangent plane: below 10° at the default bound on Steiner's curves). A half-sheet that
 * bends more (a cone's nappe, the fan round a pinch point) is cut into fans that each meet
 * it, so a cone's tip is not rounded into one average. */
#define ISM_SHEET_GROUP_MAX_ANGLE (20.0 * 3.14159265358979323846 / 180.0)

/* cn: 3 floats per corner of m (3 t + k), unit; mark: per corner, 1 where cn is the corner's
 * own triangle's sheet normal at a locus vertex. The marked corners at each vertex are
 * joined across the mesh edges they share whose other end carries no mark (an edge off the
 * locus, within one sheet), while the joined set's normalised sum of normals stays within
 * ISM_SHEET_GROUP_MAX_ANGLE of each member's (closest pairs first); every set of two or more
 * then gets that sum, bit for bit the same float triple. Unmarked corners are untouched.
 * False when out of memory (cn then unchanged). */
bool ism_sheet_groups_join(const ism_mesh *m, const uint8_t *mark, float *cn);

#endif
