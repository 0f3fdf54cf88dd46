/* curves.h — the pass that chains non-manifold edges into curves and lists the non-manifold
 * points (curves.c). */
#ifndef ISM_AN_CURVES_H
#define ISM_AN_CURVES_H

#include <stdbool.h>
#include "core/mesh/mesh.h"
#include "core/analysis/analysis_types.h"
#include "core/analysis/edges.h"
#include "core/analysis/vertices.h"

/* Non-manifold curves and points (needs the vertex classes and vf); false when out of
 * memory. */
bool ism_an_find_curves(const ism_mesh *m, const ism_an_edge_table *et,
                        const ism_an_vertex_facts *vf, ism_analysis *a);
bool ism_an_find_points(const ism_mesh *m, const ism_an_vertex_facts *vf, ism_analysis *a);

#endif
