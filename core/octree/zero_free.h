/* zero_free.h — the test that a would-be leaf holds no point where |f| comes within the
 * double-root eps of 0: then no segment of it has a root or a tangent point (edge_roots.c),
 * so it emits nothing, and the polygoniser skips it (ISM_NODE_ZERO_FREE). Intervals over
 * the node's octants, in one batched call, and the mean-value form are tighter than the
 * node's own interval (which contained 0, or the node would be empty). */
#ifndef ISM_ZERO_FREE_H
#define ISM_ZERO_FREE_H

#include <stdbool.h>
#include <stdint.h>
#include "core/eval/eval.h"
#include "core/eval/interval_jet.h"
#include "core/octree/corners.h"

/* True when f keeps |f| > eps, with one sign, on the whole closed box lo..hi whose corners
 * k holds: every corner beyond eps with the same sign, and either the interval over each of
 * the box's 8 octants (one batched call) or the mean-value form over the box (through jet,
 * when not NULL) beyond eps with that sign. False says nothing. *intervals counts the
 * enclosures evaluated. */
bool ism_box_zero_free(const ism_tape *t, ism_eval_ws *ws, ism_ivjet_ws *jet,
                       const double lo[3], const double hi[3], const ism_corners *k,
                       double eps, uint64_t *intervals);

#endif
