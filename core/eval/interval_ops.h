/* interval_ops.h — interval arithmetic with outward rounding, one inline function per
 * operation, each returning an interval that encloses the exact range of the operation
 * over its argument intervals (and so also the double-precision value computed for any
 * point inside them).
 *
 * Outward rounding: every computed bound is pushed outward by at least one ulp with
 * `(x - 2^-1074) - |x|*2^-52`, which is always <= the next double below x, without a branch,
 * a rounding-mode switch or a call (see down1/up1). Results of libm functions (not
 * correctly rounded) are pushed by four ulps. A NaN bound (inf - inf, 0 * inf) never
 * escapes: ism_iv_sane turns it into the matching infinity.
 *
 * The common operations are written without branches (selects only). The batched interval
 * evaluator rounds by the rounding mode instead and uses these for its box-by-box operations
 * (libm functions, division, powers, abs) only.
 *
 * Needs FP contraction off (-ffp-contract=off; gcc's -std=c11 implies it, clang's default
 * is on): a contracted (x + c) + |x|*r is one fma, still outward but not the bits of the
 * SSE2 forms here or of interval_lanes.h's vdown1 / vup1, which the "same bits" claims and
 * the mesh_identity sets rely on (revJ 3: -mavx2 -mfma, clang, 2.2M of 20M cases differ). */
#ifndef ISM_INTERVAL_OPS_H
#define ISM_INTERVAL_OPS_H

#include <math.h>
#include <stddef.h>
#if defined(__SSE2__)
#include <emmintrin.h>
#endif
#include "core/eval/eval.h"
#include "core/expr/scalar_ops.h"

/* (x - 2^-1074) is x itself for a normal x and exact below; subtracting |x| * 2^-52 (at
 * least one ulp of x) then lands at or below the next double under x. The two halves are
 * independent, which keeps the latency of the single-box evaluator's chain short. */
#define ISM_ROUND1_ABS 0x1p-1074 /* the least subnormal: a step below x even near 0 */
#define ISM_ROUND1_REL 0x1p-52   /* at least one ulp of x, relative to |x| */
static inline double down1(double x) { return (x - ISM_ROUND1_ABS) - fabs(x) * ISM_ROUND1_REL; }
static inline double up1(double x) { return (x + ISM_ROUND1_ABS) + fabs(x) * ISM_ROUND1_REL; }
/* four ulps for libm's results: four times each of the steps above */
#define ISM_ROUND4_ABS 0x1p-1072
#define ISM_ROUND4_REL 0x1p-50
static inline double down4(double x) { return (x - ISM_ROUND4_ABS) - fabs(x) * ISM_ROUND4_REL; }
static inline double up4(double x) { return (x + ISM_ROUND4_ABS) + fabs(x) * ISM_ROUND4_REL; }

static inline ism_interval iv(double lo, double hi)
{
    ism_interval r = { lo, hi };
    return r;
}

static inline ism_interval ism_iv_whole(void) { return iv(-INFINITY, INFINITY); }

static inline double nan_to(double v, double instead) { return v == v ? v : instead; }

#if defined(__SSE2__)
/* An interval as one SSE2 vector [lo, hi] and back. */
static inline __m128d iv_vec(ism_interval a) { return _mm_set_pd(a.hi, a.lo); }

/* iv_of_vec stores the vector's 16 bytes over the whole struct, lo then hi. */
_Static_assert(sizeof(ism_interval) == 2 * sizeof(double) &&
                   offsetof(ism_interval, hi) == sizeof(double),
               "ism_interval is [lo, hi] with no padding");

static inline ism_interval iv_of_vec(__m128d v)
{
    ism_interval r;
    _mm_storeu_pd((double *)(void *)&r, v); /* the object r, not past r.lo */
    return r;
}

/* [down1(lo), up1(hi)] in one vector pass: the same IEEE operations lane by lane (x - c is
 * x + (-c), and |x| * (-r) is -(|x| * r) exactly in round-to-nearest), so the same bits for
 * every non-NaN result; a NaN stays a NaN (its sign may differ: the compiler may swap the
 * add's operands, and which NaN wins follows the order), and ism_iv_sane discards it. */
static inline __m128d round1_out(__m128d v)
{
    const __m128d step = _mm_set_pd(ISM_ROUND1_ABS, -ISM_ROUND1_ABS);
    const __m128d rel = _mm_set_pd(ISM_ROUND1_REL, -ISM_ROUND1_REL);
    __m128d mag = _mm_andnot_pd(_mm_set1_pd(-0.0), v);
    return _mm_add_pd(_mm_add_pd(v, step), _mm_mul_pd(mag, rel));
}
#endif

/* Replaces NaN bounds by the infinity on their side (every operation keeps lo <= hi
 * otherwise). With SSE2 one unordered compare of both bounds and one branch, rarely taken,
 * where the two nan_to tests cost ~9 instructions on each step of the interval pass (~20% of
 * a pass on Barth's tape); the same bits either way. */
static inline ism_interval ism_iv_sane(ism_interval r)
{
#if defined(__SSE2__)
    __m128d v = iv_vec(r);
    if (__builtin_expect(_mm_movemask_pd(_mm_cmpunord_pd(v, v)) == 0, 1))
        return r;
#endif
    return iv(nan_to(r.lo, -INFINITY), nan_to(r.hi, INFINITY));
}

static inline ism_interval iv_add(ism_interval a, ism_interval b)
{
#if defined(__SSE2__)
    return iv_of_vec(round1_out(_mm_add_pd(iv_vec(a), iv_vec(b))));
#else
    return iv(down1(a.lo + b.lo), up1(a.hi + b.hi));
#endif
}

static inline ism_interval iv_add_c(ism_interval a, double c)
{
#if defined(__SSE2__)
    return iv_of_vec(round1_out(_mm_add_pd(iv_vec(a), _mm_set1_pd(c))));
#else
    return iv(down1(a.lo + c), up1(a.hi + c));
#endif
}

/* [a.lo - b.hi, a.hi - b.lo]: b's bounds swapped into the lanes. */
static inline ism_interval iv_sub(ism_interval a, ism_interval b)
{
#if defined(__SSE2__)
    return iv_of_vec(round1_out(_mm_sub_pd(iv_vec(a), _mm_set_pd(b.lo, b.hi))));
#else
    return iv(down1(a.lo - b.hi), up1(a.hi - b.lo));
#endif
}

static inline ism_interval iv_c_sub(double c, ism_interval a)
{
#if defined(__SSE2__)
    return iv_of_vec(round1_out(_mm_sub_pd(_mm_set1_pd(c), _mm_set_pd(a.lo, a.hi))));
#else
    return iv(down1(c - a.hi), up1(c - a.lo));
#endif
}

static inline ism_interval iv_neg(ism_interval a)
{
    return iv(-a.hi, -a.lo);
}

/* A product bound: 0 * inf (the only NaN a product of non-NaN bounds can give) counts as
 * 0, the bound of a product of reals. */
static inline double mul0(double x, double y)
{
    return nan_to(x * y, 0.0);
}

static inline double min4(double a, double b, double c, double d)
{
    return ism_min(ism_min(a, b), ism_min(c, d));
}

static inline double max4(double a, double b, double c, double d)
{
    return ism_max(ism_max(a, b), ism_max(c, d));
}

/* The product's bounds from its four corner products, each NaN (0 * inf) counted as 0. */
static inline ism_interval iv_mul_scalar(ism_interval a, ism_interval b)
{
    double p1 = mul0(a.lo, b.lo), p2 = mul0(a.lo, b.hi), p3 = mul0(a.hi, b.lo),
           p4 = mul0(a.hi, b.hi);
    return iv(down1(min4(p1, p2, p3, p4)), up1(max4(p1, p2, p3, p4)));
}

/* iv_mul_scalar bit for bit, with the four products two by two in SSE2 lanes: [p1, p3] and
 * [p2, p4]; minpd / maxpd take the first operand exactly where ism_min / ism_max do (a < b,
 * a > b; else the second, signed zeros included), so the lanes' min(p1, p2), min(p3, p4)
 * and then the min of the two are min4's, in min4's order. A NaN product (0 * inf, rare)
 * takes the scalar path. The interval jets spent ~40 instructions per product, a third of
 * them the four NaN tests (callgrind, torus at 1e-2). */
static inline __attribute__((always_inline)) ism_interval iv_mul(ism_interval a, ism_interval b)
{
#if defined(__SSE2__)
    __m128d va = _mm_set_pd(a.hi, a.lo);
    __m128d q = _mm_mul_pd(va, _mm_set1_pd(b.lo)); /* [p1, p3] */
    __m128d r = _mm_mul_pd(va, _mm_set1_pd(b.hi)); /* [p2, p4] */
    if (__builtin_expect(_mm_movemask_pd(_mm_or_pd(_mm_cmpunord_pd(q, q),
                                                   _mm_cmpunord_pd(r, r))) != 0, 0))
        return iv_mul_scalar(a, b);
    __m128d mn = _mm_min_pd(q, r), mx = _mm_max_pd(q, r);
    __m128d lo = _mm_min_sd(mn, _mm_unpackhi_pd(mn, mn));
    __m128d hi = _mm_max_sd(mx, _mm_unpackhi_pd(mx, mx));
    return iv_of_vec(round1_out(_mm_unpacklo_pd(lo, hi)));
#else
    return iv_mul_scalar(a, b);
#endif
}

/* a * c for a constant c of known sign, the choice taken once by the caller: iv_mul_c, the
 * batched evaluator (its MUL_RC, one per instruction) and eval_interval_jet.c's mul_rc (once
 * for a jet's value and partials; cneg also for a NaN c). A finite c != 0 gives no NaN bound;
 * a NaN or infinite c (a tape's immediate may be either) can, and the caller cleans it. */
static inline ism_interval iv_mul_cpos(ism_interval a, double c)
{
#if defined(__SSE2__)
    return iv_of_vec(round1_out(_mm_mul_pd(iv_vec(a), _mm_set1_pd(c))));
#else
    return iv(down1(a.lo * c), up1(a.hi * c));
#endif
}

static inline ism_interval iv_mul_cneg(ism_interval a, double c)
{
#if defined(__SSE2__)
    return iv_of_vec(round1_out(_mm_mul_pd(_mm_set_pd(a.lo, a.hi), _mm_set1_pd(c))));
#else
    return iv(down1(a.hi * c), up1(a.lo * c));
#endif
}

static inline ism_interval iv_mul_c(ism_interval a, double c)
{
    if (c == 0.0)
        return iv(0.0, 0.0);
    return c > 0.0 ? iv_mul_cpos(a, c) : iv_mul_cneg(a, c);
}

/* a / b: the whole line when b holds 0, or when inf / inf leaves a bound undefined. */
static inline ism_interval iv_div(ism_interval a, ism_interval b)
{
    double q1 = a.lo / b.lo, q2 = a.lo / b.hi, q3 = a.hi / b.lo, q4 = a.hi / b.hi;
    double s = q1 + q2 + q3 + q4;
    double side = b.lo > 0.0 ? 1.0 : b.hi < 0.0 ? 1.0 : 0.0; /* b excludes 0 */
    double lo = down1(min4(q1, q2, q3, q4)), hi = up1(max4(q1, q2, q3, q4));
    lo = side == 1.0 ? lo : -INFINITY;
    hi = side == 1.0 ? hi : INFINITY;
    return iv(nan_to(s, -INFINITY) == s ? lo : -INFINITY, s == s ? hi : INFINITY);
}

static inline ism_interval iv_div_c(ism_interval a, double c)
{
    double p = a.lo / c, q = a.hi / c;
    int pos = c > 0.0;
    double lo = pos ? p : q, hi = pos ? q : p;
    return iv(down1(lo), up1(hi));
}

/* c / a: monotone on each side of 0. */
static inline ism_interval iv_c_div(double c, ism_interval a)
{
    double p = c / a.hi, q = c / a.lo;
    double lo = down1(c >= 0.0 ? p : q), hi = up1(c >= 0.0 ? q : p);
    int excludes0 = a.lo > 0.0 || a.hi < 0.0;
    return excludes0 ? iv(lo, hi) : ism_iv_whole();
}

static inline ism_interval iv_min(ism_interval a, ism_interval b)
{
    return iv(ism_min(a.lo, b.lo), ism_min(a.hi, b.hi));
}

static inline ism_interval iv_max(ism_interval a, ism_interval b)
{
    return iv(ism_max(a.lo, b.lo), ism_max(a.hi, b.hi));
}

static inline ism_interval iv_abs(ism_interval a)
{
    int nonneg = a.lo >= 0.0, nonpos = a.hi <= 0.0;
    double inner = nonpos ? -a.hi : 0.0;
    double lo = nonneg ? a.lo : inner;
    return iv(lo, ism_max(fabs(a.lo), fabs(a.hi)));
}

/* Bounds of m^n for m >= 0 with the products of ism_powi, each rounded outward. */
static inline double powi_down(double m, unsigned n)
{
    double r = 1.0, p = m;
    while (n) {
        if (n & 1u)
            r = ism_max(down1(r * p), 0.0);
        n >>= 1;
        if (n)
            p = ism_max(down1(p * p), 0.0);
    }
    return r;
}

static inline double powi_up(double m, unsigned n)
{
    double r = 1.0, p = m;
    while (n) {
        if (n & 1u)
            r = up1(r * p);
        n >>= 1;
        if (n)
            p = up1(p * p);
    }
    return r;
}

/* a^n, n >= 2: even powers are >= 0 and exact at 0 when a holds 0. */
static inline ism_interval iv_powi(ism_interval a, unsigned n)
{
    if (a.lo >= 0.0)
        return iv(powi_down(a.lo, n), powi_up(a.hi, n));
    if (n % 2u == 0) {
        if (a.hi <= 0.0)
            return iv(powi_down(-a.hi, n), powi_up(-a.lo, n));
        return iv(0.0, powi_up(ism_max(-a.lo, a.hi), n));
    }
    double lo = -powi_up(-a.lo, n);
    double hi = a.hi >= 0.0 ? powi_up(a.hi, n) : -powi_down(-a.hi, n);
    return iv(lo, hi);
}

static inline ism_interval iv_square(ism_interval a)
{
    double l2 = a.lo * a.lo, h2 = a.hi * a.hi;
    int nonneg = a.lo >= 0.0, nonpos = a.hi <= 0.0; /* both tested: no branch */
    double inner = nonpos ? h2 : 0.0;
    double lo = nonneg ? l2 : inner;
#if defined(__SSE2__)
    /* maxsd takes its first operand where ism_max does (a > b), the high lane as it is */
    __m128d r = round1_out(_mm_set_pd(ism_max(l2, h2), lo));
    return iv_of_vec(_mm_max_sd(r, _mm_setzero_pd()));
#else
    return iv(ism_max(down1(lo), 0.0), up1(ism_max(l2, h2)));
#endif
}

static inline ism_interval iv_sqrt(ism_interval a)
{
    return iv(ism_max(down1(ism_sqrt_clip(a.lo)), 0.0), up1(ism_sqrt_clip(a.hi)));
}

static inline ism_interval iv_exp(ism_interval a)
{
    return iv(ism_max(down4(exp(a.lo)), 0.0), up4(exp(a.hi)));
}

static inline ism_interval iv_log(ism_interval a)
{
    double hi = ism_log_clip(a.hi);
    return iv(down4(ism_log_clip(a.lo)), hi == -INFINITY ? hi : up4(hi));
}

/* max(a, 0)^c for a non-integer constant c: monotone on [0, inf). */
static inline ism_interval iv_powc(ism_interval a, double c)
{
    double lo = ism_powc(a.lo, c), hi = ism_powc(a.hi, c);
    if (c < 0.0) {
        double t = lo;
        lo = hi;
        hi = t;
    }
    return iv(ism_max(down4(lo), 0.0), up4(hi));
}

/* True when some integer k may satisfy u <= k <= v (u, v carry a rounding margin). */
static inline int holds_integer(double u, double v)
{
    return ceil(u) <= v;
}

/* Arguments beyond this make sin/cos/tan give their whole range: the periods no longer
 * resolve. */
#define ISM_TRIG_LIMIT 1e9

/* Whether [lo, hi] may contain phase + k*period for an integer k, with a margin for the
 * rounding of the division (answering yes too often only loosens, never breaks, a bound):
 * ISM_TRIG_TOL_ABS + ISM_TRIG_TOL_REL max(|lo|, |hi|), named for interval_lanes.h's lane form,
 * which must take the same. */
#define ISM_TRIG_TOL_ABS 1e-12
#define ISM_TRIG_TOL_REL 4e-16
static inline int may_contain(double lo, double hi, double phase, double period)
{
    double tol = ISM_TRIG_TOL_ABS + ISM_TRIG_TOL_REL * ism_max(fabs(lo), fabs(hi));
    return holds_integer((lo - phase) / period - tol, (hi - phase) / period + tol);
}

/* Whether sin and cos over a resolve to less than their whole range: a narrower than a
 * period and its bounds within ISM_TRIG_LIMIT. */
static inline int iv_trig_resolves(ism_interval a)
{
    return a.hi - a.lo < 2.0 * M_PI && fabs(a.lo) < ISM_TRIG_LIMIT && fabs(a.hi) < ISM_TRIG_LIMIT;
}

/* sin over a (iv_trig_resolves(a)) given s1 = sin(a.lo), s2 = sin(a.hi). */
static inline ism_interval iv_sin_at(ism_interval a, double s1, double s2)
{
    double lo = ism_max(down4(ism_min(s1, s2)), -1.0), hi = ism_min(up4(ism_max(s1, s2)), 1.0);
    if (may_contain(a.lo, a.hi, M_PI / 2, 2.0 * M_PI))
        hi = 1.0;
    if (may_contain(a.lo, a.hi, -M_PI / 2, 2.0 * M_PI))
        lo = -1.0;
    return iv(lo, hi);
}

/* cos over a (iv_trig_resolves(a)) given c1 = cos(a.lo), c2 = cos(a.hi). */
static inline ism_interval iv_cos_at(ism_interval a, double c1, double c2)
{
    double lo = ism_max(down4(ism_min(c1, c2)), -1.0), hi = ism_min(up4(ism_max(c1, c2)), 1.0);
    if (may_contain(a.lo, a.hi, 0.0, 2.0 * M_PI))
        hi = 1.0;
    if (may_contain(a.lo, a.hi, M_PI, 2.0 * M_PI))
        lo = -1.0;
    return iv(lo, hi);
}

static inline ism_interval iv_sin(ism_interval a)
{
    if (!iv_trig_resolves(a))
        return iv(-1.0, 1.0);
    return iv_sin_at(a, sin(a.lo), sin(a.hi));
}

static inline ism_interval iv_cos(ism_interval a)
{
    if (!iv_trig_resolves(a))
        return iv(-1.0, 1.0);
    return iv_cos_at(a, cos(a.lo), cos(a.hi));
}

static inline ism_interval iv_tan(ism_interval a)
{
    if (!(a.hi - a.lo < M_PI) || !(fabs(a.lo) < ISM_TRIG_LIMIT)
        || !(fabs(a.hi) < ISM_TRIG_LIMIT) || may_contain(a.lo, a.hi, M_PI / 2, M_PI))
        return ism_iv_whole();
    return iv(down4(tan(a.lo)), up4(tan(a.hi)));
}

#endif
