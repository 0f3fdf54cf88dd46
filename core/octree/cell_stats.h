/* cell_stats.h — arithmetic on the polygoniser's per-thread counters (ism_cell_stats,
 * cell_types.h): what one step added, and adding it again where a memo copies the step's
 * output (leaf_memo.h, the tile memo in cell_cache.h). */
#ifndef ISM_CELL_STATS_H
#define ISM_CELL_STATS_H

#include "core/octree/cell_types.h"

/* Counter differences after - before (what one step added). */
ism_cell_stats ism_cell_stats_minus(const ism_cell_stats *after, const ism_cell_stats *before);

/* Adds every counter of d to st. */
void ism_cell_stats_add(ism_cell_stats *st, const ism_cell_stats *d);

#endif
