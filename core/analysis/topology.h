/* topology.h — the topology pass (topology.c): Euler characteristic, components,
 * orientability, boundary loops, genus. */
#ifndef ISM_AN_TOPOLOGY_H
#define ISM_AN_TOPOLOGY_H

#include <stdbool.h>
#include "core/mesh/mesh.h"
#include "core/analysis/analysis_types.h"
#include "core/analysis/edges.h"
#include "core/analysis/vertices.h"

/* Euler characteristic, components, orientability, boundary loops, genus (needs the vertex
 * classes and vf); false when out of memory. */
bool ism_an_topology(const ism_mesh *m, const ism_an_edge_table *et, ism_an_vertex_facts *vf,
                     ism_analysis *a);

#endif
