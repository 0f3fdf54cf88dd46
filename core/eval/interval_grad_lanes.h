/* interval_grad_lanes.h — one instruction of the batched interval gradient pass over a group
 * of ISM_IVG_VL lanes (step: the value and first partials, each lane bit for bit what
 * eval_interval_jet.c's gradient pass computes over its box), the loading of a group's
 * variables, and which tapes the lanes take. Shared by the batched gradient pass
 * (eval_interval_grad_batch.c) and the batched jets (eval_interval_jet_lanes.c), which add
 * the Hessian entries after each step. Internal to core/eval; INLINE helpers only
 * (lanes4.h's rule), its unprefixed names (vj, iz, vpick, lin, each, branch, step, ...)
 * reserved in the files that include it, as interval_lanes.h's are.
 *
 * The lanes are walked in groups of ISM_IVG_VL, each one value of GCC's vector extension
 * (AVX2 registers in the AVX2 clone, chosen at run time, pairs of SSE2 ones otherwise); a
 * batch is padded up to whole groups by repeating its last box. */
#ifndef ISM_INTERVAL_GRAD_LANES_H
#define ISM_INTERVAL_GRAD_LANES_H

#include "core/eval/interval_jet_ws.h"
#include "core/eval/interval_lanes.h"
#include "core/eval/workspace.h"
#include "core/expr/tape.h"

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

/* Group g's variables (registers 0-2 of r) over box[0..n), padded with the last box:
 * load_box's, a bound not a number, or lo > hi, giving the whole line. */
INLINE void load_group(vj *r, const ism_interval (*box)[3], size_t n, size_t g)
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

/* Every instruction of t is one the lanes take: those hess_only takes, and min, max, abs. */
INLINE bool lanes_take(const ism_tape *t, bool *branches)
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

#endif
