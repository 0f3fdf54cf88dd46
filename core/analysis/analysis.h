/* analysis.h — what a mesh says about its surface: manifold / boundary / non-manifold edges
 * and vertices (cones of faces, Pérez-Aquila & Aguilera 2003), non-manifold curves and points,
 * topology, curvature from the implicit function, triangle quality and distance to f = 0.
 *
 * The fields below are the contract with proto/ (encoders, stats JSON) and the viewer:
 * extend freely, but keep these names and meanings. */
#ifndef ISM_ANALYSIS_H
#define ISM_ANALYSIS_H

#include <stddef.h>
#include <stdint.h>
#include <stdbool.h>
#include "core/mesh/mesh.h"
#include "core/expr/expr.h"

/* Per-vertex class (one byte per vertex; the viewer colours by it). */
enum ism_vertex_class {
    ISM_VERTEX_MANIFOLD = 0,          /* one cone of faces, all its edges manifold */
    ISM_VERTEX_BOUNDARY = 1,          /* on a boundary edge */
    ISM_VERTEX_NONMANIFOLD_EDGE = 2,  /* on an edge with more than two triangles */
    ISM_VERTEX_NONMANIFOLD_POINT = 3, /* several cones meet here, no non-manifold edge */
    ISM_VERTEX_ISOLATED = 4,          /* in no triangle */
};

#define ISM_ANGLE_BINS 18 /* smallest-angle histogram: 18 bins of 5 degrees, 0..90 */

typedef struct ism_analysis_options {
    bool curvature;      /* evaluate the Hessian at every vertex (needs f) */
    bool accuracy;       /* |f|/|∇f| and Newton distances (needs f) */
    bool project;        /* move manifold vertices onto f = 0 along ∇f (off by default) */
} ism_analysis_options;

void ism_analysis_options_default(ism_analysis_options *o);

typedef struct ism_analysis {
    /* edges */
    size_t edges, boundary_edges, manifold_edges, nonmanifold_edges;

    /* vertices */
    size_t nverts;
    uint8_t *vertex_class;            /* nverts entries, enum ism_vertex_class */
    size_t nonmanifold_vertices;      /* classes 2 and 3 */

    /* Non-manifold edges chained into polylines: curve i runs over vertex indices
     * curve_verts[curve_start[i] .. curve_start[i+1]) (closed when first == last). */
    size_t ncurves;
    uint32_t *curve_start;            /* ncurves + 1 entries */
    uint32_t *curve_verts;

    /* Non-manifold points: vertices where several cones meet (class 3) and the end points
     * / junctions of non-manifold curves where curves branch. */
    size_t npoints;
    uint32_t *points;                 /* vertex indices */

    /* topology */
    long euler;                       /* V - E + F (V counts vertices used by triangles) */
    size_t components;                /* connected by shared edges */
    size_t boundary_loops;
    bool orientable;                  /* every component consistently orientable */
    long genus;                       /* for a single closed orientable manifold mesh, else -1 */

    /* curvature from f (NULL when not asked for); finite everywhere: 0 where singular */
    float *mean_curvature;
    float *gauss_curvature;
    float *k1, *k2;                   /* principal curvatures, k1 >= k2 */
    uint8_t *singular;                /* 1 where |∇f| vanishes (curvature undefined) */
    size_t singular_vertices;
    double total_gauss;               /* sum over vertices of K * (area / 3), ≈ ∫K dA */
    double area;

    /* triangle quality: smallest angle of each triangle, in degrees */
    double min_angle, median_angle, share_under_10;
    uint64_t angle_hist[ISM_ANGLE_BINS];
    size_t degenerate_triangles;      /* zero area */

    /* accuracy: distance estimates |f| / |∇f| and Newton projection distance */
    double max_dist_vertex, mean_dist_vertex;
    double max_dist_centroid, mean_dist_centroid;
    double max_newton_dist;
} ism_analysis;

/* Analyses m. f may be NULL (then curvature and accuracy are skipped). Returns false on
 * allocation failure (err says so). a must be released with ism_analysis_free. */
bool ism_analyse(const ism_mesh *m, const ism_tape *f, const ism_analysis_options *o,
                 ism_analysis *a, ism_error *err);

void ism_analysis_free(ism_analysis *a);

#endif
