/* project.h — the optional clean-up step that moves manifold vertices onto f = 0
 * (project.c); public (analysis.h includes it). */
#ifndef ISM_AN_PROJECT_H
#define ISM_AN_PROJECT_H

#include <stddef.h>
#include <stdbool.h>
#include "core/mesh/mesh.h"
#include "core/expr/expr.h"
#include "core/analysis/analysis_types.h"

/* What ism_analysis_project did. */
typedef struct ism_projection {
    size_t moved;          /* vertices moved onto f = 0 */
    size_t kept_feature;   /* vertices not moved: not class 0 (boundary, non-manifold...) */
    size_t kept_singular;  /* class-0 vertices not moved: ∇f vanishes there */
    size_t kept_far;       /* not moved: Newton would move it more than half its shortest
                              edge, or did not converge */
    double max_move;       /* longest move made */
} ism_projection;

/* Moves each class-0 vertex of m (a is an analysis of this very mesh: vertex_class, and
 * gradient_scale when it was computed) onto f = 0 by Newton steps along ∇f, and points its
 * normal along ±∇f at the new place (keeping the old normal's side). Never moves a boundary
 * or non-manifold vertex, a vertex where ∇f vanishes, or a vertex further than half its
 * shortest incident edge. Analyse the mesh again afterwards for figures of the moved mesh.
 * o may be NULL. False on bad input or allocation failure (m then unchanged). */
bool ism_analysis_project(ism_mesh *m, const ism_tape *f, const ism_analysis *a,
                          const ism_analysis_options *o, ism_projection *out, ism_error *err);

#endif
