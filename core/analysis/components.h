/* components.h — connected components by shared edges and by shared vertices
 * (components.c), parts of the topology pass. */
#ifndef ISM_AN_COMPONENTS_H
#define ISM_AN_COMPONENTS_H

#include <stddef.h>
#include <stdint.h>
#include <stdbool.h>
#include "core/mesh/mesh.h"
#include "core/analysis/edges.h"
#include "core/analysis/vertices.h"

/* Numbers the components (triangles joined by shared edges) in order of their smallest
 * triangle: comp[t] for every triangle (ISM_AN_NONE if collapsed). */
bool ism_an_edge_components(const ism_mesh *m, const ism_an_edge_table *et, uint32_t *comp,
                            size_t *ncomp);

/* Components of the graph of vertices joined by triangles (used vertices only). */
bool ism_an_vertex_components(const ism_mesh *m, const ism_an_vertex_facts *vf, size_t *n);

#endif
