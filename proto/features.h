/* features.h — the non-manifold structure that must travel beside the triangles, because
 * Draco splits vertices along non-manifold edges and drops degenerate faces: the analysis's
 * non-manifold curves and points (with their vertex class), and the boundary chains. The
 * viewer gets it as the "features" JSON next to a .drc (GET /v1/meshes/{key}/features) and as
 * LINES / POINTS primitives inside a .glb.
 *
 * Features JSON (version 1; coordinates are the float32 positions before quantisation):
 *   {"version": 1,
 *    "classes": ["manifold", "boundary", "nonmanifold_edge", "nonmanifold_point", "isolated"],
 *    "curves":     [{"closed": bool, "xyz": [x0, y0, z0, x1, y1, z1, ...]}, ...],
 *    "points":     [{"xyz": [x, y, z], "class": 2|3, "kind": "cones"|"curve_end"|"junction"}],
 *    "boundaries": [{"closed": bool, "xyz": [...]}, ...],
 *    "counts": {"curves", "curve_edges", "points", "boundaries", "boundary_edges"}}
 * "class" is the vertex class (index into "classes", the same numbers as the Draco "class"
 * attribute); a curve's consecutive points are joined by non-manifold edges. */
#ifndef ISM_FEATURES_H
#define ISM_FEATURES_H

#include <stddef.h>
#include <stdint.h>
#include <stdbool.h>
#include "core/mesh/mesh.h"
#include "core/analysis/analysis.h"

/* Polylines over vertex indices: line i is verts[start[i] .. start[i+1]); closed when its
 * first and last vertex are the same. */
typedef struct ism_polylines {
    size_t n;
    uint32_t *start;           /* n + 1 entries */
    uint32_t *verts;
} ism_polylines;

void ism_polylines_free(ism_polylines *p);

/* Chains the boundary edges of m (edges of exactly one triangle; triangles with a repeated
 * index are ignored) into polylines following the triangles' winding: closed loops, and open
 * chains where a boundary meets a non-manifold vertex. O(triangles). False when out of
 * memory. */
bool ism_boundary_chains(const ism_mesh *m, ism_polylines *out);

typedef struct ism_features {
    ism_polylines curves;      /* non-manifold curves (a copy of the analysis's) */
    ism_polylines boundaries;
    size_t npoints;
    uint32_t *points;          /* non-manifold points (vertex indices) */
    uint8_t *point_kind;       /* enum ism_point_kind per point */
    uint8_t *point_class;      /* vertex class per point */
} ism_features;

/* Collects the features of m from its analysis a (a may be NULL: curves and points then
 * stay empty, boundaries are still chained). Boundaries are skipped when a says there are no
 * boundary edges. False when out of memory. */
bool ism_features_build(const ism_mesh *m, const ism_analysis *a, ism_features *f);
void ism_features_free(ism_features *f);

/* The features JSON above. malloc'd, NULL when out of memory. */
char *ism_features_json(const ism_mesh *m, const ism_features *f, size_t *len);

/* Name of a point kind ("cones", "curve_end", "junction"). */
const char *ism_point_kind_name(int kind);

#endif
