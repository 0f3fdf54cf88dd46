/* conform_internal.h — what the files of the conformance pass share: the surgery context
 * (mesh, per-triangle dead marks, vertex→triangle incidence), hole loops, and the polyline
 * of a curve with its arclength parameter. Not a public header. */
#ifndef ISM_CONFORM_INTERNAL_H
#define ISM_CONFORM_INTERNAL_H

#include <stddef.h>
#include <stdint.h>
#include <stdbool.h>
#include "core/eval/eval.h"
#include "core/singular/conform.h"

#define CF_NONE UINT32_MAX

typedef struct cf_ctx {
    const ism_tape *f;
    ism_eval_ws *ws;
    ism_mesh *m;
    uint8_t *dead;          /* per triangle: removed by surgery (compacted at the end) */
    size_t cap_dead;
    uint32_t *inc_start;    /* live triangles around each vertex: inc_tri[inc_start[v] ..
                               inc_start[v+1]) (rebuilt before each surgery) */
    uint32_t *inc_tri;
    size_t inc_nverts, cap_inc_start, cap_inc_tri;
    uint8_t *singular;      /* per vertex: made by the pass where ∇f vanishes (normal from
                               the adjacent triangles at the end) */
    size_t cap_singular;
    double cell;            /* finest octree cell: the scale of the surgery */
    ism_conform_stats *st;
} cf_ctx;

/* Radius of the ball or tube cut around the locus, in finest cells: the polygoniser's
 * confusion (digon loops, island caps in a neighbour cell, polygons crossing without a shared
 * edge) stays in the cells that hold the singularity and their neighbours, within about
 * 2√3 cells; a triangle is cut when any part of it comes this close. */
#define CF_RHO_CELLS 2.5
/* ... and at least this many times the longest edge of the triangles there, where the
 * octree did not reach its finest depth. */
#define CF_RHO_EDGES 1.25

/* One run of the pass: the context, the locus and the mesh vertex given to each point. */
typedef struct cf_run {
    cf_ctx c;
    ism_locus *l;
    const ism_locus_options *o;
    uint32_t *point_vertex; /* per locus point: its mesh vertex, or CF_NONE */
} cf_run;

/* A chain of hole-boundary vertices, oriented so that new triangles traverse v[i] → v[i+1]
 * (opposite to the kept triangle on that edge). closed: v[n-1] → v[0] is an edge too. */
typedef struct cf_loop {
    uint32_t *v;
    size_t n;
    bool closed;
} cf_loop;

typedef struct cf_loops {
    cf_loop *l;
    size_t n, cap;
} cf_loops;

void cf_loops_free(cf_loops *ls);

/* A curve's polyline with cumulative arclength s[i] at point i (s[n] = total length when
 * closed: the closing segment), and a uniform grid over its segments for nearest-point
 * queries. */
typedef struct cf_polyline {
    const double *p;        /* 3 per point */
    size_t n;
    bool closed;
    double *s;              /* n + 1 entries */
    double length;
    double lo[3], step;     /* grid origin and cell side */
    int dim[3];
    uint32_t *g_start, *g_seg; /* segments per grid cell (CSR) */
} cf_polyline;

/* ---- conform_mesh.c: incidence, dead marks, growth ---- */
bool cf_ctx_prepare(cf_ctx *c);          /* room for the dead marks and incidence (current mesh) */
void cf_ctx_free(cf_ctx *c);
bool cf_add_triangle(cf_ctx *c, uint32_t a, uint32_t b, uint32_t d);
uint32_t cf_add_vertex(cf_ctx *c, const double p[3], bool singular);
/* Longest edge of the live triangles at vertex v / with a vertex within r of p. */
double cf_vertex_longest_edge(const cf_ctx *c, uint32_t v);
double cf_longest_edge_near(const cf_ctx *c, const double p[3], double r);
/* Removes dead triangles and the vertices only they used; recomputes the singular vertices'
 * normals. */
bool cf_compact(cf_ctx *c);

/* ---- conform_hole.c: removal and hole loops ---- */
/* Marks dead the live triangles for which near(ctx, triangle) is true, then chains the
 * hole's boundary edges (edges left with one live triangle that lost at least one) into
 * loops. Returns false on allocation failure (nothing marked then). *removed counts the
 * triangles marked. */
typedef bool (*cf_tri_pred)(const cf_ctx *c, uint32_t t, void *arg);
bool cf_cut_hole(cf_ctx *c, cf_tri_pred near, void *arg, cf_loops *out,
                 uint32_t **removed, size_t *nremoved);
/* cf_cut_hole, grown (*radius, which pred reads through arg, times a factor) until the rim
 * is clear of other sheets (cf_rim_clear), a bounded number of times and never beyond
 * max_radius. */
bool cf_cut_clean(cf_ctx *c, cf_tri_pred pred, void *arg, double *radius,
                  double max_radius, cf_loops *ls, uint32_t **removed, size_t *nremoved);
/* Undoes a cut whose refilling failed: revives the triangles, drops everything appended
 * since (ntris, nverts). */
void cf_undo(cf_ctx *c, const uint32_t *removed, size_t nremoved, size_t ntris, size_t nverts);
/* True when no rim vertex has another sheet of f = 0 within `clearance` along its normal:
 * the rim lies where the polygoniser's sheets are apart, outside its confusion. */
bool cf_rim_clear(cf_ctx *c, const cf_loops *ls, double clearance);
/* Squared distance from q to the triangle abc. */
double cf_point_triangle_d2(const double q[3], const double a[3], const double b[3],
                            const double c[3]);

/* ---- conform_fill.c: rings, ladders, fans ---- */
/* Moves p onto f = 0 by Newton along ∇f, unless that moves it more than max_move or does not
 * bring it closer (then p is kept). */
void cf_project(cf_ctx *c, double p[3], double max_move);
/* Number of intermediate rings for a strip of width `width` next to a loop of mean edge
 * length `edge`. */
int cf_ring_count(double width, double edge);
double cf_loop_mean_edge(const cf_ctx *c, const cf_loop *l);
/* Triangles between two rows of equal length (a outer, b inner, same direction). */
bool cf_ladder(cf_ctx *c, const uint32_t *a, const uint32_t *b, size_t n, bool closed);
/* Fans the loop to vertex apex through `rings` rings of vertices between the loop and
 * apex_pos, projected onto f = 0. */
bool cf_fan(cf_ctx *c, const cf_loop *l, uint32_t apex, const double apex_pos[3], int rings);
/* Fans a loop to its centroid projected onto f = 0 (the fallback that leaves no crack). */
bool cf_fan_centroid(cf_ctx *c, const cf_loop *l);

/* ---- conform_curve.c: polylines ---- */
bool cf_polyline_init(cf_polyline *pl, const double *p, size_t n, bool closed, double step);
void cf_polyline_free(cf_polyline *pl);
/* Distance from q to the polyline, its arclength parameter and foot point (when not NULL);
 * returns INFINITY when nothing lies within `within` (the grid is searched that far). */
double cf_polyline_nearest(const cf_polyline *pl, const double q[3], double within, double *s,
                           double foot[3]);

/* ---- conform_zip.c: zipping loops to a curve ---- */
/* Refills the hole loops cut around a group of npl double curves (meeting at shared end
 * points): each loop (through rings) is stitched to the vertices cv[k] (one per polyline
 * point) of the curves it runs along, by arclength. */
bool cf_zip_loops(cf_ctx *c, const cf_polyline *pl, const uint32_t *const *cv, size_t npl,
                  const cf_loops *ls, double rho);

/* ---- conform_point.c, conform_tube.c: the two surgeries ---- */
/* Point i of the locus made one vertex shared by its cones. False only when out of memory
 * (the mesh is then as before). */
bool cf_conform_point(cf_run *r, size_t i);
/* The double curves idx[0..n) (a group meeting at shared end points) made chains of mesh
 * edges. False only when out of memory (the mesh is then as before). */
bool cf_conform_curves(cf_run *r, const size_t *idx, size_t n);

/* ---- conform_artefacts.c ---- */
/* Non-manifold edges and points of m off the locus l (check.h's rule). */
bool cf_count_artefacts(const ism_mesh *m, const ism_locus *l, const double box[6],
                        size_t *edges, size_t *verts, ism_error *err);

#endif
