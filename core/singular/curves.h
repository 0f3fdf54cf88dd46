/* curves.h — the singular curves of f = 0 in a box: the 1-D parts of f = ∇f = 0, traced
 * from the search's candidate boxes as polylines, each a double curve or a whisker, with its
 * ends typed, and the pinch and triple points they meet. */
#ifndef ISM_CURVES_H
#define ISM_CURVES_H

#include <stdbool.h>
#include "core/expr/expr.h"
#include "core/singular/locus.h"

/* Traces every singular curve through the seed boxes of io->boxes (ISM_LBOX_PROJECTED,
 * rank 2, not ISM_LBOX_USED) inside o->box, both ways from each seed, and appends to
 * io->curves:
 *   - polylines whose points lie within 1e-9 × box diagonal of f = ∇f = 0, consecutive
 *     points between 0.05 and ~0.55 of a finest search cell (smallest box side /
 *     2^max_depth) apart, except next to pinch points and ends;
 *   - kind DOUBLE where the Hessian across the curve is indefinite, WHISKER where definite;
 *     a curve changing kind is split at the pinch point between (located to 1e-10 ×
 *     diagonal), which is added to io->points as ISM_SING_PINCH, uncertified;
 *   - ends: BOX (the last point exactly on the box's face), closed loops (closed = true),
 *     PINCH, TRIPLE (where ≥ 3 branches end at a point where the Hessian across the curve
 *     degenerates — rank 0 as at xyz = 0's origin, or rank 1 without a pinch as where two
 *     whiskers cross in z² + x²y² —: added once as ISM_SING_TRIPLE within 1e-9 × diagonal,
 *     or an existing point there retyped so), POINT (an existing point, or such a point where
 *     < 3 branches end, added as ISM_SING_DEGENERATE), LOST.
 * Boxes the curves and their points explain are marked ISM_LBOX_USED (any rank: those the
 * polylines pass through, and those whose q lies within 1/16 cell of one). Seeds whose q
 * does not lead onto a curve of the zero set inside the box (|f| not ~0, an isolated
 * critical point, Hessian rank 1, a point beyond the box's face) are left unmarked. Stops at o->deadline_ms, *o->cancel or the work budget with
 * io->incomplete set and a reason (what was traced stays valid); a LOST end also sets it. o->threads is not used
 * (tracing is a small, sequential part of the stage). False (err set) only on invalid
 * options or out of memory. */
bool ism_sing_trace_curves(const ism_tape *f, const ism_locus_options *o, ism_locus *io,
                           ism_error *err);

/* Names the reason of every uncertified point where ≥ 2 branches of io's curves end and whose
 * rank-1 system is singular (ISM_UNCERT_CONTACT, the certificates' default for that case):
 * curves cross there (ISM_UNCERT_CROSSING: z² + x²y², whose x and y axes are whiskers
 * crossing at the origin, H = diag(0, 0, 2)); a contact of two sheets is reached by no curve.
 * Run after every point is certified. False only when out of memory. */
bool ism_sing_name_crossings(ism_locus *io);

#endif
