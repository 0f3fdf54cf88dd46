/* sheet_cells.h — the finest cells of the lattice (box side / 2^depth on each axis) that may
 * hold a double sheet: an interval octree (min/max shortened on the way down, never the full
 * grid) keeps the cells whose interval of f holds 0; then, eight cells at a time with their
 * 27 lattice points shared, a cell stays only when f does not change sign at its corners
 * (a sign change is a surface the polygoniser meshes) and two corner gradients point apart
 * (across f = g²·k, ∇f = 2gk∇g + g²∇k flips; near a sign-changing surface the gradients
 * are nearly parallel). */
#ifndef ISM_SHEET_CELLS_H
#define ISM_SHEET_CELLS_H

#include <stddef.h>
#include <stdint.h>
#include "core/expr/expr.h"
#include "core/octree/grid.h"

typedef struct ism_sheet_cells_params {
    const ism_tape *f;
    const ism_grid *grid;       /* the lattice; grid->depth (>= 1) is the finest level */
    int threads;                /* >= 1 */
    size_t max_cells;           /* budget of cells listed (ISM_SC_BUDGET beyond it) */
    const volatile int *cancel; /* polled; non-zero stops the search */
    double deadline_ms;         /* ism_now_ms() past which the search stops (0 = none) */
} ism_sheet_cells_params;

enum ism_sc_status { ISM_SC_OK = 0, ISM_SC_BUDGET, ISM_SC_CANCELLED, ISM_SC_DEADLINE,
                     ISM_SC_NO_MEMORY };

typedef struct ism_sheet_cells {
    uint64_t *cells;            /* lattice keys (lattice_key.h) of the cells' lowest corners,
                                   in a fixed order whatever the thread count */
    size_t n;
    uint64_t intervals;         /* interval evaluations of f (octree nodes) */
    uint64_t gradient_boxes;    /* interval evaluations of f and ∇f */
    uint64_t zero_cells;        /* finest cells whose interval holds 0 */
    uint64_t points, gradients; /* point and gradient evaluations */
} ism_sheet_cells;

/* Lists the cells. On a status other than OK, out holds what was found before stopping.
 * Free out->cells with free(). */
enum ism_sc_status ism_sheet_cells_find(const ism_sheet_cells_params *p, ism_sheet_cells *out);

/* The same filter (without the octree) on n given finest cells (lattice keys, any order,
 * no duplicates), for instance the candidates an earlier interval search kept: lists those
 * that pass, grouped by block. */
enum ism_sc_status ism_sheet_cells_filter(const ism_sheet_cells_params *p, const uint64_t *cells,
                                          size_t n, ism_sheet_cells *out);

#endif
