/* accuracy.h — how far the mesh lies from f = 0 between its vertices (accuracy.c), and the
 * summary figures of a list of distances. */
#ifndef ISM_AN_ACCURACY_H
#define ISM_AN_ACCURACY_H

#include <stddef.h>
#include <stdbool.h>
#include "core/mesh/mesh.h"
#include "core/expr/expr.h"
#include "core/analysis/analysis_types.h"
#include "core/analysis/edges.h"
#include "core/util/pool.h"

/* Maximum, mean and 99th percentile of the distances that are not NaN (moves those to the
 * front of dist and may reorder them; the percentile found on the threads of pool, NULL: the
 * calling thread); skipped: how many were NaN. */
typedef struct ism_an_distances {
    double max, mean, p99;
    size_t skipped;
} ism_an_distances;
void ism_an_distance_figures(double *dist, size_t n, ism_pool *pool, ism_an_distances *out);

/* Distances at triangle centroids and edge midpoints (after ism_an_implicit_figures with
 * accuracy, which sets the singular threshold and the vertices' distances: false without),
 * the maxima taking those just within max_error (the mesh's bound, 0: none) a Newton step
 * further (the means and 99th percentiles do not depend on it), evaluated on the threads of
 * pool (NULL: the calling thread); false when out of memory. */
bool ism_an_between_vertices(const ism_mesh *m, const ism_tape *f, const ism_an_edge_table *et,
                             double max_error, ism_pool *pool, ism_analysis *a);

#endif
