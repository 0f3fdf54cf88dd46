/* wire_mesh.h — a mesh as it goes on the wire: float32 positions, unit normals everywhere
 * (where ∇f vanished, the area-weighted normal of the vertex's triangles), curvature clamped
 * to what the mesh can resolve, the per-vertex class, the per-triangle labels (cell, double
 * sheet) and whether anything is left to draw.
 * Shared by the Draco and glTF encoders. */
#ifndef ISM_WIRE_MESH_H
#define ISM_WIRE_MESH_H

#include <stddef.h>
#include <stdint.h>
#include <stdbool.h>
#include "core/mesh/mesh.h"
#include "core/analysis/analysis.h"
#include "core/curves/cut_types.h"
#include "core/eval/eval.h"

typedef struct ism_wire_mesh {
    size_t nverts, ntris;
    const uint32_t *tri;       /* the mesh's triangles (not owned) */
    float *pos;                /* 3 per vertex */
    float *normal;             /* 3 per vertex, or NULL when not asked for */
    float *mean_curvature;     /* NULL when not asked for (or not computed) */
    float *gauss_curvature;
    const uint8_t *vertex_class; /* the analysis's (not owned); NULL when not asked for */
    const uint32_t *tri_cell;  /* per triangle: its arrangement cell (not owned); NULL none */
    const uint8_t *tri_sheet;  /* per triangle: 1 on a double sheet (not owned); NULL none */
    /* Sharp creases: the corners whose normal is not their vertex's (the side of a crease
     * whose branch is not the one ∇f took there), by corner index 3 t + k ascending, with a
     * unit normal each (not owned; ncorner_normals 0 when none or normals not sent). */
    size_t ncorner_normals;
    const uint32_t *corner_at;
    const float *corner_normal;
    /* Per corner of corner_at: 1 when its normal is its triangle's sheet normal at a vertex on
     * the singular locus (ism_wire_corner_normals), 0 for a crease side (not owned; NULL when
     * none is). The viewer's formats (drc, glb) split points there and the OBJ gives it a `vn`
     * of its own; the PLY keeps one row per mesh vertex everywhere (its vertex count is the
     * stats'): a crease vertex's row sums its sides' normals, the locus's marks are left out
     * of that sum. */
    const uint8_t *corner_locus;
    size_t live_triangles;     /* triangles whose three vertex indices differ */
    double bounds[6];          /* of the float positions: xmin ymin zmin xmax ymax zmax */
} ism_wire_mesh;

/* Builds the wire form. attrs is a set of enum ism_attr bits; a may be NULL (then no
 * curvature and no class are sent). Curvature is clamped to |H| <= curvature_limit and
 * |K| <= curvature_limit² (pass the mesh's resolution 1 / finest cell size; <= 0 for no
 * clamping). False when out of memory. */
bool ism_wire_mesh_build(const ism_mesh *m, const ism_analysis *a, unsigned attrs,
                         double curvature_limit, ism_wire_mesh *w);

void ism_wire_mesh_free(ism_wire_mesh *w);

/* A corner's normal is sent apart from its vertex's when they differ by more than this
 * angle (radians): 1e-3 is below what 10-bit octahedral normals resolve (~2e-3), so smooth
 * parts, where the branch gradient is ∇f to rounding, send none. */
#define ISM_CORNER_NORMAL_MIN_ANGLE 1e-3

/* The corners of w (built from m) whose branch normal (core/curves/crease_normals.h; cut:
 * the mesh's crease edges, NULL when none were cut) differs from the vertex's wire normal by
 * more than ISM_CORNER_NORMAL_MIN_ANGLE, into malloc'd *at / *normal (NULL, *n 0 when none,
 * or no normals in w). Corners at a vertex on the singular locus (∇f = 0 there: a double
 * curve's vertex is shared by two sheets, and its one normal — noise, or the average of
 * every sheet through it — shades the triangles beside the curve as saw teeth; issue 13)
 * that no crease side claims carry their own sheet's normal — one per half-sheet there
 * (proto/sheet_groups.h), the same float triple for each of its corners — marked 1 in
 * malloc'd *locus (per entry of *at; NULL when no entry is such a corner). an: m's analysis with f
 * evaluated (curvature or accuracy asked, so singular_vertices is counted), or NULL (a
 * preview): when it counts no singular vertex and f has no branches, nothing is looked
 * for. False when out of memory. */
bool ism_wire_corner_normals(const ism_tape *f, const ism_analysis *an, const ism_mesh *m,
                             const ism_cut *cut, const ism_wire_mesh *w, size_t *n,
                             uint32_t **at, float **normal, uint8_t **locus);

#endif
