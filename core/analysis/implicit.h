/* implicit.h — the pass that evaluates f on the mesh (implicit.c): curvature, the singular
 * flag and the distances to f = 0. */
#ifndef ISM_AN_IMPLICIT_H
#define ISM_AN_IMPLICIT_H

#include <stdbool.h>
#include "core/mesh/mesh.h"
#include "core/expr/expr.h"
#include "core/analysis/analysis_types.h"
#include "core/analysis/vertices.h"
#include "core/util/pool.h"

/* Curvature and accuracy from f (needs vertex_area, corners), evaluated on the threads of
 * pool (NULL: the calling thread); false when out of memory. */
bool ism_an_implicit_figures(const ism_mesh *m, const ism_tape *f, const ism_analysis_options *o,
                             const ism_an_vertex_facts *vf, ism_pool *pool, ism_analysis *a);

/* Clamps to ±1e30 and turns NaN into 0, for float outputs. */
float ism_an_finite_float(double x);

#endif
