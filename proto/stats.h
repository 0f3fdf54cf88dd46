/* stats.h — the stats JSON that accompanies every mesh: the key, what was sent (format,
 * bytes, empty or not), the polygoniser's counters and phase times, the analysis's figures
 * (edges, classes, topology, curvature integrals, triangle quality, distance to f = 0), the
 * timings of each pipeline phase, and warnings for the cases the algorithm could not resolve.
 *
 *   {"key", "mesher", "version", "format", "bytes", "features_bytes", "empty",
 *    "mesh": {"vertices", "triangles", "encoded_points", "encoded_faces"},
 *    "polygoniser": {"mesher": "primal" | "straddle" | "dual", "dual_declined": null or a
 *                    reason (core/octree/mesher.h's table), ... ism_poly_stats fields ...,
 *                    "time_ms": {"octree", "polygons",
 *                    "cracks", "mesh", "total"}},
 *    "analysis": {..., "accuracy": {"max_dist_vertex", ..., "max_error", "met"}},
 *    "singular": {locus counts (features.h), "artefacts", "nonmanifold_edges_off",
 *                 "nonmanifold_points_off", "incomplete", "boxes_visited", "evals_interval",
 *                 "evals_jet" (every Hessian taken, spent projection runs' too: see locus.h),
 *                 "time_ms", "conform": {points_conformed, points_failed,
 *                 points_short_cones, curves_conformed, curves_kept, curves_failed,
 *                 loops_fallback, triangles_removed, triangles_added, time_ms}},
 *    "simplify": {"triangles_before", "triangles_after", "collapses", "flips", "moves",
 *                 "rounds", "locked_vertices", "min_angle_before", "min_angle_after",
 *                 "time_ms", "stopped"} (only after the simplification),
 *    "remesh": {"flips", "moves", "collapses", "inserts", "locked_vertices",
 *               "min_angle_before", "min_angle_after", "time_ms"} (only after the quality
 *               pass),
 *    "preview": {"skipped": ["singular", "curves", "quality", "analysis", "features"],
 *               "thin_search": "coarse"} (only in a preview: the stages it did not run, and
 *               its hidden-piece search: whole nodes only, ism_poly_options.thin_coarse),
 *    "timings_ms": {"decode", "compile", "singular", "polygonise", "analyse", "features",
 *    "encode", "total"}, "warnings": ["..."]}
 * (timings_ms comes right after "mesh"; the members from "polygoniser" on are the surface's,
 * the same for every encoding of it; the timings of a mesh encoded from a stored computed
 * surface are the computation's, with its own "encode"). */
#ifndef ISM_STATS_H
#define ISM_STATS_H

#include <stddef.h>
#include <stdbool.h>
#include "core/analysis/analysis.h"
#include "core/octree/polygonise.h"
#include "core/remesh/remesh.h"
#include "core/remesh/simplify.h"
#include "core/singular/check.h"
#include "core/singular/conform.h"
#include "core/singular/locus.h"

enum ism_timing { ISM_TIME_DECODE, ISM_TIME_COMPILE, ISM_TIME_SINGULAR, ISM_TIME_POLYGONISE, ISM_TIME_ANALYSE, ISM_TIME_FEATURES,
                  ISM_TIME_ENCODE, ISM_TIME_TOTAL, ISM_TIME_COUNT };

typedef struct ism_stats_input {
    const char *key;
    const char *format;
    size_t bytes, features_bytes;
    bool empty;
    size_t vertices, triangles;           /* of the polygoniser's mesh */
    size_t encoded_points, encoded_faces; /* what a Draco decoder gets (0 for other formats) */
    const ism_poly_stats *poly;           /* may be NULL */
    const ism_analysis *analysis;         /* may be NULL */
    const ism_locus *locus;               /* the singular locus from f (may be NULL) */
    const ism_locus_check *check;         /* the mesh checked against it (may be NULL) */
    const ism_conform_stats *conform;     /* what the conformance pass did (may be NULL) */
    double max_error;                     /* the requested error bound; 0 when none */
    const ism_remesh_stats *remesh;       /* the quality pass ("quality": "good"), or NULL */
    const ism_simplify_stats *simplify;   /* the simplification (under max_error), or NULL */
    bool preview;                         /* a preview: the stages it skips are listed */
    double timings_ms[ISM_TIME_COUNT];
    const char *surface;                  /* ism_stats_surface_json's text, or NULL: then */
    size_t surface_len;                   /* it is written from poly ... conform */
} ism_stats_input;

/* The members that do not depend on the encoding ("polygoniser", "analysis", "singular",
 * "warnings") as one JSON object: kept with the computed surface (proto/computed.h) and
 * spliced into the stats of each encoding of it. malloc'd; NULL when out of memory. */
char *ism_stats_surface_json(const ism_stats_input *in, size_t *len);

/* The whole stats JSON: key ... mesh, timings_ms, then the surface members. malloc'd JSON
 * text; NULL when out of memory. */
char *ism_stats_json(const ism_stats_input *in, size_t *len);

#endif
