/* conform.h — makes the polygoniser's mesh conform to a singular locus found from f: every
 * sheet-carrying singular point (node, cusp, degenerate contact) becomes one mesh vertex at
 * its certified position shared by all its cones, and every double curve a chain of mesh
 * edges on the curve's polyline with the crossing sheets' triangles on it (four per edge).
 *
 * Method: surgery. The triangles within a ball (point) or tube (curve) of a few cells around
 * the locus are removed, the hole's boundary edges chained into loops (one per cone or sheet
 * side), and each loop refilled: fanned to the point, or zipped to the curve's vertices, with
 * rings of intermediate vertices projected onto f = 0 so the new triangles are as close to
 * the surface as the polygoniser's. */
#ifndef ISM_CONFORM_H
#define ISM_CONFORM_H

#include <stddef.h>
#include <stdbool.h>
#include "core/expr/expr.h"
#include "core/mesh/mesh.h"
#include "core/singular/conform_stats.h"
#include "core/singular/locus.h"

/* Makes mesh conform to locus (o->box and o->max_depth give the finest cell, the scale of
 * the surgery; o->cancel, o->deadline_ms and o->conform_work_max are polled between items and
 * inside each, every ISM_CONFORM_POLL_WORK units of work at most: a surgery stopped in the
 * middle is undone, and the locus is marked incomplete). Sets each point's
 * `cones` (cones of faces at its vertex; 0 when it got none). The mesh stays welded and
 * consistently oriented per sheet; vertices that lost all their triangles are removed.
 * False only on bad input or allocation failure (err says which): the mesh is then still
 * valid and crack-free, the item being worked on when memory ran out left as it was. st may
 * be NULL. */
bool ism_conform_mesh(const ism_tape *f, const ism_locus_options *o, ism_locus *locus,
                      ism_mesh *mesh, ism_conform_stats *st, ism_error *err);

/* The radius of the smallest ball the pass cuts around a point (world units): every mesh
 * element within it is rebuilt whatever the polygoniser made there. */
double ism_conform_min_radius(const ism_locus_options *o);

#endif
