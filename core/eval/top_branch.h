/* top_branch.h — the one rule for which operand of a min or max f's derivative passes on
 * (every gradient evaluator's and ism_eval_piece's), and for f's top min/max the branch f's
 * own gradient follows. Inline: the point evaluators' min/max steps and the build's corner
 * labels ask it once per instruction or corner. (The label, ism_top_active_branch, is eval.h's:
 * it differs from this rule only on ties and NaN.) */
#ifndef ISM_TOP_BRANCH_H
#define ISM_TOP_BRANCH_H

#include <stdbool.h>
#include "core/expr/tape.h"

/* The operand of min(a, b) (is_min) or max(a, b) whose value and partials f's derivative
 * passes on: 0 (a) where a wins strictly (min: a < b, max: a > b), else 1 (b) — b on a tie,
 * and wherever a or b is NaN. The rule of eval_gradient.c's steps and eval_hessian.c's
 * (eval_gradient_batch.c's k_pick is its four-lane form) and of ism_eval_piece's natural
 * branch (1 + this); ism_top_active_branch's label differs from it only there (a tie or a
 * NaN gives the label 0). */
static inline int ism_minmax_gradient_operand(bool is_min, double a, double b)
{
    return is_min ? !(a < b) : !(a > b);
}

/* When t ends in min/max of two registers (ism_tape_top_minmax): 0 or 1, the branch
 * (ism_top_active_branch's numbering) whose gradient f's own gradient is where the two values
 * are val; -1 when t does not end so. It names the labelled branch exactly where that branch
 * wins strictly or is the second one. */
static inline int ism_top_gradient_branch(const ism_tape *t, const double val[2])
{
    const ism_instr *top = ism_tape_top_minmax(t);
    if (!top)
        return -1;
    return ism_minmax_gradient_operand(top->op == ISM_OP_MIN_RR, val[0], val[1]);
}

#endif
