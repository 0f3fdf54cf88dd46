/* sheet_groups.h — one normal per half-sheet at a vertex on the singular locus (issue 13).
 * ism_wire_corner_normals gives each corner at a locus vertex (a double curve's, a node's, a
 * pinch or triple point's: ∇f = 0 there) its own triangle's sheet normal; sent as it is,
 * every such corner becomes a point of its own in drc/glb (+4–17.5% Draco bytes on the locus
 * presets). The triangles round such a vertex fall into half-sheets: the fan of one sheet on
 * one side of the curve (the two sides of a sheet across a double curve are two: ∇f, whose
 * sign orients the mesh, flips across the other sheet), a node's nappe, a pinch point's fan.
 * Corners of one half-sheet share one normal, the normalised sum of their triangles' sheet
 * normals, so they share one point; a nappe, which has no one normal at its tip, is cut
 * into narrow fans instead. */
#ifndef ISM_SHEET_GROUPS_H
#define ISM_SHEET_GROUPS_H

#include <stdbool.h>
#include <stdint.h>
#include "core/mesh/mesh.h"

/* A half-sheet is joined whole, one normal for all its corners at the vertex, when that
 * normal is within this angle (radians) of every member's own sheet normal: a sheet with a
 * tangent plane at the vertex (the sheets through a double curve, each side of it), whose
 * triangles' normals differ by the chords' sag only (Steiner at the default bound: within 4°
 * of their faces; at 1e-2 × diagonal up to ~6° between members, where the fan angle below
 * would cut 6 of 350 curve vertices' half-sheets); the corners' normals are interpolated
 * over their triangles, and tests/cli/test_double_curve_normals.py counts a corner as a
 * tooth beyond 30° from its face: 20° keeps 10° for the sheet normal's own distance from
 * the face's. */
#define ISM_SHEET_GROUP_MAX_ANGLE (20.0 * 3.14159265358979323846 / 180.0)

/* A half-sheet that one normal cannot serve (a node's nappe: a cone has no tangent plane at
 * its tip, each generator its own normal; a pinch point's fan) is cut into fans whose normal
 * is within this angle of each member's: at 20° the viewer drew a node's tip as a few
 * bright bands (fan normals up to 40° apart where fans meet), at 10° faint bands, at 5° the
 * same picture as one normal per triangle (kummer-16-nodes, zoomed to a node; a whole nappe
 * as one normal shades the tip dark and round). */
#define ISM_SHEET_FAN_MAX_ANGLE (5.0 * 3.14159265358979323846 / 180.0)

/* cn: 3 floats per corner of m (3 t + k), unit; mark: per corner, 1 where cn is the corner's
 * own triangle's sheet normal at a locus vertex. The marked corners at each vertex are
 * joined across the mesh edges they share whose other end carries no mark and that no other
 * marked triangle there has (an edge off the locus, within one sheet) into half-sheets; a
 * half-sheet that ISM_SHEET_GROUP_MAX_ANGLE allows is one set, any other is cut into fans
 * under ISM_SHEET_FAN_MAX_ANGLE (closest pairs first); every set of two or more then gets
 * its normalised sum of normals, bit for bit the same float triple. Unmarked corners are
 * untouched. False when out of memory (cn then unchanged). */
bool ism_sheet_groups_join(const ism_mesh *m, const uint8_t *mark, float *cn);

#endif
