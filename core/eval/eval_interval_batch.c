/* eval_interval_batch.c — the interval evaluator over many boxes at once (an octree node's
 * eight children, say): registers hold the lower bounds and the NEGATED upper bounds of up to
 * ISM_IV_CHUNK boxes as two arrays, and each instruction is one loop over the boxes.
 *
 * Outward rounding by the rounding mode: the whole batch runs rounding toward -inf (one
 * MXCSR write per call, restored at the end), so a lower bound is the operation itself, and
 * an upper bound hi is kept as nh = -hi, for which rounding down is rounding hi up: a + b is
 * [al + bl, -(anh + bnh)] with two additions and nothing else. Each bound is the correctly
 * rounded outward one, at least as tight as ism_eval_interval's one-ulp widening of a
 * rounded-to-nearest value (so these intervals lie inside the single-box ones, up to the
 * libm operations, which run box by box in round-to-nearest with interval_ops.h's rules).
 *
 * Vector code: one switch per instruction per chunk, loops over a whole number of AVX2
 * vectors with restrict pointers (no instruction writes a register it reads).
 *
 * No NaN from inf - inf: every register keeps lo < +inf and nh < +inf (an interval holds a
 * finite number), so sums and products by a finite constant never meet +inf and -inf and
 * need no check; the few places that could break it (constants, the boxes, the box-by-box
 * operations) clamp +inf to DBL_MAX, which only widens a degenerate [inf, inf]. Products
 * of two registers can still be 0 * inf: one test per vector, and a vector that has one
 * counts it as 0 (iv_mul's rule). This file is compiled with
 * -frounding-math (Makefile) so gcc keeps every operation as written (no -(a*b) for
 * a*(-b)). */
#include "core/eval/avx2_clone.h"
#include "core/eval/interval_lanes.h"
#include "core/eval/interval_ops.h"
#include "core/eval/threaded.h"
#include "core/eval/workspace.h"

#include <fenv.h>
#include <float.h>
#include <string.h>
#if defined(__x86_64__) || defined(__i386__)
#include <xmmintrin.h>
#endif

/* Lanes are processed in multiples of this (one AVX2 vector of doubles). */
#define LANES 4

#define ALWAYS_INLINE inline __attribute__((always_inline))

/* Tells gcc that m is a whole number of vectors (no remainder loop). */
#define WHOLE_VECTORS(m) \
    do { if ((m) % LANES != 0) __builtin_unreachable(); } while (0)

/* ---- the rounding mode ---- */

#if defined(__x86_64__) || defined(__i386__)
typedef unsigned rounding;
/* MXCSR's rounding-control field (bits 13-14) and its round-down value. */
#define MXCSR_RC_MASK 0x6000u
#define MXCSR_RC_DOWN 0x2000u
#define MXCSR_RC_NEAREST 0x0000u
static ALWAYS_INLINE rounding rounding_get(void) { return _mm_getcsr(); }
static ALWAYS_INLINE void rounding_set(rounding r)
{
    __asm__ volatile("" ::: "memory"); /* no load or store moves across the switch */
    _mm_setcsr(r);
    __asm__ volatile("" ::: "memory");
}
static ALWAYS_INLINE rounding rounding_down(rounding r) { return (r & ~MXCSR_RC_MASK) | MXCSR_RC_DOWN; }
static ALWAYS_INLINE rounding rounding_nearest(rounding r) { return (r & ~MXCSR_RC_MASK) | MXCSR_RC_NEAREST; }
#else
typedef int rounding;
static ALWAYS_INLINE rounding rounding_get(void) { return fegetround(); }
static ALWAYS_INLINE void rounding_set(rounding r) { fesetround(r); }
static ALWAYS_INLINE rounding rounding_down(rounding r) { (void)r; return FE_DOWNWARD; }
static ALWAYS_INLINE rounding rounding_nearest(rounding r) { (void)r; return FE_TONEAREST; }
#endif

/* ---- the operations, rounding down; (l, nh) is [l, -nh] ---- */

/* A NaN bound becomes -inf (the whole side; for nh, hi = +inf), and +inf becomes DBL_MAX
 * (the register invariant above): one max and one min. */
static ALWAYS_INLINE double sane(double v)
{
    double m = v > -INFINITY ? v : -INFINITY;
    return m < DBL_MAX ? m : DBL_MAX;
}

#define KERNEL_RR(NAME, BODY)                                                                \
    static ALWAYS_INLINE void NAME(double *restrict ol, double *restrict onh,                \
                                   const double *restrict al, const double *restrict anh,    \
                                   const double *restrict bl, const double *restrict bnh,    \
                                   size_t m)                                                 \
    {                                                                                        \
        WHOLE_VECTORS(m);                                                                    \
        _Pragma("GCC unroll 2") for (size_t j = 0; j < m; j++) {                             \
            BODY                                                                             \
        }                                                                                    \
    }
#define KERNEL_RC(NAME, BODY)                                                                \
    static ALWAYS_INLINE void NAME(double *restrict ol, double *restrict onh,                \
                                   const double *restrict al, const double *restrict anh,    \
                                   double c, size_t m)                                       \
    {                                                                                        \
        WHOLE_VECTORS(m);                                                                    \
        _Pragma("GCC unroll 2") for (size_t j = 0; j < m; j++) {                             \
            BODY                                                                             \
        }                                                                                    \
    }

/* a + b = [al + bl, ah + bh]; a - b = [al - bh, ah - bl] = [al + bnh, -(anh + bl)]. With
 * every operand below +inf (and c finite: BATCH_STEP_AS checks) no sum is NaN, and rounding down
 * turns an overflow to +inf into DBL_MAX, so the results stay below +inf. */
KERNEL_RR(k_add, ol[j] = al[j] + bl[j]; onh[j] = anh[j] + bnh[j];)
KERNEL_RR(k_sub, ol[j] = al[j] + bnh[j]; onh[j] = anh[j] + bl[j];)
KERNEL_RC(k_add_c, ol[j] = al[j] + c; onh[j] = anh[j] - c;)
/* c - a = [c - ah, c - al] = [c + anh, -(al - c)]. */
KERNEL_RC(k_c_sub, ol[j] = c + anh[j]; onh[j] = al[j] - c;)
/* c > 0: [al c, ah c] = [al c, -(anh c)]; c < 0: [ah c, al c] = [anh (-c), -(al (-c))]. */
KERNEL_RC(k_mul_cpos, ol[j] = al[j] * c; onh[j] = anh[j] * c;)
KERNEL_RC(k_mul_cneg, ol[j] = anh[j] * -c; onh[j] = al[j] * -c;)
KERNEL_RC(k_neg, ol[j] = anh[j]; onh[j] = al[j]; (void)c;)
KERNEL_RC(k_copy, ol[j] = al[j]; onh[j] = anh[j]; (void)c;)
KERNEL_RR(k_min, ol[j] = ism_min(al[j], bl[j]); onh[j] = ism_max(anh[j], bnh[j]);)
KERNEL_RR(k_max, ol[j] = ism_max(al[j], bl[j]); onh[j] = ism_min(anh[j], bnh[j]);)
KERNEL_RC(k_min_c, ol[j] = ism_min(al[j], c); onh[j] = ism_max(anh[j], -c);)
KERNEL_RC(k_max_c, ol[j] = ism_max(al[j], c); onh[j] = ism_min(anh[j], -c);)

/* a^2: the lower bound is the square of the least |x| over a, max(al, -ah, 0) = max(al,
 * anh, 0) (iv_square's choice, without a branch); the upper bound from -al*al and -ah*ah
 * rounded down. */
static ALWAYS_INLINE ism_interval square_lane(double l, double nh)
{
    double h = -nh, least = ism_max(ism_max(l, nh), 0.0);
    return iv(least * least, ism_min(l * -l, nh * h));
}
KERNEL_RC(k_square, ism_interval r = square_lane(al[j], anh[j]); ol[j] = r.lo; onh[j] = r.hi;
          (void)c;)

/* a * b: the least of the four products for lo, the least of their negations for nh (a
 * product 0 * inf counts as 0, as in iv_mul). */
static ALWAYS_INLINE ism_interval mul_lane(double al, double anh, double bl, double bnh)
{
    double ah = -anh, bh = -bnh;
    return iv(min4(mul0(al, bl), mul0(al, bh), mul0(ah, bl), mul0(ah, bh)),
              min4(mul0(al, -bl), mul0(al, bnh), mul0(anh, bl), mul0(ah, bnh)));
}
KERNEL_RR(k_mul, ism_interval r = mul_lane(al[j], anh[j], bl[j], bnh[j]); ol[j] = r.lo;
          onh[j] = r.hi;)

/* a * b without the test for 0 * inf: returns nonzero when some lane may have had one (a
 * product NaN, or the sum of the four lower products NaN: then k_mul runs again). The upper
 * products are the lower ones' operands with a sign changed, so NaN in the same places. */
static ALWAYS_INLINE long long k_mul_finite(double *restrict ol, double *restrict onh,
                                            const double *restrict al,
                                            const double *restrict anh,
                                            const double *restrict bl,
                                            const double *restrict bnh, size_t m)
{
    long long bad = 0;
    WHOLE_VECTORS(m);
    _Pragma("GCC unroll 2") for (size_t j = 0; j < m; j++) {
        double ah = -anh[j], bh = -bnh[j];
        double p1 = al[j] * bl[j], p2 = al[j] * bh, p3 = ah * bl[j], p4 = ah * bh;
        ol[j] = min4(p1, p2, p3, p4);
        onh[j] = min4(al[j] * -bl[j], al[j] * bnh[j], anh[j] * bl[j], ah * bnh[j]);
        double sum = (p1 + p2) + (p3 + p4);
        bad |= (long long)(sum != sum);
    }
    return bad;
}

/* ---- the other operations: box by box with interval_ops.h, in round-to-nearest ---- */

static ism_interval nearest_op(const ism_instr *in, ism_interval a, ism_interval b)
{
    switch (in->op) {
    case ISM_OP_MUL_RC: return iv_mul_c(a, in->imm);
    case ISM_OP_DIV_RR: return iv_div(a, b);
    case ISM_OP_DIV_RC: return iv_div_c(a, in->imm);
    case ISM_OP_DIV_CR: return iv_c_div(in->imm, a);
    case ISM_OP_ABS: return iv_abs(a);
    case ISM_OP_POWI: return iv_powi(a, in->b);
    case ISM_OP_POWC: return iv_powc(a, in->imm);
    case ISM_OP_SQRT: return iv_sqrt(a);
    case ISM_OP_TAN: return iv_tan(a);
    case ISM_OP_EXP: return iv_exp(a);
    case ISM_OP_LOG: return iv_log(a);
    default: return ism_iv_whole();
    }
}

static void run_nearest(const ism_instr *in, double *ol, double *onh, const double *al,
                        const double *anh, const double *bl, const double *bnh, size_t m,
                        rounding mode)
{
    rounding_set(rounding_nearest(mode));
    for (size_t j = 0; j < m; j++) {
        ism_interval r = nearest_op(in, iv(al[j], -anh[j]), iv(bl[j], -bnh[j]));
        ol[j] = sane(r.lo);
        onh[j] = sane(-r.hi);
    }
    rounding_set(rounding_down(mode));
}

/* sin or cos four lanes at a time in round-to-nearest: each lane iv_sin / iv_cos of its box
 * bit for bit (interval_lanes.h's v_sin_at / v_cos_at, the same IEEE operations), its bounds'
 * libm pairs from the workspace's memo (trig_pair.h's ism_trig_pair_libm, as the single-box
 * pass's interval_trig.h takes them), none for a lane that does not resolve (it gets [-1, 1]).
 * The bounds stay within [-1, 1], so sane() would change none. Compiled twice (avx2_clone.h)
 * and never inlined: inlined into chunks it cost tapes without sines 0.08% (Klein bottle at
 * E = 0.0141: chunks_avx2 +0.50M, callgrind). Gyroid ball at E = 1e-3 (callgrind,
 * ism_mesh_surface, one thread): box by box with iv_sin / iv_cos, 712,944 libm calls and
 * 116.6M instructions of 125.7M in ism_eval_interval_batch; with these, 2,200 sincos calls and
 * 34.2M in all. */
ISM_AVX2_TWICE(__attribute__((noinline)) void, run_trig,
               (int op, double *restrict ol, double *restrict onh, const double *restrict al,
                const double *restrict anh, size_t m, rounding mode, ism_trig_cache *trig),
               (op, ol, onh, al, anh, m, mode, trig),
    rounding_set(rounding_nearest(mode));
    for (size_t j = 0; j < m; j += LANES) {
        vi a = {v4_ld(al + j), -v4_ld(anh + j)};
        v4i ok = v_trig_resolves(a);
        double w[2][2][LANES] = {{{0}}}; /* [bound][sin, cos][lane] */
        for (int k = 0; k < LANES; k++)
            if (ok[k]) {
                ism_trig_pair_libm(trig, a.lo[k], &w[0][0][k], &w[0][1][k]);
                ism_trig_pair_libm(trig, a.hi[k], &w[1][0][k], &w[1][1][k]);
            }
        vi r = op == ISM_OP_SIN ? v_sin_at(a, v4_ld(w[0][0]), v4_ld(w[1][0]))
                                : v_cos_at(a, v4_ld(w[0][1]), v4_ld(w[1][1]));
        v4_st(ol + j, v4_pick(ok, r.lo, splat(-1.0)));
        v4_st(onh + j, -v4_pick(ok, r.hi, splat(1.0)));
    }
    rounding_set(rounding_down(mode));)

/* After an operation with an infinite constant (max(a, inf), a + inf): the invariant back. */
static ALWAYS_INLINE void sanitize(double *restrict ol, double *restrict onh, size_t m)
{
    WHOLE_VECTORS(m);
    for (size_t j = 0; j < m; j++) {
        ol[j] = sane(ol[j]);
        onh[j] = sane(onh[j]);
    }
}

/* Every operation's step over the first m lanes (a multiple of LANES) of every register, as
 * a statement in ol, onh (its register's bounds), al, anh, bl, bnh (its operands'; b is a
 * when the operation reads no second register), c (its constant), in, m, mode and trig (the
 * workspace's sine memo): one list, expanded by chunks's labels. */
#define BATCH_OPS(X)                                                                        \
    X(ISM_OP_CONST, for (size_t j = 0; j < m; j++) {                                        \
        ol[j] = sane(c);                                                                    \
        onh[j] = sane(-c);                                                                  \
    })                                                                                      \
    X(ISM_OP_COPY, k_copy(ol, onh, al, anh, c, m))                                          \
    X(ISM_OP_ADD_RR, k_add(ol, onh, al, anh, bl, bnh, m))                                   \
    X(ISM_OP_ADD_RC, k_add_c(ol, onh, al, anh, c, m))                                       \
    X(ISM_OP_SUB_RR, k_sub(ol, onh, al, anh, bl, bnh, m))                                   \
    X(ISM_OP_SUB_CR, k_c_sub(ol, onh, al, anh, c, m))                                       \
    X(ISM_OP_MUL_RR, if (k_mul_finite(ol, onh, al, anh, bl, bnh, m))                        \
                         k_mul(ol, onh, al, anh, bl, bnh, m))                               \
    X(ISM_OP_MUL_RC, if (c > 0.0) k_mul_cpos(ol, onh, al, anh, c, m);                       \
                     else if (c < 0.0) k_mul_cneg(ol, onh, al, anh, c, m);                  \
                     else NEAREST)                                                          \
    X(ISM_OP_DIV_RR, NEAREST)                                                               \
    X(ISM_OP_DIV_RC, NEAREST)                                                               \
    X(ISM_OP_DIV_CR, NEAREST)                                                               \
    X(ISM_OP_MIN_RR, k_min(ol, onh, al, anh, bl, bnh, m))                                   \
    X(ISM_OP_MIN_RC, k_min_c(ol, onh, al, anh, c, m))                                       \
    X(ISM_OP_MAX_RR, k_max(ol, onh, al, anh, bl, bnh, m))                                   \
    X(ISM_OP_MAX_RC, k_max_c(ol, onh, al, anh, c, m))                                       \
    X(ISM_OP_NEG, k_neg(ol, onh, al, anh, c, m))                                            \
    X(ISM_OP_SQUARE, k_square(ol, onh, al, anh, c, m))                                      \
    X(ISM_OP_POWI, NEAREST)                                                                 \
    X(ISM_OP_POWC, NEAREST)                                                                 \
    X(ISM_OP_SQRT, NEAREST)                                                                 \
    X(ISM_OP_SIN, run_trig(ISM_OP_SIN, ol, onh, al, anh, m, mode, trig))                    \
    X(ISM_OP_COS, run_trig(ISM_OP_COS, ol, onh, al, anh, m, mode, trig))                    \
    X(ISM_OP_TAN, NEAREST)                                                                  \
    X(ISM_OP_EXP, NEAREST)                                                                  \
    X(ISM_OP_LOG, NEAREST)                                                                  \
    X(ISM_OP_ABS, NEAREST)
ISM_THREADED_COMPLETE(BATCH_OPS, "BATCH_OPS names every operation (the label table)");

/* Box by box in round-to-nearest (nearest_op; the whole line past the list). */
#define NEAREST run_nearest(in, ol, onh, al, anh, bl, bnh, m, mode)

/* One operation's labelled step: its registers, its code, then, for an operation reading
 * no second register whose constant is not finite, the register invariant back (sanitize).
 * HAS_B is a constant for each listed operation, so the test folds away for the others. */
#define BATCH_STEP_AS(LABEL, HAS_B, E)                                                      \
    LABEL : {                                                                               \
        double *ol = lo + (size_t)in->out * ISM_IV_CHUNK;                                   \
        double *onh = nh + (size_t)in->out * ISM_IV_CHUNK;                                  \
        const double *al = lo + (size_t)in->a * ISM_IV_CHUNK;                               \
        const double *anh = nh + (size_t)in->a * ISM_IV_CHUNK;                              \
        size_t b_ = (size_t)((HAS_B) ? in->b : in->a) * ISM_IV_CHUNK;                       \
        const double *bl = lo + b_, *bnh = nh + b_;                                         \
        const double c = in->imm;                                                           \
        (void)al, (void)anh, (void)bl, (void)bnh, (void)c;                                  \
        E;                                                                                  \
        if (!(HAS_B) && !isfinite(c))                                                       \
            sanitize(ol, onh, m);                                                           \
    }                                                                                       \
    ISM_THREADED_NEXT(next_op, in, end, goto tape_done)
#define BATCH_STEP(OP, E) BATCH_STEP_AS(L_##OP, ism_op_has_reg_b(OP), E)

/* ---- packing ---- */

static ALWAYS_INLINE void pack_box(const double *restrict b, double *restrict lo,
                                   double *restrict nh, size_t j)
{
    double l = b[2 * j], h = b[2 * j + 1];
    lo[j] = l <= h ? sane(l) : -INFINITY;
    nh[j] = l <= h ? sane(-h) : -INFINITY;
}

typedef double vec4 __attribute__((vector_size(4 * sizeof(double))));
typedef long long lvec4 __attribute__((vector_size(4 * sizeof(long long))));

/* Lanes of v above most become most (a macro: a function returning a vector would change
 * the ABI between the AVX2 and baseline paths). */
#define CLAMP4(v, most) ((vec4)(((lvec4)(v) & ((v) < (most))) | ((lvec4)(most) & ~((v) < (most)))))

/* Four boxes' bounds (l0 h0 l1 h1 | l2 h2 l3 h3) split into lows and negated highs. */
static ALWAYS_INLINE void pack_four(const double *b, double *lo, double *nh)
{
    vec4 p, q;
    memcpy(&p, b, sizeof p);
    memcpy(&q, b + 4, sizeof q);
    vec4 l = __builtin_shuffle(p, q, (lvec4){ 0, 2, 4, 6 });
    vec4 h = __builtin_shuffle(p, q, (lvec4){ 1, 3, 5, 7 });
    lvec4 ok = l <= h;
    vec4 whole = { -INFINITY, -INFINITY, -INFINITY, -INFINITY };
    vec4 most = { DBL_MAX, DBL_MAX, DBL_MAX, DBL_MAX }, nh4 = -h;
    l = CLAMP4(l, most); /* the register invariant: below +inf */
    nh4 = CLAMP4(nh4, most);
    vec4 vl = (vec4)(((lvec4)l & ok) | ((lvec4)whole & ~ok));
    vec4 vnh = (vec4)(((lvec4)nh4 & ok) | ((lvec4)whole & ~ok));
    memcpy(lo, &vl, sizeof vl);
    memcpy(nh, &vnh, sizeof vnh);
}

/* Box coordinates into a register: n lanes, then lanes n..m-1 repeat the last box. The
 * boxes are read as a flat array of bounds (lo, hi, lo, hi, ...), four at a time, then
 * the rest. */
static ALWAYS_INLINE void pack(const ism_interval *v, double *restrict lo, double *restrict nh,
                               size_t n, size_t m)
{
    const double *restrict b = &v[0].lo;
    size_t whole = n / LANES * LANES;
    for (size_t j = 0; j < whole; j += LANES)
        pack_four(b + 2 * j, lo + j, nh + j);
    for (size_t j = whole; j < n; j++)
        pack_box(b, lo, nh, j);
    for (size_t j = n; j < m; j++) {
        lo[j] = lo[n - 1];
        nh[j] = nh[n - 1];
    }
}

/* The result register's first n lanes into out, likewise. */
static ALWAYS_INLINE void unpack(const double *restrict lo, const double *restrict nh,
                                 ism_interval *out, size_t n)
{
    double *restrict o = &out[0].lo;
    size_t whole = n / LANES * LANES;
    WHOLE_VECTORS(whole);
    for (size_t j = 0; j < whole; j++) {
        o[2 * j] = lo[j];
        o[2 * j + 1] = -nh[j];
    }
    for (size_t j = whole; j < n; j++) {
        o[2 * j] = lo[j];
        o[2 * j + 1] = -nh[j];
    }
}

/* The boxes n <= ISM_IV_CHUNK into the input registers, m lanes (n rounded up to LANES). */
static ALWAYS_INLINE void chunk_in(double *lo, double *nh, const ism_interval *x,
                                   const ism_interval *y, const ism_interval *z, size_t n,
                                   size_t m)
{
    pack(x, lo + ISM_REG_X * ISM_IV_CHUNK, nh + ISM_REG_X * ISM_IV_CHUNK, n, m);
    pack(y, lo + ISM_REG_Y * ISM_IV_CHUNK, nh + ISM_REG_Y * ISM_IV_CHUNK, n, m);
    pack(z, lo + ISM_REG_Z * ISM_IV_CHUNK, nh + ISM_REG_Z * ISM_IV_CHUNK, n, m);
}

/* Every chunk in round-down mode (the caller's mode restored after), each through the whole
 * tape by direct threading (threaded.h: each step's code ends in its own end test and jump,
 * where a switch in a loop paid a bound test, the switch's table, the loop's test and every
 * step the constant's test); compiled twice (avx2_clone.h's ISM_AVX2_TWICE). */
ISM_AVX2_TWICE(void, chunks,
               (const ism_tape *t, double *lo, double *nh, ism_trig_cache *trig,
                const ism_interval *x, const ism_interval *y, const ism_interval *z,
                ism_interval *out, size_t n),
               (t, lo, nh, trig, x, y, z, out, n),
    ISM_THREADED_TABLE(next_op, BATCH_OPS);
    rounding mode = rounding_get();
    rounding_set(rounding_down(mode));
    for (size_t done = 0; done < n; done += ISM_IV_CHUNK) {
        size_t k = n - done < ISM_IV_CHUNK ? n - done : ISM_IV_CHUNK;
        size_t m = (k + LANES - 1) / LANES * LANES;
        chunk_in(lo, nh, x + done, y + done, z + done, k, m);
        const ism_instr *in = t->code, *const end = t->code + t->len;
        if (in == end)
            goto tape_done;
        goto *next_op[in->op];
        BATCH_OPS(BATCH_STEP)
        BATCH_STEP_AS(L_BAD, ism_op_has_reg_b(in->op), NEAREST)
    tape_done:;
        size_t r = (size_t)t->result * ISM_IV_CHUNK;
        unpack(lo + r, nh + r, out + done, k);
    }
    rounding_set(mode);)

void ism_eval_interval_batch(const ism_tape *t, ism_eval_ws *ws, const ism_interval *x,
                             const ism_interval *y, const ism_interval *z, ism_interval *out,
                             size_t n)
{
    if (!ism_ws_fits(ws, t)) {
        for (size_t i = 0; i < n; i++)
            out[i] = ism_iv_whole();
        return;
    }
    if (n == 0)
        return;
    chunks(t, ws->iv_lo, ws->iv_hi, ws->trig, x, y, z, out, n);
}
