/* arrangement.h — the arrangement that curves cut on a meshed surface, like a doubly-connected
 * edge list: vertices (curve crossings, branch points, curve ends at the box, curves meeting
 * a double curve or a singular point of the locus, one point on each closed curve that meets
 * nothing), edges (curve arcs between them, each a chain of mesh vertices),
 * faces (the cells: triangles connected across mesh edges that lie on no curve) with area
 * and Euler characteristic, and curves (connected arcs of one cutting function). */
#ifndef ISM_ARRANGEMENT_H
#define ISM_ARRANGEMENT_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>
#include "core/curves/arr_types.h"
#include "core/curves/cut.h"
#include "core/mesh/mesh.h"
#include "core/singular/locus.h"

/* Builds the arrangement of the cut edges c on m, reordering m's triangles so each face's
 * triangles are contiguous (in order of each face's first triangle; order inside a face
 * kept; c's tri_parent, when set, reordered with them). A curve vertex within on_tol of a
 * point of locus (NULL: none) is typed ISM_ARR_SINGULAR_POINT, one where a curve crosses a
 * mesh edge of three or more triangles (a double curve) ISM_ARR_DOUBLE_CURVE; curves end
 * there. a is overwritten. False when out of memory. */
bool ism_arrangement_build(ism_mesh *m, ism_cut *c, const ism_locus *locus, double on_tol,
                           ism_arrangement *a);

void ism_arrangement_free(ism_arrangement *a);

#endif
