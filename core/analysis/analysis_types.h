/* analysis_types.h — the data an analysis fills: vertex classes, point kinds, the options and
 * the ism_analysis record (see analysis.h for the conventions and the calls). Types only, so
 * the passes in core/analysis include this and never the header that declares the driver.
 *
 * The fields below are the contract with proto/ (encoders, stats JSON) and the viewer:
 * extend freely, but keep these names and meanings. */
#ifndef ISM_ANALYSIS_TYPES_H
#define ISM_ANALYSIS_TYPES_H

#include <stddef.h>
#include <stdint.h>
#include <stdbool.h>

/* Per-vertex class (one byte per vertex; the viewer colours by it). When several apply, the
 * first in this order wins: isolated, non-manifold edge, non-manifold point, boundary,
 * manifold. */
enum ism_vertex_class {
    ISM_VERTEX_MANIFOLD = 0,          /* one cone of faces, all its edges manifold */
    ISM_VERTEX_BOUNDARY = 1,          /* on a boundary edge (and one cone of faces) */
    ISM_VERTEX_NONMANIFOLD_EDGE = 2,  /* on an edge with more than two triangles */
    ISM_VERTEX_NONMANIFOLD_POINT = 3, /* several cones meet here, no non-manifold edge (a
                                         Kummer node, two sheets touching at a point, two
                                         open fans sharing a boundary vertex) */
    ISM_VERTEX_ISOLATED = 4,          /* in no triangle (or only in collapsed ones) */
};
#define ISM_VERTEX_CLASSES 5

/* Why a vertex is listed in points[]. */
enum ism_point_kind {
    ISM_POINT_CONES = 0,     /* class 3: several cones of faces meet at the vertex */
    ISM_POINT_CURVE_END = 1, /* one non-manifold edge ends here (a curve's free end) */
    ISM_POINT_JUNCTION = 2,  /* three or more non-manifold edges meet (curves branch) */
};

#define ISM_ANGLE_BINS 18 /* smallest-angle histogram: 18 bins of 5 degrees, 0..90 */

typedef struct ism_analysis_options {
    bool curvature;      /* evaluate the Hessian at every vertex (needs f) (default on) */
    bool accuracy;       /* |f|/|∇f| and Newton distances (needs f) (default on) */
    bool project;        /* move manifold vertices onto f = 0 along ∇f (off by default).
                            ism_analyse never moves anything (its mesh is const): a caller
                            that sets this runs ism_analysis_project and then analyses the
                            moved mesh again. */
    int threads;         /* threads the analysis runs in all, its side thread included
                          * (0 = online cores; at most 64) */
    double singular_rel; /* |∇f| <= singular_rel * gradient_scale counts as vanishing
                            (default 1e-6); see gradient_scale below */
    int newton_steps;    /* Newton steps for the projection distance and projection (4) */
    double max_error;    /* the bound the mesh was made under (0: none, the default): the
                            distances between vertices whose first-order estimate lies just
                            within it are measured a Newton step further (accuracy.c), as
                            the polygoniser measured them, for the largest distances only
                            (max_dist_midpoint, max_dist_centroid), so "met" holds them to
                            E; the means and 99th percentiles are the first-order figures
                            whatever the bound, the same bits with it or without */
} ism_analysis_options;

/* One connected component (triangles joined by shared edges, of any kind). */
typedef struct ism_component {
    size_t triangles, edges, vertices; /* a vertex shared by two components counts in each */
    long euler;                        /* vertices - edges + triangles of this component */
    size_t boundary_edges, nonmanifold_edges;
    size_t boundary_loops;             /* closed boundary loops (see boundary_loops below) */
    size_t boundary_chains;            /* boundary chains ending on non-manifold edges */
    bool closed;                       /* no boundary edge */
    bool manifold;                     /* no non-manifold edge, and no vertex with two of its
                                          cones in this component (two components may touch
                                          at a vertex and each still be a manifold) */
    bool orientable;                   /* consistently orientable across its manifold edges */
    long genus;                        /* manifold, orientable and every boundary chain closed:
                                          (2 - euler - boundary_loops) / 2 — for a closed
                                          component the usual genus; else -1 */
    uint32_t first_triangle;           /* smallest triangle index (components are listed in
                                          this order) */
} ism_component;

typedef struct ism_analysis {
    /* edges */
    size_t edges, boundary_edges, manifold_edges, nonmanifold_edges;

    /* vertices */
    size_t nverts;
    uint8_t *vertex_class;            /* nverts entries, enum ism_vertex_class */
    size_t nonmanifold_vertices;      /* classes 2 and 3 */
    size_t class_count[ISM_VERTEX_CLASSES]; /* vertices of each class */

    /* Non-manifold edges chained into polylines: curve i runs over vertex indices
     * curve_verts[curve_start[i] .. curve_start[i+1]) (closed when first == last).
     * Chains pass through vertices with exactly two non-manifold edges and break at every
     * other vertex (ends and junctions). First the chains that start at an end point or
     * junction, by that vertex's index (then by edge order around it), then the closed
     * loops with no such vertex, each starting at its smallest vertex, by that index. */
    size_t ncurves;
    uint32_t *curve_start;            /* ncurves + 1 entries */
    uint32_t *curve_verts;

    /* Non-manifold points: vertices where several cones meet (class 3) and the end points
     * / junctions of non-manifold curves where curves branch. Ascending vertex index. */
    size_t npoints;
    uint32_t *points;                 /* vertex indices */
    uint8_t *point_kind;              /* npoints entries, enum ism_point_kind */
    double *point_pos;                /* 3 per point: the vertex position */

    /* topology */
    long euler;                       /* V - E + F (V counts vertices used by triangles) */
    size_t components;                /* connected by shared edges */
    size_t boundary_loops;
    bool orientable;                  /* every component consistently orientable */
    size_t inconsistent_edges;        /* manifold edges whose two triangles run the same way
                                         (a mesh can be orientable yet not oriented) */
    long genus;                       /* for a single closed orientable manifold mesh, else -1 */
    size_t vertices_used, triangles_used; /* V and F of the Euler characteristic */
    size_t collapsed_triangles;       /* triangles with a repeated vertex index (ignored) */
    size_t duplicate_triangles;       /* triangles with the same three vertices as another
                                         (counted once per extra copy; they do take part in
                                         the topology and make their edges non-manifold) */
    size_t vertex_components;         /* connected by shared vertices (a Kummer node joins) */
    size_t boundary_chains;           /* boundary chains that end on a non-manifold edge
                                         instead of closing into a loop. Boundary edges are
                                         chained by walking each end vertex's cone of faces
                                         to the next boundary edge; boundary_loops counts the
                                         chains that close. */
    ism_component *component;         /* components entries */
    /* The boundary chains as polylines, in the shape of the curves above: chain i runs over
     * boundary_verts[boundary_start[i] .. boundary_start[i+1]) (closed when first == last),
     * the way its first edge's triangle runs it; loops first-found by edge order. */
    size_t nboundaries;               /* boundary_loops + boundary_chains */
    uint32_t *boundary_start;         /* nboundaries + 1 entries */
    uint32_t *boundary_verts;

    /* curvature from f (NULL when not asked for); finite everywhere: 0 where singular.
     * Sign: mean = (|g|² tr H - g H gᵀ) / (2|g|³) = div(∇f/|∇f|) / 2, so a surface bending
     * away from the side ∇f points to is positive: x²+y²+z²-r² has mean +1/r (and
     * r²-x²-y²-z² has -1/r). Gaussian = -det([[H, gᵀ], [g, 0]]) / |g|⁴ (Goldman 2005),
     * independent of the sign of f. k1,2 = mean ± sqrt(max(mean² - K, 0)). Values are
     * clamped to ±1e30. */
    float *mean_curvature;
    float *gauss_curvature;
    float *k1, *k2;                   /* principal curvatures, k1 >= k2 */
    uint8_t *singular;                /* 1 where |∇f| vanishes (curvature undefined), also
                                         where f or its derivatives are not finite there.
                                         Filled whenever f is given and curvature or accuracy
                                         is asked for. */
    size_t singular_vertices;
    double total_gauss;               /* sum over vertices of K * (area / 3), ≈ ∫K dA */
    double total_abs_gauss;           /* sum of |K| * vertex_area (the scale of total_gauss) */
    double area;
    double *vertex_area;              /* nverts: one third of the incident triangle areas */

    /* The function's scale: the median of |∇f| over the vertices used by triangles (0 when
     * f was not evaluated). |∇f| <= singular_threshold = singular_rel * gradient_scale is
     * "vanishing" (singular vertex; centroid left out of the distance figures). */
    double gradient_scale, singular_threshold;

    /* triangle quality: smallest angle of each triangle, in degrees. Statistics cover the
     * triangles that are not degenerate; a triangle is degenerate when collapsed or when
     * |AB × AC| <= 1e-12 * (longest side)² (zero area up to rounding). */
    double min_angle, median_angle, share_under_10;
    uint64_t angle_hist[ISM_ANGLE_BINS];
    size_t degenerate_triangles;      /* zero area */
    /* aspect ratio of each non-degenerate triangle: longest side / (2 √3 × inradius), 1 for
     * an equilateral triangle, growing without bound as it flattens (= longest side ×
     * perimeter / (4 √3 area)); the largest, the mean and the 99th percentile (rank
     * floor(0.99 (n - 1)) ascending) */
    double aspect_max, aspect_mean, aspect_p99;
    float *triangle_min_angle;        /* ntris entries (0 for degenerate triangles) */

    /* accuracy: distance estimates |f| / |∇f| at vertices, edge midpoints and triangle
     * centroids (the mesh between its vertices; there capped by the bound through the
     * element's corners, |p − v| + v's distance: dist_bound.h), each with its maximum, mean
     * and 99th percentile (the value at rank floor(0.99 (n - 1)) in ascending order), and the
     * Newton projection distance. At midpoints and centroids the estimates that could be the
     * maximum or the 99th percentile are measured again by finding the surface near them
     * (accuracy.c, nearest.h): beside singular points and curves the estimate overstates.
     * Points where |∇f| vanishes are left out (counted in
     * accuracy_skipped). The Newton distance iterates p -= f ∇f / |∇f|² (newton_steps times,
     * stopping early where ∇f vanishes) and measures how far p moved. */
    double max_dist_vertex, mean_dist_vertex, p99_dist_vertex;
    double max_dist_midpoint, mean_dist_midpoint, p99_dist_midpoint;
    double max_dist_centroid, mean_dist_centroid, p99_dist_centroid;
    double max_newton_dist, mean_newton_dist;
    size_t accuracy_skipped;
    float *distance;                  /* nverts: |f|/|∇f| at each vertex (0 where singular);
                                         NULL when accuracy is not asked for */
} ism_analysis;

#endif
