/* remesh_types.h — the data the quality pass (remesh.h) takes and hands back: its options,
 * its statistics and the renumbering of the mesh. Types only, so the pass's own steps
 * (rm_pass.h) share them without depending on the driver. */
#ifndef ISM_REMESH_TYPES_H
#define ISM_REMESH_TYPES_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>
#include "core/expr/expr.h"

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
    bool measure_all_centroids;    /* the reference path: every centroid a check asks about is
                                      measured (no per-triangle record, rm_cbound.h and,
                                      under max_error, rm_brec.h); the
                                      meshes are the same (tests compare) */
} ism_remesh_options;

typedef struct ism_remesh_stats {
    size_t flips, moves;           /* edge flips made (with a junction's fan mended, each a
                                      flip that moves two vertices too: rm_junction_fan.c),
                                      vertex moves accepted */
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

#endif
