/* cut.h — cutting a triangle mesh of f = 0 along curves f = 0, g = 0: triangles crossed by
 * g = 0 are split so mesh edges run along the curve, every new vertex put on both surfaces
 * by Newton (on three where two curves cross a mesh edge together). The curve is then the
 * set of cut edges. */
#ifndef ISM_CUT_H
#define ISM_CUT_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>
#include "core/curves/cut_fn.h"
#include "core/curves/cut_types.h"
#include "core/mesh/mesh.h"

void ism_cut_free(ism_cut *c);

/* Cuts m along every function of ev in turn (c initialised to zeros by the caller). tol is
 * the distance both surfaces must be within at curve vertices (1e-10 × the box diagonal
 * asks the precision). Triangle winding is kept; normals of new vertices are ∇f's
 * direction, oriented like their edge's. Vertices no triangle, segment or cut edge uses are
 * dropped at the end (the others keep their order; indices renumbered). False when out of
 * memory. */
bool ism_cut_mesh(ism_cut_eval *ev, double tol, ism_mesh *m, ism_cut *c);

#endif
