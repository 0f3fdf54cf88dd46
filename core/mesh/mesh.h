/* mesh.h — the indexed triangle mesh that the polygoniser produces and everything after it
 * (analysis, writers, encoders) reads: double positions, unit normals from ∇f, triangles
 * as vertex index triples, all in growable arrays with a hard budget. */
#ifndef ISM_MESH_H
#define ISM_MESH_H

#include <stddef.h>
#include <stdint.h>
#include <stdbool.h>

typedef struct ism_mesh {
    size_t nverts, ntris;
    size_t cap_verts, cap_tris;
    double *pos;    /* 3 per vertex */
    float *normal;  /* 3 per vertex, unit length (or 0,0,0 where no normal is known) */
    uint32_t *tri;  /* 3 per triangle, counter-clockwise seen from where ∇f points */
    /* One-dimensional parts of the surface: the paper's one-edge (degenerate) polygons,
     * e.g. the parts of Steiner's double lines that no sheet passes through. */
    size_t nsegs, cap_segs;
    uint32_t *seg;  /* 2 vertex indices per segment */
} ism_mesh;

void ism_mesh_init(ism_mesh *m);
void ism_mesh_free(ism_mesh *m);

/* Makes room for at least nverts vertices and ntris triangles. False on allocation failure. */
bool ism_mesh_reserve(ism_mesh *m, size_t nverts, size_t ntris);

/* Appends a vertex (normal may be NULL). Returns its index, or UINT32_MAX when out of memory. */
uint32_t ism_mesh_add_vertex(ism_mesh *m, const double p[3], const float *normal);

/* Appends a triangle. False when out of memory. */
bool ism_mesh_add_triangle(ism_mesh *m, uint32_t a, uint32_t b, uint32_t c);

/* Appends a segment (a one-edge polygon). False when out of memory. */
bool ism_mesh_add_segment(ism_mesh *m, uint32_t a, uint32_t b);

/* Bytes held by the mesh's arrays (for memory budgets). */
size_t ism_mesh_bytes(const ism_mesh *m);

/* Drops every vertex that no triangle or segment uses and that used[v] (nonzero) does not
 * keep; the others keep their order, triangles and segments are renumbered, and used[v]
 * becomes old vertex v's new index (UINT32_MAX: dropped) for what the caller indexes beside
 * the mesh. used: m->nverts entries. */
void ism_mesh_compact(ism_mesh *m, uint32_t *used);

/* Drops the segments and every vertex no triangle uses, keeping the others in order
 * (triangles renumbered). For a mesh whose one-dimensional parts travel elsewhere (the
 * singular locus carries whiskers as curves). False when out of memory (m unchanged). */
bool ism_mesh_drop_loose(ism_mesh *m);

/* Axis-aligned bounds of the vertices; false for an empty mesh. */
bool ism_mesh_bounds(const ism_mesh *m, double lo[3], double hi[3]);

#endif
