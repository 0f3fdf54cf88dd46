/* workspace.h — the per-thread registers of every evaluator (layout shared by the files of
 * core/eval; not public). One workspace is sized for a tape and serves every tape
 * shortened from it, since shortening keeps the register numbering. */
#ifndef ISM_WORKSPACE_H
#define ISM_WORKSPACE_H

#include <stdint.h>
#include "core/eval/eval.h"
#include "core/eval/trig_pair.h"
#include "core/expr/tape.h"

/* Boxes per inner chunk of the batched interval evaluator. */
#define ISM_IV_CHUNK 64

typedef struct ism_dual {
    double v, d[3];           /* value and gradient */
} ism_dual;

typedef struct ism_jet {
    double v, d[3], h[6];     /* value, gradient, Hessian (xx xy xz yy yz zz) */
} ism_jet;

struct ism_eval_ws {
    uint32_t nregs;           /* registers available */
    size_t code_cap;          /* longest tape served (for the per-instruction arrays) */
    double *batch;            /* nregs * ISM_EVAL_BATCH doubles, register-major */
    double *scalar;           /* nregs */
    ism_interval *iv;         /* nregs */
    double *iv_lo, *iv_hi;    /* nregs * ISM_IV_CHUNK each: batched lower bounds, negated upper */
    ism_dual *dual;           /* nregs */
    double *gbatch;           /* nregs * 4 * ISM_GRAD_BATCH: value, d/dx, d/dy, d/dz lanes */
    ism_jet *jet;             /* nregs */
    void *hbatch;             /* ism_eval_hessian_batch's registers (made on its first call) */
    uint8_t *choice;          /* code_cap: min/max branch proved by the last interval pass */
    uint8_t *needed;          /* nregs: scratch for shortening */
    ism_trig_cache *trig;     /* sines and cosines of recent arguments (pure: never stale) */
};

/* True when ws has room for evaluating t. */
static inline int ism_ws_fits(const ism_eval_ws *ws, const ism_tape *t)
{
    return ws && t && ws->nregs >= t->nregs && ws->code_cap >= t->len;
}

/* What kink in passes on its branch br (1 or 2, as an ism_piece names it and as shortening
 * records a decided min/max): its operand a, its register b, its constant (the _RC forms'
 * branch 2) or -a (abs on branch 2). One rule for the shortened tapes (shorten.c) and the
 * forced pieces (ism_eval_piece_value, ism_eval_piece_gradient), each switching on it. */
enum ism_kink_passed { ISM_PASS_A, ISM_PASS_B, ISM_PASS_IMM, ISM_PASS_NEG_A };
static inline enum ism_kink_passed ism_kink_pass(const ism_instr *in, unsigned br)
{
    if (in->op == ISM_OP_ABS)
        return br == 1 ? ISM_PASS_A : ISM_PASS_NEG_A;
    if (br == 1)
        return ISM_PASS_A;
    return in->op == ISM_OP_MIN_RR || in->op == ISM_OP_MAX_RR ? ISM_PASS_B : ISM_PASS_IMM;
}

/* The branch piece pc takes at the tape's k-th kink (bits 2k, 2k + 1, eval.h): 1 or 2, or 0
 * (both, as f) there and past ISM_PIECE_KINKS. The one decoder of the passes that force a
 * piece (ism_eval_piece_value, ism_eval_piece_gradient). */
static inline unsigned ism_piece_branch(ism_piece pc, unsigned k)
{
    return k < ISM_PIECE_KINKS ? (unsigned)(pc >> (2 * k)) & 3u : 0;
}

/* The piece ws->choice (one byte per instruction of t: a kink's branch, 1 or 2, or 0 for
 * both) names: back from f's result through the operands the branches taken read. kinks: t's
 * number of kinks (ism_tape_kinks), at most ISM_PIECE_KINKS. *open (may be NULL): set when a
 * kink on that path has choice 0 (the piece is then not determined). (shorten.c) */
ism_piece ism_piece_walk(const ism_tape *t, ism_eval_ws *ws, size_t kinks, bool *open);

#endif
