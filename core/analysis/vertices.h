/* vertices.h — the per-vertex facts (corners, cones of faces, non-manifold degree) that
 * vertices.c computes while classifying vertices, and the later passes read. */
#ifndef ISM_AN_VERTICES_H
#define ISM_AN_VERTICES_H

#include <stdint.h>
#include <stdbool.h>
#include "core/mesh/mesh.h"
#include "core/analysis/analysis_types.h"
#include "core/analysis/edges.h"

typedef struct ism_an_vertex_facts {
    uint32_t *corners;    /* corners of non-collapsed triangles at the vertex */
    uint32_t *cones;      /* cones of faces around the vertex */
    uint32_t *nm_degree;  /* non-manifold edges at the vertex */
    uint32_t *cone_sets;  /* per corner (half-edge): union-find of the corners in one cone */
} ism_an_vertex_facts;

void ism_an_vertex_facts_free(ism_an_vertex_facts *vf);

/* Starts vf (all else empty): the corners at each vertex (false when out of memory). */
bool ism_an_count_corners(const ism_mesh *m, ism_an_vertex_facts *vf);

/* Cones of faces and vertex classes: fills the rest of vf (after ism_an_count_corners) and
 * a->vertex_class, class counts. */
bool ism_an_classify_vertices(const ism_mesh *m, const ism_an_edge_table *et,
                              ism_an_vertex_facts *vf, ism_analysis *a);

#endif
