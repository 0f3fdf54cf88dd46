/* crease_normals.h — sharp shading along creases: one normal per triangle corner, from the
 * branch of f the triangle lies on, so a crease vertex carries one normal per side. */
#ifndef ISM_CREASE_NORMALS_H
#define ISM_CREASE_NORMALS_H

#include <stdbool.h>
#include "core/curves/cut_types.h"
#include "core/eval/eval.h"
#include "core/mesh/mesh.h"

/* out (9 floats per triangle): at each corner the unit gradient of the branch of f the
 * triangle lies on (branches.h), pointing as ∇f_i does; the vertex's own normal where f has
 * no min/max or no branch is decided. The triangle's branch is f's at its first corner off
 * the crease (the ends of cut's crease edges; cut NULL: none known) — a corner on the
 * surface, on the triangle's side, since no edge of a mesh cut along its creases crosses
 * one — and at its centroid when every corner is on the crease or ties. (The centroid alone
 * is no guide for a sliver along the crease: the flat triangle's middle lies off the
 * surface by more than its width, on either side.) False when out of memory. */
bool ism_crease_corner_normals(const ism_tape *f, const ism_mesh *m, const ism_cut *cut,
                               float *out);

#endif
