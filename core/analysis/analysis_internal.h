/* analysis_internal.h — what the analysis passes share inside core/analysis: the edge table,
 * per-vertex counts, the error helper, the union-find and the block-parallel runner. Not a
 * public header: nothing outside core/analysis includes it. */
#ifndef ISM_ANALYSIS_INTERNAL_H
#define ISM_ANALYSIS_INTERNAL_H

#include <stddef.h>
#include <stdint.h>
#include <stdbool.h>
#include "core/analysis/analysis.h"
#include "core/eval/eval.h"

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

bool ism_an_edge_table_build(const ism_mesh *m, ism_an_edge_table *et);
void ism_an_edge_table_free(ism_an_edge_table *et);

/* Both end points of edge e, smaller first. */
void ism_an_edge_ends(const ism_mesh *m, const ism_an_edge_table *et, uint32_t e, uint32_t *lo,
                      uint32_t *hi);

/* Per-vertex facts shared by the passes. */
typedef struct ism_an_vertex_facts {
    uint32_t *corners;    /* corners of non-collapsed triangles at the vertex */
    uint32_t *cones;      /* cones of faces around the vertex */
    uint32_t *nm_degree;  /* non-manifold edges at the vertex */
    uint32_t *cone_sets;  /* per corner (half-edge): union-find of the corners in one cone */
} ism_an_vertex_facts;

void ism_an_vertex_facts_free(ism_an_vertex_facts *vf);

/* Cones of faces and vertex classes: fills vf and a->vertex_class, class counts. */
bool ism_an_classify_vertices(const ism_mesh *m, const ism_an_edge_table *et,
                              ism_an_vertex_facts *vf, ism_analysis *a);

/* Non-manifold curves and points (needs classes and vf). */
bool ism_an_find_curves(const ism_mesh *m, const ism_an_edge_table *et,
                        const ism_an_vertex_facts *vf, ism_analysis *a);
bool ism_an_find_points(const ism_mesh *m, const ism_an_vertex_facts *vf, ism_analysis *a);

/* Numbers the components (triangles joined by shared edges) in order of their smallest
 * triangle: comp[t] for every triangle (ISM_AN_NONE if collapsed). */
bool ism_an_edge_components(const ism_mesh *m, const ism_an_edge_table *et, uint32_t *comp,
                            size_t *ncomp);

/* Components of the graph of vertices joined by triangles (used vertices only). */
bool ism_an_vertex_components(const ism_mesh *m, const ism_an_vertex_facts *vf, size_t *n);

/* Sets bad[c] for every component c that cannot be oriented consistently across its
 * manifold edges; counts the manifold edges whose triangles run the same way. */
bool ism_an_orientation(const ism_mesh *m, const ism_an_edge_table *et, const uint32_t *comp,
                        uint8_t *bad, size_t *inconsistent);

/* Chains the boundary edges (walking each end vertex's cone of faces to the next boundary
 * edge): fills a->boundary_loops, a->boundary_chains and component[c].boundary_loops. */
bool ism_an_boundary_chains(const ism_mesh *m, const ism_an_edge_table *et,
                            const ism_an_vertex_facts *vf, const uint32_t *comp, ism_analysis *a);

/* Counts triangles with the same three vertices as an earlier one. */
bool ism_an_count_duplicates(const ism_mesh *m, const ism_an_edge_table *et, ism_analysis *a);

/* Euler characteristic, components, orientability, boundary loops, genus. */
bool ism_an_topology(const ism_mesh *m, const ism_an_edge_table *et, ism_an_vertex_facts *vf,
                     ism_analysis *a);

/* Smallest angles, degenerate triangles, vertex areas, total area. */
bool ism_an_triangle_quality(const ism_mesh *m, ism_analysis *a);

/* Curvature and accuracy from f (needs vertex_area, corners). */
bool ism_an_implicit_figures(const ism_mesh *m, const ism_tape *f, const ism_analysis_options *o,
                             const ism_an_vertex_facts *vf, ism_analysis *a);

/* Maximum, mean and 99th percentile of the distances that are not NaN (reorders dist);
 * skipped: how many were NaN. */
typedef struct ism_an_distances {
    double max, mean, p99;
    size_t skipped;
} ism_an_distances;
void ism_an_distance_figures(double *dist, size_t n, ism_an_distances *out);

/* Distances at triangle centroids and edge midpoints (after ism_an_implicit_figures, which
 * sets the singular threshold). */
bool ism_an_between_vertices(const ism_mesh *m, const ism_tape *f, const ism_an_edge_table *et,
                             int threads, ism_analysis *a);

/* Input checks shared by ism_analyse and ism_analysis_project (false with a message). */
bool ism_an_check_mesh(const ism_mesh *m, ism_error *err);
bool ism_an_check_options(const ism_analysis_options *o, ism_error *err);

/* Fills err (may be NULL) with a positionless message; returns false (the expression
 * engine's ism_error_set). */
#define ism_an_fail ism_error_set

/* Union-find over n elements whose roots are always the smallest member: parent[i] <= i. */
uint32_t ism_an_uf_find(uint32_t *parent, uint32_t i);
/* Joins the sets of i and j; true when they were different sets. */
bool ism_an_uf_union(uint32_t *parent, uint32_t i, uint32_t j);

/* The k-th smallest (0-based) of v[0..n), reordering v. n > k. */
double ism_an_select_double(double *v, size_t n, size_t k);
float ism_an_select_float(float *v, size_t n, size_t k);

/* Runs fn(ctx, ws, block) for every block < nblocks on up to `threads` threads, each with its
 * own workspace for f. Blocks are independent; results must not depend on which thread ran
 * which block. False when no workspace could be made. */
typedef void (*ism_an_block_fn)(void *ctx, ism_eval_ws *ws, size_t block);
bool ism_an_run_blocks(const ism_tape *f, int threads, size_t nblocks, ism_an_block_fn fn,
                       void *ctx);

/* Threads to use for option value t (0 = online cores), at most 64. */
int ism_an_threads(int t);

/* Clamps to ±1e30 and turns NaN into 0, for float outputs. */
float ism_an_finite_float(double x);

#endif
