/* crease_normals.h — sharp shading along creases: one normal per triangle corner, from the
 * branch of f the triangle lies on, so a crease vertex carries one normal per side. */
#ifndef ISM_CREASE_NORMALS_H
#define ISM_CREASE_NORMALS_H

#include <stdbool.h>
#include "core/eval/eval.h"
#include "core/mesh/mesh.h"

/* out (9 floats per triangle): at each corner the unit gradient of the branch of f taken at
 * the triangle's centroid (branches.h), pointing as ∇f_i does;
 * the vertex's own normal where f has no min/max or ties at the centroid. Meant for a mesh
 * cut along its creases (no triangle straddles one). False when out of memory. */
bool ism_crease_corner_normals(const ism_tape *f, const ism_mesh *m, float *out);

#endif
