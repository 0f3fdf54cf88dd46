/* cut.h — cutting a triangle mesh of f = 0 along curves f = 0, g = 0: triangles crossed by
 * g = 0 are split so mesh edges run along the curve, every new vertex put on both surfaces
 * by Newton (on three where two curves cross a mesh edge together). The curve is then the
 * set of cut edges. */
#ifndef ISM_CUT_H
#define ISM_CUT_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>
#include "core/curves/cut_fn.h"
#include "core/mesh/mesh.h"

/* A mesh edge lying on the curve of function fn. */
typedef struct ism_cut_edge {
    uint32_t a, b, fn;
    uint32_t branch[2]; /* a crease edge: the branches of f on its two sides (branches.h),
                           else ISM_CUT_NO_BRANCH */
} ism_cut_edge;

#define ISM_CUT_NO_BRANCH UINT32_MAX

typedef struct ism_cut {
    ism_cut_edge *edges;
    size_t nedges;
    size_t unrefined;      /* curve vertices Newton could not put on both surfaces (kept at
                              the linear estimate) */
    double worst_f, worst_g; /* largest |f|/|∇f|, |g|/|∇g| over the curve's vertices */
    uint32_t *tri_parent;  /* per triangle of the cut mesh: the triangle of the mesh before
                              the cut it lies in (labels of the polygoniser's triangles, such
                              as double-sheet ranges, follow through it); NULL before a cut */
} ism_cut;

void ism_cut_free(ism_cut *c);

/* Cuts m along every function of ev in turn (c initialised to zeros by the caller). tol is
 * the distance both surfaces must be within at curve vertices (1e-10 × the box diagonal
 * asks the precision). Triangle winding is kept; normals of new vertices are ∇f's
 * direction, oriented like their edge's. False when out of memory. */
bool ism_cut_mesh(ism_cut_eval *ev, double tol, ism_mesh *m, ism_cut *c);

#endif
