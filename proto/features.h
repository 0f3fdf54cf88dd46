/* features.h — the singular structure that travels beside the triangles: the singular locus
 * found from f (certified points, singular curves, double sheets), the mesh's own
 * non-manifold edges and points checked against it (Draco splits vertices along non-manifold
 * edges and drops degenerate faces, so none of this can be re-derived from a .drc), and the
 * boundary chains. The viewer gets it as the "features" JSON next to a .drc
 * (GET /v1/meshes/{key}/features, `isomesh --features FILE`) and as LINES / POINTS
 * primitives inside a .glb.
 *
 * Features JSON (version 2; locus coordinates as printed by the table below, mesh coordinates
 * as the float32 positions before quantisation):
 *   {"version": 2,
 *    "classes": ["manifold", "boundary", "nonmanifold_edge", "nonmanifold_point", "isolated"],
 *    "singular_points": [{"xyz", "radius", "type", "certified", "hessian_eigenvalues",
 *                         "residual_f", "residual_grad", "cones"}],
 *    "curves": [{"kind": "double"|"whisker", "closed", "points", "tolerance",
 *                "xyz": [x0, y0, z0, ...],
 *                "ends": [{"type", "xyz", "point"}]}],        (ends: [] when closed)
 *              then the requested curves: {"kind": "section"|"level"|"intersection"|
 *                "silhouette"|"crease", "source", "index", "closed", "length", "edges",
 *                "tolerance" (crease only: the digits table below), "arcs",
 *                "ends": [{"type": "box"|"double_curve"|"singular_point", "xyz",
 *                "vertex", "point" (singular_point: index into singular_points)}]}
 *    "arrangement": {...} (only when curves were requested; features_curves.c),
 *    "double_sheets": [{"first_triangle", "triangles", "area"}],
 *    "nonmanifold_edges": [{"closed", "on_locus", "off_edges", "xyz"}],   chains of mesh edges
 *              of > 2 triangles; off_edges: the chain's edges (edge j joins points j and j + 1)
 *              with an end off the locus, the ones counts.artefacts counts
 *    "nonmanifold_points": [{"xyz", "class", "kind", "on_locus"}],
 *    "boundaries": [{"closed", "xyz"}],
 *    "incomplete": bool, "incomplete_why": string (only when incomplete),
 *    "tolerance": number (only when the mesh positions are drawn within one: the table below),
 *    "counts": {...}}
 * "class" is the vertex class (index into "classes", the same numbers as the Draco "class"
 * attribute). An element with "on_locus": false is an artefact of the polygoniser. */
#ifndef ISM_FEATURES_H
#define ISM_FEATURES_H

#define ISM_FEATURES_VERSION 2

/* How many digits the features JSON prints, from each value's own stated tolerance (the one
 * table; digits below the tolerance are noise and were most of the bytes: 17 significant
 * digits per coordinate made the features of klein-bottle 49% of its default .drc):
 *   singular curves' points ("curves"[k].xyz, .ends[].xyz, .first_uncertified.xyz, kinds
 *     double / whisker): d = ism_features_decimals(r) decimals, r the curve's certificate
 *     radius (the largest half-width of a Krawczyk square: a zero of the gradient across the
 *     curve lies in the square of half-width r round each certified point). Rounding moves each
 *     coordinate by <= 0.5 * 10^-d, the point by <= ISM_FEATURES_ROUNDING(d) = (sqrt 3 / 2) *
 *     10^-d <= r; the JSON states certificate_radius = r + ISM_FEATURES_ROUNDING(d) (<= 2 r), so
 *     the printed point lies within sqrt 2 * that of the zero, as the full one lay within
 *     sqrt 2 * r. The curve's stated 1e-9 x diagonal (r <= 0.5e-9 x diagonal) still holds.
 *     A curve without a finite r > 0 is printed in full. With a drawing tolerance t > 0
 *     (below) only the traced points that keep every other one within t - that rounding of
 *     the polyline through them are printed (polyline_thin.h; the first uncertified point
 *     always, first_uncertified.index counts the printed ones); the curve states t as
 *     "tolerance" and the traced count as "points".
 *   the drawn mesh polylines, when the features are given a drawing tolerance t > 0
 *     (ism_features.draw_tol; the pipeline's is ISM_FEATURES_DRAW_TOL_REL x the mesh's bound
 *     E, or x the finest cell's edge on the depth path; stated as the top-level "tolerance"):
 *     - crease arcs ("curves"[k].arcs of kind crease: the cut the pipeline adds where f's
 *       top min/max changes branch, not a curve the request asked for), boundaries, and the
 *       nonmanifold_edges chains with every edge on the locus (on_locus, off_edges empty:
 *       the singular curve is drawn from "curves"; the viewer draws none of these chains;
 *       every chain when the mesh was not checked against a locus): each thinned to the
 *       mesh vertices that keep every other one within t - ISM_FEATURES_ROUNDING(d) of the
 *       polyline through them (polyline_thin.h); counts.boundary_edges and
 *       counts.nonmanifold_edges still count the mesh's edges;
 *     - every mesh position printed (those, the other nonmanifold_edges chains, which keep
 *       every vertex so that off_edges index them, nonmanifold_points): with
 *       d = ism_features_decimals(t / 2) decimals.
 *     So every printed point lies within ISM_FEATURES_ROUNDING(d) <= t / 2 of its mesh vertex,
 *     and every vertex of a thinned chain within t of the printed polyline. A crease curve
 *     states t as its "tolerance" too. The mesh's own chains, every vertex in full, travel in
 *     the .obj (`l` lines of groups crease_curves, nonmanifold_curves, boundaries) and the
 *     .glb (LINES). At t = 0 (isomesh -e's features) mesh positions print as float32 (below)
 *     and crease arcs in full, as the requested curves' arcs always do (their points are
 *     within the curve tolerance 1e-10 x diagonal of the curve the request named).
 *   every other double: the shortest text that reads back to the same double.
 *   mesh positions at t = 0 and the arrangement's and curve ends' vertices: the shortest text
 *     that reads back to the same float32.
 * Only the printed text changes: the computed entry keeps full doubles, so its version and the
 * features version stay. */
#define ISM_FEATURES_MAX_DECIMALS 17 /* what %.*f can carry of a double near 1 */
/* How far printing a point's three coordinates with d decimals can move it. */
#define ISM_FEATURES_ROUNDING(d) (0.8660254037844386 * pow(10.0, -(d)))

/* The drawing tolerance, relative to the mesh's bound E (ism_features.draw_tol = this x E).
 * The mesh lies within E of the surface; a polyline drawn within E / 10 of the mesh's is well
 * inside that, and at the default bound (E = 1e-3 x diagonal) it is about a fifth of a pixel
 * of a 1,000-pixel view of the box (the .drc's 14-bit positions move vertices by up to
 * diagonal / 2^15, E / 33). Measured (session 20, features JSON gzipped beside the default
 * .drc): gyroid-ball's crease of 6,376 vertices in full digits made the features 101% of the
 * .drc; thinned within E / 10 (1,369 points at 4 decimals) 6.3%, within E / 4 4.1%, within E
 * 2.1%; cube-minus-ball 22.5% -> 7.8%. */
#define ISM_FEATURES_DRAW_TOL_REL 0.1

/* The fewest decimals d (0..ISM_FEATURES_MAX_DECIMALS) with ISM_FEATURES_ROUNDING(d) <= tol;
 * -1 when tol is not finite and > 0, or finer than that (print in full). */
int ism_features_decimals(double tol);

#include <math.h>
#include <stddef.h>
#include <stdint.h>
#include <stdbool.h>
#include "core/mesh/mesh.h"
#include "core/analysis/analysis.h"
#include "core/singular/check.h"
#include "core/singular/locus.h"
#include "core/curves/arrangement.h"

/* Polylines over vertex indices: line i is verts[start[i] .. start[i+1]); closed when its
 * first and last vertex are the same. */
typedef struct ism_polylines {
    size_t n;
    uint32_t *start;           /* n + 1 entries */
    uint32_t *verts;
} ism_polylines;

void ism_polylines_free(ism_polylines *p);

typedef struct ism_features {
    ism_polylines curves;      /* non-manifold curves (a copy of the analysis's) */
    ism_polylines boundaries;  /* boundary chains (a copy of the analysis's) */
    size_t npoints;
    uint32_t *points;          /* non-manifold points (vertex indices) */
    uint8_t *point_kind;       /* enum ism_point_kind per point */
    uint8_t *point_class;      /* vertex class per point */
    const ism_locus *locus;    /* the singular locus found from f (not owned; may be NULL) */
    const ism_locus_check *check; /* the mesh checked against it (not owned; may be NULL) */
    const ism_arrangement *arrangement; /* requested curves cut into the mesh (not owned;
                                           NULL when none were asked) */
    const ism_cut_fn *cut_fns;  /* the functions arrangement's curves come from */
    ism_polylines arcs;        /* the requested curves' arcs (arrangement edges), mesh vertices */
    uint8_t *arc_kind;         /* per arc: enum ism_cut_kind */
    uint32_t *arc_curve;       /* per arc: its curve (the order of the requested curves in the
                                  features JSON) */
    double draw_tol;           /* > 0: the drawn mesh polylines thinned and rounded within it
                                  (the digits table above); 0: printed in full */
} ism_features;

/* Collects the features of a mesh from its analysis a (NULL for an empty mesh: every list
 * stays empty): non-manifold curves and points, boundary chains. False when out of memory. */
bool ism_features_build(const ism_analysis *a, ism_features *f);
void ism_features_free(ism_features *f);

/* The features JSON above (f->locus and f->check are read when set). malloc'd, NULL when out
 * of memory. */
char *ism_features_json(const ism_mesh *m, const ism_features *f, size_t *len);

/* The locus's counts as members of the open JSON object w: "singular_points", "certified",
 * "uncertified", "by_type" {node, isolated, ...}, "curves", "double_curves",
 * "whisker_curves", "double_sheets" (l may be NULL: all 0). Shared by features and stats. */
struct ism_jw;
/* features_curves.c: the requested curves as items of the open "curves" array (kinds
 * section, level, intersection, silhouette, crease; "arcs" polylines in full precision, the
 * crease's within tol with d decimals when tol > 0 (ism_features_json's: the digits table
 * above), "ends"), and
 * the "arrangement" object (vertices, edges, faces with triangle ranges of m's order, area,
 * euler, boundary cycles; components; euler {mesh, arrangement, ok}). */
void ism_features_cut_curves_json(struct ism_jw *w, const ism_mesh *m,
                                  const ism_arrangement *a, const ism_cut_fn *fns,
                                  double tol, int d);
void ism_features_arrangement_json(struct ism_jw *w, const ism_mesh *m,
                                   const ism_arrangement *a);
void ism_locus_counts_json(struct ism_jw *w, const ism_locus *l);

/* The mesh polyline verts[0..n) as a JSON array of x0, y0, z0, ... (features.h's digits
 * table): thinned by ism_polyline_thin within tol - ISM_FEATURES_ROUNDING(d) when tol > 0
 * (d >= 0 then), each coordinate with d decimals when d >= 0, else in full (full_doubles) or
 * as float32. Out of memory fails w. */
void ism_features_chain_xyz(struct ism_jw *w, const ism_mesh *m, const uint32_t *verts,
                            size_t n, double tol, int d, bool full_doubles);

/* Copies a's edges into f->arcs, arc_kind (from fns) and arc_curve, for the formats that draw
 * them (glb LINES, OBJ `l`). False when out of memory. */
bool ism_features_add_arcs(ism_features *f, const ism_arrangement *a, const ism_cut_fn *fns);

/* Name of a requested curve's kind (enum ism_cut_kind): "section", "level", ... */
const char *ism_cut_kind_name(int kind);

/* Name of a point kind ("cones", "curve_end", "junction"). */
const char *ism_point_kind_name(int kind);

#endif
