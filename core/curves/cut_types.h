/* cut_types.h — the result of cutting a mesh along curves (cut.h): the cut edges, data
 * only, shared by the cut's driver, its files (cut_internal.h) and the arrangement. */
#ifndef ISM_CUT_TYPES_H
#define ISM_CUT_TYPES_H

#include <stddef.h>
#include <stdint.h>

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

#endif
