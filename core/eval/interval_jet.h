/* interval_jet.h — interval forward-mode derivatives: over a box, outward-rounded enclosures
 * of f, its gradient and (optionally) its Hessian, for interval Newton / Krawczyk tests and
 * for excluding boxes where ∇f cannot vanish.
 *
 * Where the box holds a point at which f is not differentiable (a min/max whose operands may
 * cross, abs of an interval holding 0, sqrt/log/real powers at the clipping edge 0, a pole),
 * the derivatives that are not bounded there are the whole line. min, max and abs can instead
 * be forced onto one branch: the enclosures then hold the derivatives of f at every point of
 * the box where that branch is the active one (the value stays the natural enclosure of f).
 * This lets a caller search each smooth piece of f separately. */
#ifndef ISM_INTERVAL_JET_H
#define ISM_INTERVAL_JET_H

#include <stddef.h>
#include <stdint.h>
#include "core/eval/eval.h"

/* f and ∇f over a box. */
typedef struct ism_ivgrad {
    ism_interval v, d[3];
} ism_ivgrad;

/* f, ∇f and the Hessian (h = xx xy xz yy yz zz) over a box. */
typedef struct ism_ivjet {
    ism_interval v, d[3], h[6];
} ism_ivjet;

/* Branch of a min, max or abs instruction (one byte per instruction of the tape). */
enum ism_branch {
    ISM_BRANCH_FREE = 0, /* whichever the box allows: a kink when both may be active */
    ISM_BRANCH_A = 1,    /* min/max: the first operand; abs(a): +a */
    ISM_BRANCH_B = 2,    /* min/max: the second operand (or the constant); abs(a): -a */
};

/* Registers of one evaluation (one per thread; serves t and every tape shortened from t). */
typedef struct ism_ivjet_ws ism_ivjet_ws;

ism_ivjet_ws *ism_ivjet_ws_new(const ism_tape *t);
void ism_ivjet_ws_free(ism_ivjet_ws *ws);

/* Encloses f and ∇f over box[0] × box[1] × box[2] (outward rounded; no NaN bound).
 * force: NULL (all free) or t's length of enum ism_branch bytes. kinks: NULL, or t's length
 * of bytes set to 1 at every free min/max/abs instruction whose both branches the box allows
 * (0 elsewhere). Returns the number of such kinks; (size_t)-1 when ws does not fit t (out is
 * then the whole line). */
size_t ism_eval_interval_grad(const ism_tape *t, ism_ivjet_ws *ws, const ism_interval box[3],
                              const uint8_t *force, uint8_t *kinks, ism_ivgrad *out);

/* Whether ism_eval_interval_grad(t, ws, box, NULL, NULL, out) would return other than 0 (a
 * free kink, or ws does not fit t), told from the natural enclosures alone: the same values
 * bit for bit without the partials, stopping at the first free kink. For a caller that
 * discards the slopes at a kink (the mean-value form), asked first where a kink may feed f
 * (the last instruction not smooth: tape.h). Leaves no gradient pass in ws's registers
 * (ism_ivjet_top_pieces reads none): the registers it ran through hold their values with
 * every partial 0, not a gradient, for any later reader of ws. */
bool ism_eval_interval_meets_kink(const ism_tape *t, ism_ivjet_ws *ws,
                                  const ism_interval box[3]);

/* Right after an ism_eval_interval_grad of t on ws over box with no branch forced (force
 * NULL), or after a batched pass of t one of whose boxes is box (ism_eval_interval_grad_lanes
 * or _batch, no batched pass since), where t ends in a min or max of two registers (or of a
 * register and a constant) that depends on all of x, y and z, and whose two branches the box
 * allows (a free kink): f and ∇f over box with that last instruction forced onto branch A
 * (piece[0]) and onto B (piece[1]), bit for bit what ism_eval_interval_grad with that force
 * gives, read from the registers the pass left (no evaluation: a kink at the top is where a
 * min or max of two solids creases, Barth's sextic in its ball, the gyroid in its ball).
 * False, piece untouched, when neither pass stands (another tape, another box, a force, a
 * jet since the scalar one), t does not end so, or its result shares a register with an
 * operand. */
bool ism_ivjet_top_pieces(const ism_tape *t, const ism_ivjet_ws *ws, const ism_interval box[3],
                          ism_ivgrad piece[2]);

/* ism_eval_interval_grad with no branch forced and no kinks wanted, keeping in ws every
 * instruction's value and first partials: a following ism_eval_interval_jet of t over the
 * same box (bit for bit) on ws, with no branch forced, then computes only the Hessian (once;
 * other evaluations on ws between the two do not matter), where t holds only affine
 * operations, +, −, ×, squares and integer powers — the results are the same bits either
 * way. t must stay allocated until then. */
size_t ism_eval_interval_grad_kept(const ism_tape *t, ism_ivjet_ws *ws,
                                   const ism_interval box[3], ism_ivgrad *out);

/* Boxes ism_eval_interval_grad_batch takes at once. It runs them in groups of 4: on the
 * torus a group ~2,100 instructions, against ~1,700 for one box's ism_eval_interval_grad_kept
 * and ~1,600 for one centre's gradient alone (callgrind, ea7be31 / 9ec8926). So a batch
 * pays from 2 boxes or centres up: the callers' thresholds (dual.c BATCH_ENCLOSURES,
 * dual_classify.c PRE_MODELS_MIN, search.c pre_gradients) rest on these figures. */
#define ISM_IVGRAD_BATCH 8

/* The boxes of one group of a batched pass (one AVX2 vector of doubles; a batch is
 * ISM_IVGRAD_BATCH / ISM_IVGRAD_GROUP groups): ism_eval_interval_jet_lanes takes the values and
 * first partials from the last pass's records only when every box's lies in one group, so a
 * caller batching jets from records takes them a group at a time (search.c box_jets). */
#define ISM_IVGRAD_GROUP 4

/* ism_eval_interval_grad_kept over box[0..n) (n <= ISM_IVGRAD_BATCH) at once, bit for bit:
 * out[k] the enclosure over box[k], each box's record kept in ws so that a following
 * ism_eval_interval_jet of t over any of them (unforced, once each) computes only the
 * Hessian; no kinks (t holds none of the operations that have them). False, computing
 * nothing, when t holds an operation besides the affine ones, +, −, ×, squares and integer
 * powers, or ws does not fit t or cannot grow: then take the boxes one by one. */
bool ism_eval_interval_grad_batch(const ism_tape *t, ism_ivjet_ws *ws,
                                  const ism_interval (*box)[3], size_t n, ism_ivgrad *out);

/* ism_eval_interval_grad_batch for tapes with min, max and abs as well: out[k] bit for bit
 * what ism_eval_interval_grad(t, ws, box[k], NULL, kinks, &out[k]) gives, nk[k] (nk may be
 * NULL) the number it returns (the box's free kinks), its kink bytes kept in ws for
 * ism_ivjet_lane_kinks, and its registers for ism_ivjet_top_pieces over box[k]; records for
 * the jets as ism_eval_interval_grad_batch keeps them when t holds none of min, max and abs
 * (then the two are the same call). False, computing nothing, when t holds an operation
 * besides the affine ones, +, −, ×, squares, integer powers, min, max and abs, or ws does not
 * fit t or cannot grow: then take the boxes one by one. */
bool ism_eval_interval_grad_lanes(const ism_tape *t, ism_ivjet_ws *ws,
                                  const ism_interval (*box)[3], size_t n, ism_ivgrad *out,
                                  uint32_t *nk);

/* The kink bytes of the last batched pass of t on ws over box (ism_eval_interval_grad_lanes
 * or _batch: no other batched pass since, box one of its boxes) into kinks (t's length of
 * bytes): 1 at every free min/max/abs instruction, 0 elsewhere, as ism_eval_interval_grad's
 * over that box; returns their number. (size_t)-1, kinks untouched, when there is no such
 * pass. */
size_t ism_ivjet_lane_kinks(const ism_tape *t, const ism_ivjet_ws *ws,
                            const ism_interval box[3], uint8_t *kinks);

/* The same with the Hessian. For a degenerate box [c, c] this encloses the exact jet at c. */
size_t ism_eval_interval_jet(const ism_tape *t, ism_ivjet_ws *ws, const ism_interval box[3],
                             const uint8_t *force, uint8_t *kinks, ism_ivjet *out);

/* ism_eval_interval_jet over box[0..n) (n <= ISM_IVGRAD_BATCH) at once, no branch forced
 * and no kinks wanted: out[k] bit for bit what ism_eval_interval_jet(t, ws, box[k], NULL,
 * NULL, &out[k]) gives. Its registers are its own: the last batched gradient pass (its
 * records, kinks and registers) and the scalar passes' registers stand as they were. False,
 * computing nothing, where ism_eval_interval_grad_lanes refuses t (an operation besides the
 * affine ones, +, −, ×, squares, integer powers, min, max and abs), ws does not fit t or
 * cannot grow, or n is 0 or too many: then take the boxes one by one. */
bool ism_eval_interval_jet_lanes(const ism_tape *t, ism_ivjet_ws *ws,
                                 const ism_interval (*box)[3], size_t n, ism_ivjet *out);

#endif
