/* zero_free.h — the test that a would-be leaf holds no point where |f| comes within the
 * double-root eps of 0: then no segment of it has a root or a tangent point (edge_roots.c),
 * so it emits nothing, and the polygoniser skips it (ISM_NODE_ZERO_FREE). Intervals over
 * the node's octants, in one batched call, are tighter than the node's own interval (which
 * contained 0, or the node would be empty). */
#ifndef ISM_ZERO_FREE_H
#define ISM_ZERO_FREE_H

#include <stdbool.h>
#include <stdint.h>
#include "core/eval/eval.h"
#include "core/octree/corners.h"

/* True when f keeps |f| > eps, with one sign, on the whole closed box lo..hi whose corners
 * k holds: every corner beyond eps with the same sign, and the interval over each of the
 * box's 8 octants beyond eps with that sign. False says nothing. *intervals counts the
 * boxes evaluated. */
bool ism_box_zero_free(const ism_tape *t, ism_eval_ws *ws, const double lo[3],
                       const double hi[3], const ism_corners *k, double eps,
                       uint64_t *intervals);

#endif
