/* remesh.h — the quality pass (issue 15 item 4): better-shaped triangles on the same surface,
 * the mesh saying the same things. Within each manifold patch it flips edges toward Delaunay
 * (Lawson) and relaxes vertices in the tangent plane (towards the area-weighted centroid of
 * their triangles), putting every moved vertex back on f = 0 by Newton along ∇f. Protected,
 * never flipped or moved: boundary and non-manifold edges, edges between differently
 * labelled triangles or given as locked (curves), crease edges (a sharp dihedral that is no
 * fold), vertices on any of them, vertices where several cones meet, where ∇f vanishes, and
 * the vertex at each given point (singular points). Needles and caps that flips and moves
 * cannot mend lose an edge by collapse (a free vertex merged into a neighbour, where the
 * link condition holds: the topology is kept), and the mesh is renumbered after; each
 * triangle keeps its label, features keep their vertices, so χ, components, non-manifold
 * edges and points and boundary loops cannot change. */
#ifndef ISM_REMESH_H
#define ISM_REMESH_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>
#include "core/expr/expr.h"
#include "core/mesh/mesh.h"

typedef struct ism_remesh_options {
    const ism_tape *f;             /* the surface (required) */
    double max_error;              /* > 0: a flip never puts its new edge's midpoint farther
                                      than max(this, the old edge's) from f = 0 (0: the old
                                      edge's distance is the bound) */
    const uint32_t *tri_label;     /* per triangle, or NULL: flips only between equal labels */
    const uint32_t *locked_edges;  /* 2 vertex indices per edge never flipped (curves) */
    size_t nlocked_edges;
    const double *locked_points;   /* 3 per point: its nearest vertex stays where it is
                                      (singular points) */
    size_t nlocked_points;
    const volatile int *cancel;    /* polled between sweeps; non-zero stops early (the mesh is
                                      valid after every sweep) */
} ism_remesh_options;

typedef struct ism_remesh_stats {
    size_t flips, moves;           /* edge flips made, vertex moves accepted */
    size_t collapses;              /* edges collapsed (each removes a vertex, two triangles) */
    size_t inserts;                /* vertices inserted beside a needle's short feature edge
                                      (each adds two triangles) */
    size_t locked_vertices;        /* vertices the pass left alone */
    double min_angle_before, min_angle_after; /* degrees, over non-degenerate triangles */
    double time_ms;
} ism_remesh_stats;

/* An index of the mesh before the pass that the pass removed. */
#define ISM_REMESH_GONE UINT32_MAX

/* How the pass renumbered the mesh, for whatever the caller keeps beside it by index (curve
 * edges, triangle ranges and labels). Vertices before the pass keep their order (those
 * collapsed away are gone), inserted ones follow them; each triangle after the pass lies in
 * one triangle before it (itself when kept, the one split otherwise), its origin, and the
 * triangles are ordered by origin, so a range of triangles before is a range after. */
typedef struct ism_remesh_renumber {
    uint32_t *vert;                /* per vertex before: its index after, or ISM_REMESH_GONE */
    uint32_t *origin;              /* per triangle after: its origin (non-decreasing) */
    size_t nverts, ntris;          /* the counts before the pass */
    size_t ntris_after;
} ism_remesh_renumber;

void ism_remesh_renumber_free(ism_remesh_renumber *ren);

/* Runs the pass on m in place: positions, normals and the triangles' corners change, and
 * collapses remove vertices and triangles (the segments are renumbered with them); ren (may
 * be NULL) gets the renumbering. False with err set when out of memory or f is missing; m is
 * then still a valid mesh of the surface (possibly partly improved), and ren says how it was
 * renumbered. */
bool ism_remesh_quality(ism_mesh *m, const ism_remesh_options *o, ism_remesh_stats *st,
                        ism_remesh_renumber *ren, ism_error *err);

/* The smallest angle (degrees) over m's non-degenerate triangles; 90 for none. */
double ism_remesh_min_angle(const ism_mesh *m);

#endif
