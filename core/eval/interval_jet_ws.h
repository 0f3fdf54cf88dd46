/* interval_jet_ws.h — the interval jets' workspace (interval_jet.h's ism_ivjet_ws), shared by
 * the box-by-box evaluator (eval_interval_jet.c) and the batched gradient pass
 * (eval_interval_grad_batch.c): their registers, and the records of gradient passes that a
 * following jet over the same box takes its values and first partials from (then computing
 * only the Hessian). Internal to core/eval. */
#ifndef ISM_INTERVAL_JET_WS_H
#define ISM_INTERVAL_JET_WS_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>
#include "core/eval/interval_jet.h"

/* One instruction's value and first partials as a gradient pass wrote them to its register. */
typedef ism_interval ism_kept_vd[4];

/* A batch's lanes are walked in groups of ISM_IVG_VL (one AVX2 vector of doubles). A
 * register of the batched pass, and an instruction's record, is ISM_IVG_GROUPS groups of
 * 8 vectors: the lower and the upper bounds of the value and of each first partial. */
#define ISM_IVG_VL 4
#define ISM_IVG_GROUPS (ISM_IVGRAD_BATCH / ISM_IVG_VL)
#define ISM_IVG_REG (ISM_IVG_GROUPS * 8 * ISM_IVG_VL) /* doubles a register or record holds */
/* ISM_IVG_GROUPS counts whole groups: a batch of 10 would walk a third group past a
 * register's end. */
_Static_assert(ISM_IVGRAD_BATCH % ISM_IVG_VL == 0, "a batch is whole groups of lanes");

struct ism_ivjet_ws {
    uint32_t nregs;
    ism_ivjet *r;
    /* The registers r hold an unforced gradient pass (force NULL; run_grad's or
     * run_grad_kept's) of last_t over last_box, read by ism_ivjet_top_pieces; NULL after a
     * second-order pass or hess_only. */
    const ism_tape *last_t;
    ism_interval last_box[3];
    /* kept[i]: instruction i's value and first partials from the last
     * ism_eval_interval_grad_kept (kept_t over kept_box), when kept_ok: that pass met no
     * kink and its record is unused (the jet that uses it asks whether every instruction of
     * kept_t is one whose Hessian hess_only can take from them). */
    size_t kept_cap;
    ism_kept_vd *kept;
    const ism_tape *kept_t;
    ism_interval kept_box[3];
    bool kept_ok;
    /* The batched gradient pass (made on its first use): its registers (nregs of
     * ISM_IVG_REG doubles) and its records (lane_cap instructions of ISM_IVG_REG), lane k's
     * of lane_t over lane_box[k] while bit k of lane_ok is set (unused; lane_t holds only
     * operations hess_only takes). */
    double *lane_regs;
    double *lane_kept;
    size_t lane_cap;
    const ism_tape *lane_t;
    ism_interval lane_box[ISM_IVGRAD_BATCH][3];
    uint32_t lane_ok;
    /* The last batched pass (either entry point): lane_pass_t, NULL when none stands, over
     * lane_box[0..lane_n); lane_regs hold its registers (ism_ivjet_top_pieces reads them),
     * lane_kinks[i] (lane_cap bytes) bit k where instruction i is a free kink over box k,
     * lane_nk[k] their count, lane_kink_at[0..lane_nkink_at) the i whose byte is not 0 (a
     * box's kink bytes are written from these alone: Barth's tape has one min/max). */
    const ism_tape *lane_pass_t;
    uint32_t lane_n;
    uint8_t *lane_kinks;
    uint32_t lane_nk[ISM_IVGRAD_BATCH];
    uint32_t *lane_kink_at;
    size_t lane_nkink_at;
};
_Static_assert(ISM_IVGRAD_BATCH <= 8, "a lane's kink is one bit of lane_kinks' bytes");

/* Operations whose Hessian hess_only computes from the operands' kept values and first
 * partials alone (eval_interval_jet.c), and the only ones the batched pass computes. */
bool ism_ivjet_hess_from_kept(int op);

/* Every instruction of t is one of those (a fact of the tape: asked on every use, never
 * remembered by the tape's address, which a tape compiled after another's free may reuse). */
bool ism_ivjet_tape_hess_from_kept(const ism_tape *t);

#endif
