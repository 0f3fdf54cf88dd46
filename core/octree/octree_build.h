/* octree_build.h — building the adaptive octree: interval exclusion of empty nodes (with
 * min/max tape shortening on the way down), unconditional subdivision to the minimum depth,
 * then the flatness test until the maximum depth. Subtrees are built in parallel and joined
 * in a fixed order, so the tree is identical for any number of threads. */
#ifndef ISM_OCTREE_BUILD_H
#define ISM_OCTREE_BUILD_H

#include <stdint.h>
#include "core/expr/expr.h"
#include "core/octree/octree.h"
#include "core/octree/plot_test.h"
#include "core/octree/refine.h"

typedef struct ism_octree_build_params {
    const ism_tape *tape;
    int min_depth, max_depth;
    ism_flatness flatness;
    int threads;
    size_t max_nodes;                 /* stop with ISM_BUILD_TOO_BIG beyond this */
    const ism_split_set *force_split; /* nodes split whatever the flatness test says (their
                                         emitted triangles missed max_error): NULL for none */
    const volatile int *cancel;
    void (*progress)(void *ctx, double fraction); /* fraction of subtrees done */
    void *progress_ctx;
} ism_octree_build_params;

typedef struct ism_octree_build_stats {
    uint64_t visited, excluded, unresolved;
    uint64_t n_point, n_gradient, n_interval;
} ism_octree_build_stats;

enum ism_build_status { ISM_BUILD_OK, ISM_BUILD_CANCELLED, ISM_BUILD_TOO_BIG, ISM_BUILD_NO_MEMORY };

/* t->grid must be set; t->nodes is allocated here (free with ism_octree_free). */
enum ism_build_status ism_octree_build(ism_octree *t, const ism_octree_build_params *p,
                                       ism_octree_build_stats *stats);

void ism_octree_free(ism_octree *t);

#endif
