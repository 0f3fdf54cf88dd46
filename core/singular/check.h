/* check.h — the mesh checked against the singular locus found from f: every non-manifold
 * element of the mesh (an edge of three or more triangles, a vertex where several cones of
 * faces meet, the ends and junctions of non-manifold chains) should lie on the locus; one
 * that does not is an artefact of the polygoniser, counted, never hidden. */
#ifndef ISM_LOCUS_CHECK_H
#define ISM_LOCUS_CHECK_H

#include <stddef.h>
#include <stdint.h>
#include <stdbool.h>
#include "core/analysis/analysis.h"
#include "core/mesh/mesh.h"
#include "core/singular/locus.h"

/* A mesh element is on the locus when it lies within this fraction of the box diagonal of a
 * singular point or of a chord of a curve's traced polyline, plus that chord's own bulge
 * (check.c: step² × curvature / 4, twice the sagitta; a chord of 0.01 on a circle of
 * radius 1 is 1.25e-5 from the arc, more than this fraction of a diagonal of 5). Conformed
 * vertices sit within 1e-9 × diagonal (locus.h); the margin is for the traced points. */
#define ISM_LOCUS_ON_REL 1e-6

typedef struct ism_locus_check {
    size_t nonmanifold_edges;       /* mesh edges of three or more triangles */
    size_t nonmanifold_edges_off;   /* ... with an end off the locus (artefacts) */
    size_t nonmanifold_points;      /* the analysis's points (cones, curve ends, junctions) */
    size_t nonmanifold_points_off;  /* ... off the locus (artefacts) */
    size_t artefacts;               /* the two _off counts added */
    uint8_t *curve_on;              /* per analysis curve (a->ncurves): 1 when every vertex
                                       of the chain is on the locus */
    uint8_t *curve_vert_on;         /* per chain vertex (as a->curve_verts, a->curve_start[
                                       a->ncurves] of them): 1 when on the locus; a chain's
                                       edge is off (counted) when either end is off */
    uint8_t *point_on;              /* per analysis point (a->npoints) */
    /* For each singular point of the locus: the mesh vertex at its position (within the
     * tolerance) or UINT32_MAX, and the number of cones of faces there (0 without vertex). */
    uint32_t *point_vertex;
    int *point_cones;
} ism_locus_check;

/* Checks the analysed mesh (a is ism_analyse's result for m) against the locus l found in
 * box (xmin ymin zmin xmax ymax zmax). Cost: O(V + T + P + S) for V vertices, T triangles,
 * P singular points and S curve segments (grids over the points and the segments; one pass
 * over the vertices and one over the triangles). False when out of memory (err says so);
 * out is then empty. */
bool ism_locus_check_mesh(const ism_locus *l, const double box[6], const ism_mesh *m,
                          const ism_analysis *a, ism_locus_check *out, ism_error *err);

void ism_locus_check_free(ism_locus_check *c);

#endif
