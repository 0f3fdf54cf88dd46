/* edges.h — the edge table every analysis pass walks (built by edges.c), and the half-edge
 * conventions it rests on. Depends on the mesh only. */
#ifndef ISM_AN_EDGES_H
#define ISM_AN_EDGES_H

#include <stddef.h>
#include <stdint.h>
#include <stdbool.h>
#include "core/mesh/mesh.h"
#include "core/util/pool.h"

#define ISM_AN_NONE UINT32_MAX

/* Half-edge h = 3t + k runs from tri[h] to tri[ism_an_he_next(h)]; it is also the corner of
 * triangle t at vertex tri[h]. */
static inline uint32_t ism_an_he_next(uint32_t h) { return h % 3 == 2 ? h - 2 : h + 1; }
static inline uint32_t ism_an_he_prev(uint32_t h) { return h % 3 == 0 ? h + 2 : h - 1; }

static inline bool ism_an_tri_collapsed(const uint32_t *tri, size_t t)
{
    uint32_t a = tri[3 * t], b = tri[3 * t + 1], c = tri[3 * t + 2];
    return a == b || b == c || a == c;
}

/* Edges of the non-collapsed triangles. Edge e joins the vertex pair (lo, hi), lo < hi, that
 * ism_an_edge_ends gives; edges are numbered in order of that pair; its half-edges are
 * edge_he[edge_start[e] .. edge_start[e + 1]) in increasing order. */
typedef struct ism_an_edge_table {
    size_t nedges;
    uint32_t *he_edge;    /* 3 * ntris: the edge of each half-edge (ISM_AN_NONE if collapsed) */
    uint32_t *edge_start; /* nedges + 1 */
    uint32_t *edge_he;    /* half-edges grouped by edge */
} ism_an_edge_table;

static inline uint32_t ism_an_edge_count(const ism_an_edge_table *et, uint32_t e)
{
    return et->edge_start[e + 1] - et->edge_start[e];
}

/* Builds the table of m's edges; false on allocation failure (et then holds nothing). */
bool ism_an_edge_table_build(const ism_mesh *m, ism_an_edge_table *et);

/* The same on the threads of pool (NULL: the calling thread); the same table on any number. */
bool ism_an_edge_table_build_on(const ism_mesh *m, ism_pool *pool, ism_an_edge_table *et);
void ism_an_edge_table_free(ism_an_edge_table *et);

/* Both end points of edge e, smaller first. */
void ism_an_edge_ends(const ism_mesh *m, const ism_an_edge_table *et, uint32_t e, uint32_t *lo,
                      uint32_t *hi);

#endif
