/* sp_collapse.h — the simplification's edge collapses (sp_collapse.c): one round over the
 * mesh's edges with an active end, shortest first, a merged vertex in no other collapse that
 * round. */
#ifndef ISM_SP_COLLAPSE_H
#define ISM_SP_COLLAPSE_H

#include "core/remesh/rm_pass.h"

/* Collapses the edges whose merge keeps the mesh within max_error (every new centroid and
 * edge midpoint measured, rm_bound.h), its topology (the link condition), its features
 * (locked vertices stay where they are, locked edges are never collapsed), its orientation
 * (no new triangle turns against its old self or the surface's normal at its corners) and
 * its shape (no new angle below the fan's smallest before, or below ISM_SP_MIN_DEG). Only
 * edges with an active end are tried; then the corners of the new triangles are the active
 * ones. Polls cancel every few hundred edges.
 * Returns the collapses made; *ok false when out of memory. */
size_t sp_collapse_round(rm_pass *p, const volatile int *cancel, bool *ok);

#endif
