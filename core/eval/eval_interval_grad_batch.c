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
 * Why: the dual mesher takes f and ∇f's natural enclosure over most children of a split
 * node (octree/dual_classify.c, ism_dual_classify_tail); one box costs ~1,700 instructions
 * on the torus's short tape, most of them the instruction dispatch and the zero tests a
 * batch shares.
 *
 * The lanes are walked in groups of ISM_IVG_VL, each one value of GCC's vector extension
 * (AVX2 registers in the AVX2 clone, chosen at run time, pairs of SSE2 ones otherwise); a
 * batch is padded up to whole groups by repeating its last box. */
#include "core/eval/avx2_clone.h"
#include "core/eval/interval_jet_ws.h"
#include "core/eval/interval_lanes.h"
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

/* One instruction of the gradient pass (jet_op with second = 0), on registers r, in jet_op's
 * order of reads and writes (an output register may be an operand's). */
INLINE void step(const ism_instr *in, vj *r, unsigned w)
{
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
    default: /* ism_ivjet_tape_hess_from_kept lets no other operation in */
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
}

/* The tape over one group's registers r (the variables loaded), each instruction's
 * register recorded in keep (ISM_IVG_REG doubles an instruction, this group's part). */
INLINE void run_group(const ism_tape *t, vj *r, vj *keep)
{
    for (size_t i = 0; i < t->len; i++) {
        const ism_instr *in = &t->code[i];
        unsigned w = in->free_of == 0 ? 7u : ISM_FREE_ALL & ~(unsigned)in->free_of;
        step(in, r, w);
        keep[i * ISM_IVG_GROUPS] = r[in->out];
    }
}

#if ISM_HAVE_AVX2_CLONE
ISM_AVX2_CLONE static void run_avx2(const ism_tape *t, vj *r, vj *keep)
{
    run_group(t, r, keep);
}
#endif

static void run_base(const ism_tape *t, vj *r, vj *keep) { run_group(t, r, keep); }

/* The pass's registers and records for t, made or grown; false when out of memory. */
static bool reserve(ism_ivjet_ws *ws, const ism_tape *t)
{
    if (!ws->lane_regs) {
        ws->lane_regs = ism_line_alloc((size_t)ws->nregs * ISM_IVG_REG * sizeof(double));
        if (!ws->lane_regs)
            return false;
    }
    if (ws->lane_cap < t->len) {
        free(ws->lane_kept);
        ws->lane_cap = 0;
        ws->lane_kept = ism_line_alloc(t->len * ISM_IVG_REG * sizeof(double));
        if (!ws->lane_kept)
            return false;
        ws->lane_cap = t->len;
    }
    return true;
}

bool ism_eval_interval_grad_batch(const ism_tape *t, ism_ivjet_ws *ws,
                                  const ism_interval (*box)[3], size_t n, ism_ivgrad *out)
{
    if (!ws || !t || !n || n > ISM_IVGRAD_BATCH || ws->nregs < t->nregs ||
        !ism_ivjet_tape_hess_from_kept(t))
        return false;
    ws->lane_ok = 0; /* before reserve, which may free the records and fail to grow them */
    if (!reserve(ws, t))
        return false;
    size_t ng = (n + VL - 1) / VL;
    for (size_t g = 0; g < ng; g++) {
        vj *r = (vj *)ws->lane_regs + g * ws->nregs, *keep = (vj *)ws->lane_kept + g;
        /* load_box: a bound not a number, or lo > hi, gives the whole line */
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
#if ISM_HAVE_AVX2_CLONE
        if (ISM_RUN_AVX2())
            run_avx2(t, r, keep);
        else
#endif
            run_base(t, r, keep);
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
    ws->lane_ok = (1u << n) - 1;
    return true;
}
