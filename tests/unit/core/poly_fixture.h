/* poly_fixture.h — helpers for the polygoniser tests: compile a surface, polygonise it, and
 * measure the mesh independently of core/analysis (edge incidence, Euler characteristic,
 * components, area, distance of vertices to the surface). */
#ifndef POLY_FIXTURE_H
#define POLY_FIXTURE_H

#include <stdbool.h>
#include <stddef.h>
#include "core/analysis/analysis.h"
#include "core/expr/expr.h"
#include "core/mesh/mesh.h"
#include "core/octree/grid.h"
#include "core/octree/polygonise.h"
#include "core/octree/sampler.h"
#include "core/singular/locus.h"
#include "tests/unit/placements.h"

typedef struct pf_surface {
    const char *expr;
    const ism_param *params;
    size_t nparams;
    const ism_let *lets;
    size_t nlets;
} pf_surface;

typedef struct pf_props {
    size_t verts_used, edges, faces;
    size_t boundary_edges, manifold_edges, nonmanifold_edges;
    long euler;
    size_t components;          /* connected through shared edges */
    double area;
    double max_dist;            /* max over vertices of |f| / |∇f| (vertices with ∇f != 0) */
    double max_abs_f;           /* max |f| over all vertices */
} pf_props;

/* 1 when ISOMESH_TEST_QUICK is set (sanitizer runs): tests lower their depths by this. */
int pf_quick(void);

/* The first of the three box placements (tests/unit/placements.h: 0 as given, 1 shifted by
 * 1e-3, 2 by irrational fractions of a finest cell) a test loops from: 0 normally; 2 under
 * ISOMESH_TEST_QUICK, so the sanitizer run, which looks for memory errors rather than geometry,
 * meshes only the least lattice-aligned box while the release run checks all three. */
int pf_first_box(void);

ism_tape *pf_compile(const pf_surface *s);

/* Default options but for the box and depths given. */
void pf_options(ism_poly_options *o, const double box[6], int dmin, int dmax);

/* Polygonises with options o; asserts success. */
void pf_run_options(const ism_tape *t, const ism_poly_options *o, ism_mesh *m,
                    ism_poly_stats *st);

/* Polygonises with the given box and depths (other options default); asserts success. */
void pf_run(const ism_tape *t, const double box[6], int dmin, int dmax, int threads,
            ism_mesh *m, ism_poly_stats *st);

/* The service's meshing (core/singular/surface.h: the locus found from f, the polygoniser's
 * mesh conformed to it) on one thread; m and l are initialised here; asserts success. */
void pf_run_surface(const ism_tape *t, const double box[6], int dmin, int dmax, ism_mesh *m,
                    ism_locus *l);

/* The same under an error bound max_error (> 0; 0: none). */
/* The service's meshing (ism_mesh_surface) of t under o into fresh m and l, asserted OK; its
 * polygoniser stats into *ps (NULL: not kept). */
void pf_mesh_surface_with(const ism_tape *t, const ism_poly_options *o, ism_mesh *m,
                          ism_locus *l, ism_poly_stats *ps);

void pf_run_surface_bounded(const ism_tape *t, const double box[6], int dmin, int dmax,
                            double max_error, ism_mesh *m, ism_locus *l);

void pf_measure(const ism_mesh *m, const ism_tape *t, pf_props *p);

/* The smallest angle of triangle t (degrees). */
double pf_tri_min_angle(const ism_mesh *m, size_t t);

/* The angle between vectors a and b (degrees, 0..180). */
double pf_vec_angle_deg(const double a[3], const double b[3]);

/* The unit normal of triangle t from its winding. */
void pf_tri_normal(const ism_mesh *m, size_t t, double n[3]);

/* Non-manifold edges (more than two triangles) whose two end points satisfy pred. */
size_t pf_count_nm_edges(const ism_mesh *m, bool (*pred)(const double a[3], const double b[3]));

/* Edges in lo..hi triangles (each edge once) whose two end points satisfy pred (NULL: all). */
size_t pf_count_edges(const ism_mesh *m, size_t lo, size_t hi,
                      bool (*pred)(const double a[3], const double b[3], const void *arg),
                      const void *arg);

/* Number of fans of triangles around vertex v (triangles containing v, joined when they
 * share an edge through v): 1 for a manifold vertex, 2 where two cones meet. */
size_t pf_vertex_cones(const ism_mesh *m, uint32_t v);

/* pf_vertex_cones of every vertex (malloc'd, nverts entries; the caller frees): one pass over
 * the triangles instead of one per vertex. */
size_t *pf_all_vertex_cones(const ism_mesh *m);

/* True when the non-manifold edges form exactly one closed curve (every vertex on them
 * meets two of them, and they are connected). */
bool pf_nm_edges_one_closed_curve(const ism_mesh *m, size_t *nedges);

/* base moved off the octree lattice by the table of tests/unit/placements.h: which 0 the 1e-3
 * placement (PF_OFF_*), which 1 the irrational one (PF_IRR_* of a finest cell of its own axis at
 * depth d); which −1: base as given (so one loop from −1 runs all three). */
void pf_sweep_box(const double base[6], int d, int which, double box[6]);

/* The lattice of 2^d steps an axis over base placed by which (pf_sweep_box), its box into box:
 * the octree's grid (grid.h) for tests that build nodes by hand. */
ism_grid pf_sweep_grid(const double base[6], int d, int which, double box[6]);

/* surf compiled, and *s a sampler of it as the octree build makes them (batched, its own
 * workspace; the caller frees s->ws and the tape returned). */
ism_tape *pf_build_sampler(const pf_surface *surf, ism_sampler *s);

/* pf_sweep_box with which 1 at the old rational placement (PF_OLD_*): only for a regression
 * case named as such (a box where a bug was found, run beside the three placements — today the
 * double torus's crease crack); not for new tests. */
void pf_sweep_box_old(const double base[6], int d, int which, double box[6]);

/* pf_sweep_box(base, d, which, box), then pf_run at depths 3..d (all threads) and
 * pf_measure into *p: one placement of a sweep over the three boxes. */
void pf_run_placed(const ism_tape *t, const double base[6], int d, int which, double box[6],
                   ism_mesh *m, pf_props *p);

/* Both ends strictly inside the box arg (farther than 1e-9 from its faces): for
 * pf_count_edges, an edge of a hole, not of the cut by the box. */
bool pf_inside_box(const double a[3], const double b[3], const void *arg);

/* The service's default error bound for box: 1e-3 × its diagonal (proto/request.h's
 * ISM_REQ_DEFAULT_ERROR_REL, written out: core tests do not include proto). */
double pf_default_error(const double box[6]);

/* Finest cell size of the box at depth d (the smallest side / 2^d). */
double pf_cell(const double box[6], int d);

/* Asserts that two meshes are the same bit for bit: positions, normals, triangles and
 * segments, in the same order. */
void pf_same_mesh(const ism_mesh *a, const ism_mesh *b, const char *what);

/* The unit sphere and the ring torus R = 1, r = 0.3 about z, with their exact (closed-form)
 * unsigned distances. */
extern const pf_surface pf_unit_sphere, pf_ring_torus;
double pf_unit_sphere_dist(const double p[3]);
double pf_ring_torus_dist(const double p[3]);

/* Barth's nodal sextic (65 nodes, 30 of them inside) in the ball r² ≤ 2.25: bench_error's
 * barth-sextic, a locus of nodes and a min/max crease where the sextic meets the sphere. */
extern const pf_surface pf_barth_sextic;

/* The gyroid sin(kx)cos(ky) + sin(ky)cos(kz) + sin(kz)cos(kx), k = 4, cut by the ball
 * r² ≤ 1.96 through max(): bench_error's gyroid-ball, a trig tape with a min/max crease. */
extern const pf_surface pf_gyroid_ball;

/* Distance from p to f = 0 by Newton's projection (the last iterate's distance plus its
 * |f| / |∇f| when it does not settle: an over-estimate). */
double pf_newton_dist(const ism_tape *t, ism_eval_ws *ws, const double p[3]);

/* The farthest centroid or edge midpoint from f = 0, by dist (NULL: pf_newton_dist on t); the
 * triangles whose normal points against ∇f at their centroid into *turned. */
double pf_worst_turned(const ism_mesh *m, const ism_tape *t, double (*dist)(const double *),
                       size_t *turned);

/* The service's analysis of m on one thread without curvature (distances at vertices, centroids
 * and midpoints): asserts it ran; the caller frees *a. */
void pf_analyse_plain(const ism_mesh *m, const ism_tape *t, ism_analysis *a);

/* The largest |dist| at the mesh's vertices, triangle centroids and edge midpoints. */
double pf_worst_distance(const ism_mesh *m, double (*dist)(const double *));

#endif
