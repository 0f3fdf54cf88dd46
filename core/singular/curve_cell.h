/* curve_cell.h — the cell a double curve asks for: the size of the octree's cells (and of the
 * conformance pass's tube, in those cells) along a certified double curve, from the curve's
 * own extent rather than the depth's lattice. At a coarse depth the tube round a curve
 * started at 2.5 cells of the depth — about the surface's size (Steiner's half-axes are 0.5
 * long, depth 3 in ±1 has cells of 0.25) — and swallowed the sheets or fitted with the wrong
 * topology; split along the curve first ("protect the features, then mesh"), the tube is
 * sized by the local cell. */
#ifndef ISM_CURVE_CELL_H
#define ISM_CURVE_CELL_H

#include <stddef.h>
#include "core/singular/locus.h"

/* The cell double curve cu asks for: the first of finest / 2^k (the octree's cells below the
 * depth's cell `finest`) no larger than its span (the farthest of its points from its first:
 * an open curve's length when straight, a closed one's diameter) / ISM_CURVE_CELLS, times
 * tan_phi / ISM_CURVE_FULL_TAN when its sheets cross at an angle φ that shallow
 * (crossing_angle.h; NAN: not measured), at most ISM_CURVE_MAX_HALVINGS halvings. Whiskers
 * and curves of fewer than 2 points ask for `finest`. */
double ism_curve_cell(const ism_sing_curve *cu, double finest, double tan_phi);

/* The cell the mesh along curve cu has: its split_cell where the octree split its nodes
 * (ism_sing_curve), else `finest`. The conformance tube and the quiet balls are sized by it:
 * sized by the cell the curve asks for on a mesh that was not split there, the tube is too
 * narrow for the depth's triangles. */
double ism_curve_mesh_cell(const ism_sing_curve *cu, double finest);

/* The smallest ism_curve_mesh_cell of the curves ending at point i (`finest` when none). */
double ism_point_curve_cell(const ism_locus *l, size_t i, double finest);

/* Cells across a double curve's span: at depths whose cells are this fine the conformance
 * tube (2.5 cells, widened ×1.4 until its rim is clear) fits each sheet beside the curve.
 * Measured on the sweep's three boxes: Steiner's half-axes (span 0.5) fit from cells of
 * 0.0625 (depth 5 in ±1; depth 4, 0.125, gave χ −4 | −1 | −5 for 5), the cross-cap's segment
 * (span 1) from 0.15 (depth 4 in ±1.2; 0.3 gave χ 1 for 2 in the 0.37-cell box). */
#define ISM_CURVE_CELLS 8.0
/* Sheets crossing at an angle φ stay within the tube's clearance (CF_CLEAR_CELLS 1.5 cells,
 * × ANGLE_MARGIN 1.1) out to 1.65 / tan φ cells of the curve; below tan φ = 1.65 /
 * CF_RHO_CELLS (2.5, the tube's first radius) = 0.66 (33°) the tube must widen by
 * 0.66 / tan φ, and the cell shrinks by as much so that the tube keeps its size next to the
 * curve's span. Two unit spheres with centres 0.2 apart cross at 11.5° (tan 0.2): the tube
 * then spans 8 cells; at the span's cell (1.99 / 8) it was 1.8 wide, about the spheres' size,
 * and swallowed the crossing (χ −1 with 25 artefacts at depths 3–4, 2 without a non-manifold
 * edge at depth 5, for 4). */
#define ISM_CURVE_FULL_TAN 0.66
/* Halvings below the depth's cell at most: the lattice holds ISM_THIN_EXTRA_DEPTH (8) levels
 * below depth.max, and a curve that asks for more is tiny next to the box. */
#define ISM_CURVE_MAX_HALVINGS 8

#endif
