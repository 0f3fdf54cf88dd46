/* arr_internal.h — what the arrangement's files share (not public): the mesh's edges with
 * their triangles and whether they lie on a curve, and a small union-find. */
#ifndef ISM_ARR_INTERNAL_H
#define ISM_ARR_INTERNAL_H

#include "core/analysis/unionfind.h"
#include "core/curves/arr_types.h"
#include "core/curves/cut_types.h"
#include "core/mesh/mesh.h"
#include "core/singular/locus.h"

typedef struct arr_mesh_edges {
    uint32_t *lo_start;   /* per vertex v: its edges to higher vertices are lo_start[v] ..
                             lo_start[v + 1] (nverts + 1 entries) */
    uint32_t *hi;         /* per edge: its higher vertex */
    uint32_t *tri_edge;   /* 3 per triangle: its edges (v0v1, v1v2, v2v0) */
    uint32_t *ntri;       /* per edge: triangles using it */
    uint8_t *on_curve;    /* per edge */
    uint8_t *v_on_curve;  /* per vertex */
    uint8_t *v_used;      /* per vertex: some triangle uses it */
    size_t n;
} arr_mesh_edges;

#define ARR_NO_EDGE UINT32_MAX

/* The edge a-b of the mesh, or ARR_NO_EDGE (a scan of the lower end's few edges). */
uint32_t arr_edge_find(const arr_mesh_edges *e, uint32_t a, uint32_t b);
bool arr_mesh_edges_build(const ism_mesh *m, const ism_cut *c, arr_mesh_edges *e);
void arr_mesh_edges_free(arr_mesh_edges *e);
/* The number of distinct edges of the mesh's triangles (SIZE_MAX when out of memory). */
size_t arr_mesh_edge_count(const ism_mesh *m);


/* Faces: triangles reordered, tri_face and faces filled; comp gets each triangle's mesh
 * component (in the new order) and a->ncomponents is set. */
bool arr_build_faces(ism_mesh *m, arr_mesh_edges *e, ism_arrangement *a, uint32_t *comp,
                     uint32_t *tri_parent);

/* Singular marks of the vertices on curves (arr_singular.c): ARR_SING_NONE, ARR_SING_DOUBLE
 * (on a double curve the curve crosses or leaves) or the index of the locus point within
 * tol (l may be NULL: no points). mark has m->nverts entries. False when out of memory. */
#define ARR_SING_NONE UINT32_MAX
#define ARR_SING_DOUBLE (UINT32_MAX - 1)
bool arr_singular_marks(const ism_mesh *m, const ism_cut *c, const arr_mesh_edges *e,
                        const ism_locus *l, double tol, uint32_t *mark);

/* Vertices, edges and curves from the cut edges; sing: the marks above. */
bool arr_build_graph(const ism_mesh *m, const ism_cut *c, const uint32_t *sing,
                     ism_arrangement *a);

#endif
