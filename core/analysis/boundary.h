/* boundary.h — boundary edges chained into loops and chains (boundary.c), part of the
 * topology pass. */
#ifndef ISM_AN_BOUNDARY_H
#define ISM_AN_BOUNDARY_H

#include <stdint.h>
#include <stdbool.h>
#include "core/mesh/mesh.h"
#include "core/analysis/analysis_types.h"
#include "core/analysis/edges.h"
#include "core/analysis/vertices.h"

/* Chains the boundary edges (walking each end vertex's cone of faces to the next boundary
 * edge): fills a->boundary_loops, a->boundary_chains and component[c].boundary_loops. */
bool ism_an_boundary_chains(const ism_mesh *m, const ism_an_edge_table *et,
                            const ism_an_vertex_facts *vf, const uint32_t *comp, ism_analysis *a);

#endif
