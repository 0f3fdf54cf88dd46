/* eval_interval_jet_lanes.c — interval jets (value, first partials and Hessian) over up to
 * ISM_IVGRAD_BATCH boxes at once (interval_jet.h's ism_eval_interval_jet_lanes, for the
 * singular search's smooth_tests), on the batched gradient pass's lanes
 * (interval_grad_lanes.h): each instruction's value and partials by its step, then its
 * Hessian entries by eval_interval_jet.c's rules, bit for bit ism_eval_interval_jet's; or,
 * right after a batched gradient pass over the same boxes (eval_interval_grad_batch.c, tapes
 * without kinks), the Hessians alone from its records, as eval_interval_jet.c's hess_only
 * takes them from one box's. In registers of their own, so that the gradient pass (its
 * records, kinks and registers) stands. */
#include "core/eval/avx2_clone.h"
#include "core/eval/interval_grad_lanes.h"
#include "core/eval/interval_jet_ws.h"
#include "core/expr/tape.h"
#include "core/util/cache_line.h"

#include <stdlib.h>
#include <string.h>

/* The batched second-order pass (ism_eval_interval_jet_lanes): each instruction's value and
 * first partials by step (the gradient pass's, which are the second-order pass's: its rules
 * for them do not depend on the Hessian), then its Hessian entries by eval_interval_jet.c's
 * rules (each_hess, add_hess, mul_hess, chain_hess with second_factor, op_branch's
 * take_derivs and set_whole_derivs), read from the operands' registers as step left them,
 * in jet_op's order; exact zeros kept and skipped as mulz / addz / subz do; entries outside
 * the instruction's want (ism_ivjet_want) 0; NaN bounds turned into infinities (sanitize). */

/* A register's six Hessian entries, one group of lanes. */
typedef struct vh {
    vi h[6];
} vh;
_Static_assert(sizeof(vh) == 12 * VL * sizeof(double), "a group's Hessian is 12 vectors");

INLINE bool want_h(unsigned w, int e) { return (w & ISM_IVJ_H(e)) != 0; }

/* dd: u'_i u'_j, the square when i = j; 0 where either is exactly 0 */
INLINE vi dd_of(const vj *a, int e)
{
    int i = ism_ivjet_hi[e], j = ism_ivjet_hj[e];
    vi p = i == j ? v_square(a->d[i]) : v_mul(a->d[i], a->d[j]);
    return vpick(iz(a->d[i]) | iz(a->d[j]), ivz(), p);
}

/* each_hess: the map on every entry in w that is not exactly 0 (kept as it is) */
INLINE void each_h(vh *o, const vh *a, int kind, double c, unsigned w)
{
    _Pragma("GCC unroll 6") for (int e = 0; e < 6; e++)
        o->h[e] = !want_h(w, e) ? ivz() : vpick(iz(a->h[e]), a->h[e], lin(a->h[e], kind, c));
}

/* op_branch's Hessian: a decided lane takes its branch's entries (abs: +a'' or, where a''
 * is not exactly 0, −a''), a free one set_whole_derivs' (0 where the operands' partials in
 * i and j and their entries are all exactly 0, or outside w; else the whole line). */
INLINE void branch_h(vh *o, const ism_instr *in, const vj *r, const vh *hr, unsigned w,
                     v4i free, v4i took_a)
{
    const vj *a = &r[in->a];
    const vh *ah = &hr[in->a];
    bool rr = in->op == ISM_OP_MIN_RR || in->op == ISM_OP_MAX_RR;
    vh zero_h; /* branch_b's constant: every partial 0 */
    _Pragma("GCC unroll 6") for (int e = 0; e < 6; e++)
        zero_h.h[e] = ivz();
    const vh *bh = rr ? &hr[in->b] : &zero_h;
    v4i flat[3];
    _Pragma("GCC unroll 3") for (int k = 0; k < 3; k++) {
        v4i none = {-1, -1, -1, -1};
        flat[k] = !(w >> k & 1) ? none : rr ? iz(a->d[k]) & iz(r[in->b].d[k]) : iz(a->d[k]);
    }
    _Pragma("GCC unroll 6") for (int e = 0; e < 6; e++) {
        if (!want_h(w, e)) {
            o->h[e] = ivz();
            continue;
        }
        vi ha = ah->h[e], hb = bh->h[e];
        vi taken = in->op != ISM_OP_ABS ? vpick(took_a, ha, hb)
                                        : vpick(took_a | iz(ha), ha, v_neg(ha));
        v4i z = flat[ism_ivjet_hi[e]] & flat[ism_ivjet_hj[e]] & iz(ha) & iz(hb);
        o->h[e] = vpick(free, vpick(z, ivz(), ivwhole()), taken);
    }
}

/* The Hessian of one instruction whose value and first partials step has just written; u is
 * SQUARE's and POWI's operand value as it stood before that write (op_unary reads it first,
 * so the two agree when the output register is the operand's). */
INLINE void hstep(const ism_instr *in, const vj *r, vh *hr, unsigned w, v4i free, v4i took_a,
                  vi u)
{
    vh *o = &hr[in->out];
    const vj *a = &r[in->a];
    const vh *ah = &hr[in->a];
    double c = in->imm;
    switch (in->op) {
    case ISM_OP_CONST:
        _Pragma("GCC unroll 6") for (int e = 0; e < 6; e++)
            o->h[e] = ivz();
        break;
    case ISM_OP_COPY: case ISM_OP_ADD_RC: each_h(o, ah, LIN_COPY, c, w); break;
    case ISM_OP_NEG: case ISM_OP_SUB_CR: each_h(o, ah, LIN_NEG, c, w); break;
    case ISM_OP_MUL_RC: each_h(o, ah, LIN_MUL, c, w); break;
    case ISM_OP_DIV_RC: each_h(o, ah, LIN_DIV, c, w); break;
    case ISM_OP_ADD_RR: case ISM_OP_SUB_RR: {
        const vh *bh = &hr[in->b];
        bool sub = in->op == ISM_OP_SUB_RR;
        _Pragma("GCC unroll 6") for (int e = 0; e < 6; e++)
            o->h[e] = !want_h(w, e) ? ivz()
                      : sub         ? subz(ah->h[e], bh->h[e])
                                    : addz(ah->h[e], bh->h[e]);
        break;
    }
    case ISM_OP_MUL_RR: {
        const vj *b = &r[in->b];
        const vh *bh = &hr[in->b];
        _Pragma("GCC unroll 6") for (int e = 0; e < 6; e++) {
            if (!want_h(w, e)) {
                o->h[e] = ivz();
                continue;
            }
            int i = ism_ivjet_hi[e], j = ism_ivjet_hj[e];
            vi cross = addz(mulz(a->d[i], b->d[j]), mulz(a->d[j], b->d[i]));
            o->h[e] = addz(addz(mulz(ah->h[e], b->v), mulz(a->v, bh->h[e])), cross);
        }
        break;
    }
    case ISM_OP_SQUARE: case ISM_OP_POWI: { /* chain_hess: g'(U), g''(U) as op_unary */
        vi g1, g2;
        if (in->op == ISM_OP_SQUARE) {
            g1 = v_mul_c(u, 2.0);
            g2 = (vi){splat(2.0), splat(2.0)};
        } else {
            unsigned n = in->b;
            g1 = v_mul_c(v_powi(u, n - 1), (double)n);
            g2 = v_mul_c(v_powi(u, n - 2), (double)n * (double)(n - 1));
        }
        _Pragma("GCC unroll 6") for (int e = 0; e < 6; e++)
            o->h[e] = !want_h(w, e) ? ivz() : addz(mulz(g1, ah->h[e]), mulz(g2, dd_of(a, e)));
        break;
    }
    case ISM_OP_MIN_RR: case ISM_OP_MIN_RC: case ISM_OP_MAX_RR: case ISM_OP_MAX_RC:
    case ISM_OP_ABS:
        branch_h(o, in, r, hr, w, free, took_a);
        break;
    default: /* lanes_take lets no other operation in */
        __builtin_trap();
    }
    v4i bad = {0, 0, 0, 0};
    _Pragma("GCC unroll 6") for (int e = 0; e < 6; e++)
        bad |= (v4i)(o->h[e].lo != o->h[e].lo) | (v4i)(o->h[e].hi != o->h[e].hi);
    if (__builtin_expect((bad[0] | bad[1] | bad[2] | bad[3]) != 0, 0)) {
        _Pragma("GCC unroll 6") for (int e = 0; e < 6; e++)
            o->h[e] = (vi){vnan_to(o->h[e].lo, -INFINITY), vnan_to(o->h[e].hi, INFINITY)};
    }
}

/* The second-order pass over one group's registers r, hr (the variables loaded). */
INLINE void run_jet_group(const ism_tape *t, vj *r, vh *hr, bool branches)
{
    const unsigned all = ism_ivjet_want(7u, 1, false);
    for (size_t i = 0; i < t->len; i++) {
        const ism_instr *in = &t->code[i];
        unsigned deps = ISM_FREE_ALL & ~(unsigned)in->free_of;
        unsigned w = in->free_of == 0 ? 7u : deps;
        unsigned w2 = in->free_of == 0 ? all : ism_ivjet_want(deps, 1, in->smooth);
        v4i took_a = {0, 0, 0, 0};
        bool unary = in->op == ISM_OP_SQUARE || in->op == ISM_OP_POWI;
        vi u = unary ? r[in->a].v : ivz(); /* before step's write: out may be a */
        v4i free = step(in, r, w, branches, &took_a);
        hstep(in, r, hr, w2, free, took_a, u);
    }
}

/* hess_only over one group of the batched gradient pass's records rec (its part of each
 * instruction's): every instruction's value and first partials copied from them into r,
 * then its Hessian by hstep (no min, max or abs: the records are of tapes without them). */
INLINE void run_hess_group(const ism_tape *t, const vj *rec, vj *r, vh *hr)
{
    const unsigned all = ism_ivjet_want(7u, 1, false);
    const v4i none = {0, 0, 0, 0};
    for (size_t i = 0; i < t->len; i++) {
        const ism_instr *in = &t->code[i];
        unsigned deps = ISM_FREE_ALL & ~(unsigned)in->free_of;
        unsigned w2 = in->free_of == 0 ? all : ism_ivjet_want(deps, 1, in->smooth);
        r[in->out] = rec[i * ISM_IVG_GROUPS];
        hstep(in, r, hr, w2, none, none, r[in->a].v); /* after the copy, as hess_op reads */
    }
}

/* One group: from the records rec when not NULL, else the whole second-order pass (a copy
 * without the branches' steps for tapes without them). Inlined into each clone below. */
INLINE void run_jet_group_of(const ism_tape *t, const vj *rec, vj *r, vh *hr, bool branches)
{
    if (rec)
        run_hess_group(t, rec, r, hr);
    else if (branches)
        run_jet_group(t, r, hr, true);
    else
        run_jet_group(t, r, hr, false);
}

#if ISM_HAVE_AVX2_CLONE
ISM_AVX2_CLONE static void run_jet_avx2(const ism_tape *t, const vj *rec, vj *r, vh *hr,
                                        bool branches)
{
    run_jet_group_of(t, rec, r, hr, branches);
}
#endif

static void run_jet_base(const ism_tape *t, const vj *rec, vj *r, vh *hr, bool branches)
{
    run_jet_group_of(t, rec, r, hr, branches);
}

static void run_jet_lanes(const ism_tape *t, const vj *rec, vj *r, vh *hr, bool branches)
{
    _Pragma("GCC unroll 3") for (int k = 0; k < 3; k++)
        for (int e = 0; e < 6; e++)
            hr[k].h[e] = ivz();
#if ISM_HAVE_AVX2_CLONE
    if (ISM_RUN_AVX2())
        run_jet_avx2(t, rec, r, hr, branches);
    else
#endif
        run_jet_base(t, rec, r, hr, branches);
}

/* The group of the last batched gradient pass of t whose unused records are of every box of
 * box[0..n), box k's lane in it into lane[k]; -1 when there is none. */
static int record_group(const ism_ivjet_ws *ws, const ism_tape *t,
                        const ism_interval (*box)[3], size_t n, int lane[])
{
    if (ws->lane_t != t)
        return -1;
    int g = -1;
    for (size_t k = 0; k < n; k++) {
        int at = -1;
        for (uint32_t m = ws->lane_ok; m && at < 0; m &= m - 1) {
            int j = __builtin_ctz(m);
            if (memcmp(box[k], ws->lane_box[j], sizeof ws->lane_box[j]) == 0)
                at = j;
        }
        if (at < 0 || (g >= 0 && at / VL != g))
            return -1;
        g = at / VL;
        lane[k] = at % VL;
    }
    return g;
}

/* Box k's jet from lane j of group g of the registers r, hr (t's result). */
static void lane_jet(const ism_tape *t, const ism_ivjet_ws *ws, size_t g, size_t j,
                     ism_ivjet *out)
{
    const vj *res = (const vj *)ws->jet_regs + g * ws->nregs + t->result;
    const vh *hres = (const vh *)ws->jet_hregs + g * ws->nregs + t->result;
    out->v = iv(res->v.lo[j], res->v.hi[j]);
    for (int k = 0; k < 3; k++)
        out->d[k] = iv(res->d[k].lo[j], res->d[k].hi[j]);
    for (int e = 0; e < 6; e++)
        out->h[e] = iv(hres->h[e].lo[j], hres->h[e].hi[j]);
}

bool ism_eval_interval_jet_lanes(const ism_tape *t, ism_ivjet_ws *ws,
                                 const ism_interval (*box)[3], size_t n, ism_ivjet *out)
{
    bool branches;
    if (!ws || !t || !n || n > ISM_IVGRAD_BATCH || ws->nregs < t->nregs ||
        !lanes_take(t, &branches))
        return false;
    if (!ws->jet_regs) {
        ws->jet_regs = ism_line_alloc((size_t)ws->nregs * ISM_IVG_REG * sizeof(double));
        ws->jet_hregs = ism_line_alloc((size_t)ws->nregs * ISM_IVG_GROUPS * sizeof(vh));
        if (!ws->jet_regs || !ws->jet_hregs) {
            free(ws->jet_regs);
            free(ws->jet_hregs);
            ws->jet_regs = ws->jet_hregs = NULL;
            return false;
        }
    }
    int lane[ISM_IVGRAD_BATCH];
    int rg = branches ? -1 : record_group(ws, t, box, n, lane);
    if (rg >= 0) { /* every box's records in one group: hess_only's lanes, in group 0 */
        vj *r = (vj *)ws->jet_regs;
        load_group(r, (const ism_interval (*)[3])ws->lane_box, ws->lane_n, (size_t)rg);
        run_jet_lanes(t, (const vj *)ws->lane_kept + rg, r, (vh *)ws->jet_hregs, false);
        for (size_t k = 0; k < n; k++) {
            lane_jet(t, ws, 0, (size_t)lane[k], &out[k]);
            ws->lane_ok &= ~(1u << (rg * VL + lane[k])); /* used: as the one-box jet's */
        }
        return true;
    }
    size_t ng = (n + VL - 1) / VL;
    for (size_t g = 0; g < ng; g++) {
        vj *r = (vj *)ws->jet_regs + g * ws->nregs;
        load_group(r, box, n, g);
        run_jet_lanes(t, NULL, r, (vh *)ws->jet_hregs + g * ws->nregs, branches);
    }
    for (size_t b = 0; b < n; b++)
        lane_jet(t, ws, b / VL, b % VL, &out[b]);
    return true;
}
