/* eval_interval_grad_batch.c — interval enclosures of f and ∇f over up to ISM_IVGRAD_BATCH
 * boxes at once (interval_jet.h's ism_eval_interval_grad_batch): the gradient pass of
 * eval_interval_jet.c on tapes of affine operations, +, −, ×, squares and integer powers,
 * each instruction one step over every box. Each lane computes exactly what
 * ism_eval_interval_grad_kept computes over its box, operation for operation: the same
 * outward rounding (interval_ops.h's down1 / up1, as IEEE operations element by element),
 * products' bounds from their four corner products in iv_mul's order (a NaN corner counted
 * as 0), the exact zeros of derivatives kept and skipped as mulz / addz / subz do (as bit
 * masks with the same outcome), the partials a value does not depend on (free_of) written
 * as 0, and NaN bounds turned into infinities; so the two agree bit for bit and a caller
 * may use either. Its records (one per lane, interval_jet_ws.h) let the jet over the same
 * box compute only the Hessian, as the scalar pass's record does.
 *
 * min, max and abs are taken as ism_eval_interval_grad takes them with no branch forced
 * (eval_interval_jet.c's op_branch), lane by lane: the value the natural enclosure, the
 * partials those of the branch the lane's box decides, or at a free kink (both branches
 * allowed) the whole line but 0 where both operands' partials are exactly [0, 0] over the
 * lane's box (or the variable is outside the want: set_whole_derivs' test, not dependence:
 * x² over x = [0, 0] depends on x, its partial is 0); each lane's free kinks are kept in the
 * workspace (ism_ivjet_lane_kinks) as that pass would list them. Tapes with these give no
 * records (hess_only takes none of them).
 *
 * Why: the dual mesher takes f and ∇f's natural enclosure over most children of a split
 * node (octree/dual_classify.c, ism_dual_classify_tail); one box costs ~1,700 instructions
 * on the torus's short tape, most of them the instruction dispatch and the zero tests a
 * batch shares.
 *
 * The same lanes give whole jets (ism_eval_interval_jet_lanes, for the singular search's
 * smooth_tests): each instruction's value and partials as above, then its Hessian entries
 * by eval_interval_jet.c's rules, bit for bit ism_eval_interval_jet's; or, right after a
 * batched gradient pass over the same boxes (tapes without kinks), the Hessians alone from
 * its records, as that file's hess_only takes them from one box's. In registers of their
 * own, so that the gradient pass (its records, kinks and registers) stands.
 *
 * The lanes are walked in groups of ISM_IVG_VL, each one value of GCC's vector extension
 * (AVX2 registers in the AVX2 clone, chosen at run time, pairs of SSE2 ones otherwise); a
 * batch is padded up to whole groups by repeating its last box. */
#include "core/eval/avx2_clone.h"
#include "core/eval/interval_jet_ws.h"
#include "core/eval/interval_lanes.h"
#include "core/eval/workspace.h"
#include "core/expr/tape.h"
#include "core/util/cache_line.h"

#include <stdlib.h>
#include <string.h>

#define VL ISM_IVG_VL
_Static_assert(VL == 4, "a group of lanes is one v4d (lanes4.h)");

/* One register of a group: the value and the three first partials (the records' layout:
 * interval_jet_ws.h). */
typedef struct vj {
    vi v, d[3];
} vj;
_Static_assert(sizeof(vj) == 8 * VL * sizeof(double), "a group's register is 8 vectors");

/* is_zero: both bounds ±0 */
INLINE v4i iz(vi u) { return (v4i)((((v4u)u.lo | (v4u)u.hi) << 1) == (v4u){0, 0, 0, 0}); }

INLINE vi vpick(v4i m, vi a, vi b) { return (vi){v4_pick(m, a.lo, b.lo), v4_pick(m, a.hi, b.hi)}; }

INLINE vi v_div_c(vi a, double c)
{
    v4d p = a.lo / splat(c), q = a.hi / splat(c);
    return c > 0.0 ? (vi){vdown1(p), vup1(q)} : (vi){vdown1(q), vup1(p)};
}

INLINE vi v_add_c(vi a, double c) { return (vi){vdown1(a.lo + splat(c)), vup1(a.hi + splat(c))}; }
INLINE vi v_c_sub(double c, vi a) { return (vi){vdown1(splat(c) - a.hi), vup1(splat(c) - a.lo)}; }

/* iv_powi lane by lane (its branches differ by lane; integer powers are rare) */
INLINE vi v_powi(vi a, unsigned n)
{
    double lo[VL], hi[VL];
    __builtin_memcpy(lo, &a.lo, sizeof lo);
    __builtin_memcpy(hi, &a.hi, sizeof hi);
    for (int j = 0; j < VL; j++) {
        ism_interval r = iv_powi(iv(lo[j], hi[j]), n);
        lo[j] = r.lo;
        hi[j] = r.hi;
    }
    vi r;
    __builtin_memcpy(&r.lo, lo, sizeof lo);
    __builtin_memcpy(&r.hi, hi, sizeof hi);
    return r;
}

/* mulz / addz / subz: exact zeros stay exact */
INLINE vi mulz(vi a, vi b) { return vpick(iz(a) | iz(b), ivz(), v_mul(a, b)); }
INLINE vi addz(vi a, vi b) { return vpick(iz(a), b, vpick(iz(b), a, v_add(a, b))); }
INLINE vi subz(vi a, vi b) { return vpick(iz(b), a, vpick(iz(a), v_neg(b), v_sub(a, b))); }

/* The affine operations' map of one interval (lin_copy / lin_neg / lin_mul / lin_div). */
enum { LIN_COPY, LIN_NEG, LIN_MUL, LIN_DIV };

INLINE vi lin(vi u, int kind, double c)
{
    switch (kind) {
    case LIN_NEG: return v_neg(u);
    case LIN_MUL: return v_mul_c(u, c);
    case LIN_DIV: return v_div_c(u, c);
    default: return u;
    }
}

/* eval_interval_jet.c's each(): the map on the value and on every partial in w that is not
 * exactly 0 (kept as it is). */
INLINE void each(vj *o, const vj *a, int kind, double c, unsigned w)
{
    o->v = lin(a->v, kind, c);
    _Pragma("GCC unroll 3") for (int k = 0; k < 3; k++)
        o->d[k] = !(w >> k & 1) ? ivz() : vpick(iz(a->d[k]), a->d[k], lin(a->d[k], kind, c));
}

/* ism_iv_whole in every lane */
INLINE vi ivwhole(void) { return (vi){splat(-INFINITY), splat(INFINITY)}; }

/* op_branch of a min, max or abs with no branch forced (eval_interval_jet.c), lane by lane:
 * the value iv_min / iv_max / iv_abs; decided_branch's strict tests (a NaN bound decides
 * nothing); a decided lane takes the branch's partials (take_derivs; abs: +a' or, as
 * each(lin_neg) does, −a' but where a' is exactly 0, kept as it is), a free one
 * set_whole_derivs' (0 where both operands' partials are exactly [0, 0] over the lane's
 * box, or the variable is outside w; else the whole line).
 * Returns the free lanes. */
INLINE v4i branch(vj *o, const ism_instr *in, const vj *r, unsigned w, v4i *took_a)
{
    const vj *a = &r[in->a];
    bool rr = in->op == ISM_OP_MIN_RR || in->op == ISM_OP_MAX_RR;
    vj cst; /* branch_b's: the constant (RC) or all 0 (abs); partials 0 */
    cst.v = in->op == ISM_OP_ABS ? ivz() : (vi){splat(in->imm), splat(in->imm)};
    _Pragma("GCC unroll 3") for (int k = 0; k < 3; k++)
        cst.d[k] = ivz();
    const vj *b = rr ? &r[in->b] : &cst;
    vi av = a->v, bv = b->v;
    v4i side_a, side_b;
    switch (in->op) {
    case ISM_OP_MIN_RR: case ISM_OP_MIN_RC:
        o->v = (vi){vmin(av.lo, bv.lo), vmin(av.hi, bv.hi)};
        side_a = (v4i)(av.hi < bv.lo);
        side_b = (v4i)(bv.hi < av.lo);
        break;
    case ISM_OP_MAX_RR: case ISM_OP_MAX_RC:
        o->v = (vi){vmax(av.lo, bv.lo), vmax(av.hi, bv.hi)};
        side_a = (v4i)(av.lo > bv.hi);
        side_b = (v4i)(bv.lo > av.hi);
        break;
    default: { /* ABS: iv_abs */
        v4d inner = v4_pick((v4i)(av.hi <= splat(0.0)), -av.hi, splat(0.0));
        o->v = (vi){v4_pick((v4i)(av.lo >= splat(0.0)), av.lo, inner),
                    vmax(vabs(av.lo), vabs(av.hi))};
        side_a = (v4i)(av.lo > splat(0.0));
        side_b = (v4i)(av.hi < splat(0.0));
        break;
    }
    }
    side_b &= ~side_a; /* decided_branch asks A first */
    v4i free = ~(side_a | side_b);
    *took_a = side_a;
    _Pragma("GCC unroll 3") for (int k = 0; k < 3; k++) {
        if (!(w >> k & 1)) {
            o->d[k] = ivz();
            continue;
        }
        vi da = a->d[k], db = b->d[k];
        vi taken = in->op != ISM_OP_ABS ? vpick(side_a, da, db)
                                        : vpick(side_a | iz(da), da, v_neg(da));
        vi loose = vpick(iz(da) & iz(db), ivz(), ivwhole());
        o->d[k] = vpick(free, loose, taken);
    }
    return free;
}

/* One instruction of the gradient pass (jet_op with second = 0), on registers r, in jet_op's
 * order of reads and writes (an output register may be an operand's). Returns the lanes
 * where it is a free kink (only min, max and abs have any; *took_a: the lanes whose box
 * decides their first branch). */
INLINE v4i step(const ism_instr *in, vj *r, unsigned w, bool branches, v4i *took_a)
{
    v4i free = {0, 0, 0, 0};
    vj *o = &r[in->out];
    const vj *a = &r[in->a];
    double c = in->imm;
    switch (in->op) {
    case ISM_OP_CONST:
        o->v = (vi){splat(c), splat(c)};
        _Pragma("GCC unroll 3") for (int k = 0; k < 3; k++)
            o->d[k] = ivz();
        break;
    case ISM_OP_NEG: each(o, a, LIN_NEG, c, w); break;
    case ISM_OP_SUB_CR:
        each(o, a, LIN_NEG, c, w);
        o->v = v_c_sub(c, a->v);
        break;
    case ISM_OP_MUL_RC: each(o, a, LIN_MUL, c, w); break;
    case ISM_OP_DIV_RC: each(o, a, LIN_DIV, c, w); break;
    case ISM_OP_ADD_RC:
        each(o, a, LIN_COPY, c, w);
        o->v = v_add_c(a->v, c);
        break;
    case ISM_OP_ADD_RR: case ISM_OP_SUB_RR: {
        const vj *b = &r[in->b];
        bool sub = in->op == ISM_OP_SUB_RR;
        o->v = sub ? v_sub(a->v, b->v) : v_add(a->v, b->v);
        _Pragma("GCC unroll 3") for (int k = 0; k < 3; k++)
            o->d[k] = !(w >> k & 1) ? ivz() : sub ? subz(a->d[k], b->d[k]) : addz(a->d[k], b->d[k]);
        break;
    }
    case ISM_OP_MUL_RR: {
        const vj *b = &r[in->b];
        o->v = v_mul(a->v, b->v);
        _Pragma("GCC unroll 3") for (int k = 0; k < 3; k++)
            o->d[k] = !(w >> k & 1) ? ivz() : addz(mulz(a->d[k], b->v), mulz(a->v, b->d[k]));
        break;
    }
    case ISM_OP_SQUARE: case ISM_OP_POWI: { /* chain(): g(U), g'(U) from U first */
        vi u = a->v, g, g1;
        if (in->op == ISM_OP_SQUARE) {
            g = v_square(u);
            g1 = v_mul_c(u, 2.0);
        } else {
            g = v_powi(u, in->b);
            g1 = v_mul_c(v_powi(u, in->b - 1), (double)in->b);
        }
        o->v = g;
        _Pragma("GCC unroll 3") for (int k = 0; k < 3; k++)
            o->d[k] = !(w >> k & 1) ? ivz() : mulz(g1, a->d[k]);
        break;
    }
    case ISM_OP_COPY:
        each(o, a, LIN_COPY, c, w);
        break;
    case ISM_OP_MIN_RR: case ISM_OP_MIN_RC: case ISM_OP_MAX_RR: case ISM_OP_MAX_RC:
    case ISM_OP_ABS:
        if (branches) { /* else (the copy for tapes without them) as default */
            free = branch(o, in, r, w, took_a);
            break;
        }
        __builtin_trap();
    default: /* lanes_take lets no other operation in */
        __builtin_trap();
    }
    /* sanitize(): NaN bounds to the infinity on their side (a partial outside w is 0), all
     * of them once one is NaN (nearly never: one test for the whole register) */
    v4i bad = (v4i)(o->v.lo != o->v.lo) | (v4i)(o->v.hi != o->v.hi);
    _Pragma("GCC unroll 3") for (int k = 0; k < 3; k++)
        bad |= (v4i)(o->d[k].lo != o->d[k].lo) | (v4i)(o->d[k].hi != o->d[k].hi);
    if (__builtin_expect((bad[0] | bad[1] | bad[2] | bad[3]) != 0, 0)) {
        o->v = (vi){vnan_to(o->v.lo, -INFINITY), vnan_to(o->v.hi, INFINITY)};
        _Pragma("GCC unroll 3") for (int k = 0; k < 3; k++)
            o->d[k] = (vi){vnan_to(o->d[k].lo, -INFINITY), vnan_to(o->d[k].hi, INFINITY)};
    }
    return free;
}

/* The tape over one group's registers r (the variables loaded): without branches each
 * instruction's register recorded in keep (ISM_IVG_REG doubles an instruction, this
 * group's part); with them its free kinks' lanes (those in `lanes`: not padding) or'ed into
 * ws->lane_kinks[i] at bit `first` + lane and counted in nk[lane]. */
INLINE void run_group(const ism_tape *t, vj *r, vj *keep, ism_ivjet_ws *ws, uint32_t *nk,
                      unsigned lanes, unsigned first, bool branches)
{
    uint8_t *kinks = ws->lane_kinks;
    for (size_t i = 0; i < t->len; i++) {
        const ism_instr *in = &t->code[i];
        unsigned w = in->free_of == 0 ? 7u : ISM_FREE_ALL & ~(unsigned)in->free_of;
        v4i took_a;
        v4i free = step(in, r, w, branches, &took_a);
        if (!branches) /* a constant in each copy: records only without kinks */
            keep[i * ISM_IVG_GROUPS] = r[in->out];
        if (!branches || !ism_op_is_kink(in->op))
            continue;
        unsigned m = 0;
        _Pragma("GCC unroll 4") for (int j = 0; j < VL; j++)
            m |= free[j] ? 1u << j : 0u;
        m &= lanes;
        if (m && !kinks[i]) /* the first lane with a kink here: listed once */
            ws->lane_kink_at[ws->lane_nkink_at++] = (uint32_t)i;
        kinks[i] |= (uint8_t)(m << first);
        for (; m; m &= m - 1)
            nk[__builtin_ctz(m)]++;
    }
}

#if ISM_HAVE_AVX2_CLONE
ISM_AVX2_CLONE static void run_avx2(const ism_tape *t, vj *r, vj *keep, ism_ivjet_ws *ws,
                                    uint32_t *nk, unsigned lanes, unsigned first, bool branches)
{
    if (branches) /* two copies: a tape without kinks pays no kink test an instruction */
        run_group(t, r, keep, ws, nk, lanes, first, true);
    else
        run_group(t, r, keep, ws, nk, lanes, first, false);
}
#endif

static void run_base(const ism_tape *t, vj *r, vj *keep, ism_ivjet_ws *ws, uint32_t *nk,
                     unsigned lanes, unsigned first, bool branches)
{
    if (branches)
        run_group(t, r, keep, ws, nk, lanes, first, true);
    else
        run_group(t, r, keep, ws, nk, lanes, first, false);
}

/* The pass's registers, records and kink bytes for t, made or grown; false when out of
 * memory. */
static inline __attribute__((always_inline)) bool reserve(ism_ivjet_ws *ws,
                                                            const ism_tape *t)
{
    if (!ws->lane_regs) {
        ws->lane_regs = ism_line_alloc((size_t)ws->nregs * ISM_IVG_REG * sizeof(double));
        if (!ws->lane_regs)
            return false;
    }
    if (ws->lane_cap < t->len) {
        free(ws->lane_kept);
        free(ws->lane_kinks);
        free(ws->lane_kink_at);
        ws->lane_cap = 0;
        ws->lane_kept = ism_line_alloc(t->len * ISM_IVG_REG * sizeof(double));
        ws->lane_kinks = malloc(t->len);
        ws->lane_kink_at = malloc(t->len * sizeof *ws->lane_kink_at);
        if (!ws->lane_kept || !ws->lane_kinks || !ws->lane_kink_at)
            return false;
        ws->lane_cap = t->len;
    }
    return true;
}

/* Every instruction of t is one the lanes take: those hess_only takes, and min, max, abs. */
static bool lanes_take(const ism_tape *t, bool *branches)
{
    *branches = false;
    if (ism_ivjet_tape_hess_from_kept(t)) /* the smooth tapes' one scan, as the batch's */
        return true;
    for (size_t i = 0; i < t->len; i++) {
        int op = t->code[i].op;
        if (ism_op_is_kink(op))
            *branches = true;
        else if (!ism_ivjet_hess_from_kept(op))
            return false;
    }
    return true;
}

/* Group g's variables (registers 0-2 of r) over box[0..n), padded with the last box:
 * load_box's, a bound not a number, or lo > hi, giving the whole line. */
static inline __attribute__((always_inline)) void
load_group(vj *r, const ism_interval (*box)[3], size_t n, size_t g)
{
    size_t b[VL];
    for (size_t j = 0; j < VL; j++)
        b[j] = g * VL + j < n ? g * VL + j : n - 1;
    for (int k = 0; k < 3; k++) {
        vi u = {{box[b[0]][k].lo, box[b[1]][k].lo, box[b[2]][k].lo, box[b[3]][k].lo},
                {box[b[0]][k].hi, box[b[1]][k].hi, box[b[2]][k].hi, box[b[3]][k].hi}};
        v4i ok = u.lo <= u.hi;
        r[k].v = (vi){v4_pick(ok, u.lo, splat(-INFINITY)), v4_pick(ok, u.hi, splat(INFINITY))};
        for (int m = 0; m < 3; m++)
            r[k].d[m] = m == k ? (vi){splat(1.0), splat(1.0)} : ivz();
    }
}

/* The pass over box[0..n) into out; with branches (t holds min, max or abs) the kinks' lanes
 * into ws->lane_kinks and their counts into ws->lane_nk (without, lane_nk untouched), else
 * the records kept. */
static inline __attribute__((always_inline)) void
run_lanes(const ism_tape *t, ism_ivjet_ws *ws, const ism_interval (*box)[3], size_t n,
          ism_ivgrad *out, bool branches)
{
    if (branches) {
        memset(ws->lane_kinks, 0, t->len);
        memset(ws->lane_nk, 0, sizeof ws->lane_nk);
    }
    ws->lane_nkink_at = 0;
    size_t ng = (n + VL - 1) / VL;
    for (size_t g = 0; g < ng; g++) {
        vj *r = (vj *)ws->lane_regs + g * ws->nregs;
        vj *rec = (vj *)ws->lane_kept + g; /* written without branches only */
        load_group(r, box, n, g);
        unsigned lanes = n - g * VL >= VL ? (1u << VL) - 1 : (1u << (n - g * VL)) - 1;
        unsigned first = (unsigned)(g * VL);
#if ISM_HAVE_AVX2_CLONE
        if (ISM_RUN_AVX2())
            run_avx2(t, r, rec, ws, ws->lane_nk + first, lanes, first, branches);
        else
#endif
            run_base(t, r, rec, ws, ws->lane_nk + first, lanes, first, branches);
    }
    for (size_t b = 0; b < n; b++) {
        const double *res = (const double *)((const vj *)ws->lane_regs +
                                             (b / VL) * ws->nregs + t->result);
        size_t j = b % VL;
        out[b].v = iv(res[j], res[VL + j]);
        for (int k = 0; k < 3; k++)
            out[b].d[k] = iv(res[(2 + 2 * k) * VL + j], res[(3 + 2 * k) * VL + j]);
        memcpy(ws->lane_box[b], box[b], sizeof ws->lane_box[b]);
    }
    ws->lane_t = t;
    ws->lane_n = (uint32_t)n;
    ws->lane_pass_t = t;
}

/* The checks both entry points make; ws's lane state reset (no records, no pass). */
static inline __attribute__((always_inline)) bool can_run(const ism_tape *t, ism_ivjet_ws *ws,
                                                            size_t n)
{
    if (!ws || !t || !n || n > ISM_IVGRAD_BATCH || ws->nregs < t->nregs)
        return false;
    ws->lane_ok = 0; /* before reserve, which may free the records and fail to grow them */
    ws->lane_pass_t = NULL;
    return true;
}

bool ism_eval_interval_grad_batch(const ism_tape *t, ism_ivjet_ws *ws,
                                  const ism_interval (*box)[3], size_t n, ism_ivgrad *out)
{
    if (!t || !ism_ivjet_tape_hess_from_kept(t) || !can_run(t, ws, n) || !reserve(ws, t))
        return false;
    run_lanes(t, ws, box, n, out, false);
    ws->lane_ok = (1u << n) - 1;
    return true;
}

bool ism_eval_interval_grad_lanes(const ism_tape *t, ism_ivjet_ws *ws,
                                  const ism_interval (*box)[3], size_t n, ism_ivgrad *out,
                                  uint32_t *nk)
{
    bool branches;
    if (!t || !lanes_take(t, &branches) || !can_run(t, ws, n) || !reserve(ws, t))
        return false;
    run_lanes(t, ws, box, n, out, branches);
    ws->lane_ok = branches ? 0 : (1u << n) - 1;
    if (!branches) /* no kink: run_lanes left lane_nk as it was */
        memset(ws->lane_nk, 0, sizeof ws->lane_nk);
    if (nk)
        memcpy(nk, ws->lane_nk, n * sizeof *nk);
    return true;
}

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
