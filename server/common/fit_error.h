/* fit_error.h — under an error bound, the max_error a mesh that stopped at the triangle
 * budget would fit with: the number a 422 too_big answer (daemon) and the CLI's message
 * suggest instead of a silently worse mesh. */
#ifndef ISM_SERVER_FIT_ERROR_H
#define ISM_SERVER_FIT_ERROR_H

#include "core/octree/polygonise.h"

#include <stdbool.h>

/* po: the options that stopped with ISM_POLY_TOO_BIG (po->max_error > 0, po->max_triangles
 * the budget, cancel/deadline honoured). preview: the pass was ism_polygonise alone, else
 * ism_mesh_surface. Returns an E, to three significant digits, that the same pass was seen to
 * mesh within the budget — or 0 when none was found (po->box's diagonal, the largest E a
 * request may ask, is still too big; cancelled; out of memory). */
double ism_fit_error(const ism_tape *f, const ism_poly_options *po, bool preview);

#endif
