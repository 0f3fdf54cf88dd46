/* duplicates.h — the pass that counts repeated triangles (duplicates.c). */
#ifndef ISM_AN_DUPLICATES_H
#define ISM_AN_DUPLICATES_H

#include <stdbool.h>
#include "core/mesh/mesh.h"
#include "core/analysis/analysis_types.h"
#include "core/analysis/edges.h"
#include "core/util/pool.h"

/* Counts triangles with the same three vertices as an earlier one, edge blocks on the threads
 * of pool (NULL: the calling thread); false when out of memory. */
bool ism_an_count_duplicates(const ism_mesh *m, const ism_an_edge_table *et, ism_pool *pool,
                             ism_analysis *a);

#endif
