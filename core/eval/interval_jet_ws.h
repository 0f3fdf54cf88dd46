/* interval_jet_ws.h — the interval jets' workspace (interval_jet.h's ism_ivjet_ws), shared by
 * the box-by-box evaluator (eval_interval_jet.c), the batched gradient pass
 * (eval_interval_grad_batch.c) and the batched jets (eval_interval_jet_lanes.c): their
 * registers, and the records of gradient passes that a following jet over the same box
 * takes its values and first partials from (then computing only the Hessian). Internal to
 * core/eval. */
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
#define ISM_IVG_VL ISM_IVGRAD_GROUP /* interval_jet.h: callers group jets by it */
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
    /* The batched second-order pass's registers (ism_eval_interval_jet_lanes; made on its
     * first use, nregs of them): values and first partials as lane_regs lays them out, and
     * each register's six Hessian entries (ISM_IVG_GROUPS groups of 12 vectors). Apart from
     * lane_regs so that the jets leave the batched gradient pass standing. */
    double *jet_regs;
    double *jet_hregs;
};
_Static_assert(ISM_IVGRAD_BATCH <= 8, "a lane's kink is one bit of lane_kinks' bytes");

/* What one instruction of a pass computes, as bits (eval_interval_jet.c's want bits): D(k)
 * the partial in variable k, H(e) the Hessian entry e (xx xy xz yy yz zz), SECOND whether
 * the pass keeps Hessian entries at all. */
#define ISM_IVJ_D(k) (1u << (k))
#define ISM_IVJ_H(e) (8u << (e))
#define ISM_IVJ_SECOND (1u << 9)
#define ISM_IVJ_H_ALL (ISM_IVJ_H(0) | ISM_IVJ_H(1) | ISM_IVJ_H(2) | ISM_IVJ_H(3) | ISM_IVJ_H(4) \
                       | ISM_IVJ_H(5))

/* The (i, j) index pairs of the six Hessian entries. */
static const int ism_ivjet_hi[6] = { 0, 0, 0, 1, 1, 2 };
static const int ism_ivjet_hj[6] = { 0, 1, 2, 1, 2, 2 };

/* The bits for an instruction whose value depends on the variables in deps (bit 0 x, 1 y,
 * 2 z), in the first (second = 0) or the second-order pass; smooth: nothing that may kink
 * feeds it (tape.h). A Hessian entry (i, j) is wanted where both i and j are in deps, every
 * entry where a kink may feed the value (set_whole_derivs makes the mixed entry (x, z) of a
 * value free of z the whole line at a kink when its x partial is not 0). */
static inline unsigned ism_ivjet_want(unsigned deps, int second, bool smooth)
{
    static const unsigned h_of[8] = {
        0u,                                                 /* none */
        ISM_IVJ_H(0),                                       /* x: xx */
        ISM_IVJ_H(3),                                       /* y: yy */
        ISM_IVJ_H(0) | ISM_IVJ_H(1) | ISM_IVJ_H(3),         /* x y */
        ISM_IVJ_H(5),                                       /* z: zz */
        ISM_IVJ_H(0) | ISM_IVJ_H(2) | ISM_IVJ_H(5),         /* x z */
        ISM_IVJ_H(3) | ISM_IVJ_H(4) | ISM_IVJ_H(5),         /* y z */
        ISM_IVJ_H_ALL,
    };
    return !second ? deps : deps | ISM_IVJ_SECOND | (smooth ? h_of[deps & 7u] : ISM_IVJ_H_ALL);
}

/* Operations whose Hessian hess_only computes from the operands' kept values and first
 * partials alone (eval_interval_jet.c), and the only ones the batched pass computes. */
bool ism_ivjet_hess_from_kept(int op);

/* Every instruction of t is one of those (a fact of the tape: asked on every use, never
 * remembered by the tape's address, which a tape compiled after another's free may reuse). */
bool ism_ivjet_tape_hess_from_kept(const ism_tape *t);

#endif
