/* zero_cells.h — the finest cells of the lattice (box side / 2^depth on each axis) whose
 * interval of f holds 0, found by an interval octree (min/max shortened on the way down)
 * that never allocates the full grid. Any cell that meets f = 0 is listed; listed cells
 * may miss it (intervals over-estimate). */
#ifndef ISM_ZERO_CELLS_H
#define ISM_ZERO_CELLS_H

#include <stddef.h>
#include <stdint.h>
#include "core/expr/expr.h"
#include "core/octree/grid.h"

typedef struct ism_zero_cells_params {
    const ism_tape *f;
    const ism_grid *grid;       /* the lattice; grid->depth is the finest level */
    int threads;                /* >= 1 */
    size_t max_cells;           /* budget: beyond it the search stops (ISM_ZC_BUDGET) */
    const volatile int *cancel; /* polled; non-zero stops the search */
    double deadline_ms;         /* ism_now_ms() past which the search stops (0 = none) */
} ism_zero_cells_params;

enum ism_zc_status { ISM_ZC_OK = 0, ISM_ZC_BUDGET, ISM_ZC_CANCELLED, ISM_ZC_DEADLINE,
                     ISM_ZC_NO_MEMORY };

typedef struct ism_zero_cells {
    uint64_t *cells;            /* lattice keys (lattice_key.h) of the cells' lowest corners,
                                   in a fixed order whatever the thread count */
    size_t n;
    uint64_t visited;           /* octree nodes whose interval was evaluated */
} ism_zero_cells;

/* Lists the cells. On a status other than OK, out holds what was found before stopping.
 * Free out->cells with free(). */
enum ism_zc_status ism_zero_cells_find(const ism_zero_cells_params *p, ism_zero_cells *out);

#endif
