/* sincos.h — the evaluators' own sine and cosine of one argument, as a pair, one argument at a
 * time (ism_sincos) or four (ism_sincos4: each lane the same IEEE operations, so a lane's bits
 * are ism_sincos's). Every evaluator of f at points takes its sines and cosines from here
 * (through trig_pair.h's memo or directly), so the scalar and batched evaluators agree bit
 * for bit; for |x| > ISM_SINCOS_LIMIT and non-finite x both take libm's sincos instead.
 *
 * Method: a table of a whole turn in 256 steps and a short polynomial between.
 *  - j = x 128/pi rounded to an integer (the 1.5 2^52 trick: j's low bits are the sum's), and
 *    r = x - j pi/128 by a four-part split of pi/128 (Cody & Waite): Q1, Q2 and Q3 of 30
 *    significant bits, so j Q1, j Q2 and j Q3 are exact for |j| < 2^23, x - j Q1 is exact
 *    (Sterbenz), the next two subtractions keep their roundings (TwoSum) in a tail lo, and
 *    j Q4 (at most 2^-74) goes into lo: r + lo is x - j pi/128 within 2^-120 + 2^-104 |r|, so
 *    nothing is lost next to a multiple of pi (no double below 2^17 lies within 2^-70 of one).
 *  - |r| <= pi/256: sin r = r + r^3 (S1 + z S2 + z^2 S3), cos r - 1 = -z/2 + z^2 (C1 + z C2),
 *    z = r^2 (Taylor; the next terms weigh 1.4e-21 and 1.3e-20 relative), with lo's first-order
 *    terms.
 *  - i = j mod 256, a = i pi/128: sin x = sin a + (sin a (cos r - 1) + cos a sin r), cos x
 *    likewise, with sin a and cos a from sincos_table.h as hi + lo (exact 0 where they vanish),
 *    and cos a sin r summed as g r + (d r + cos a (sin r - r)) (cos a = g + d, g = -1, 0 or
 *    1): g r is exact, so next to a zero of sin x (where sin x, sin a and r are alike) one
 *    rounding of r's size stays, not three.
 * Coefficients, split and table: tests/unit/core/sincos_coeffs.py (mpmath; nothing copied).
 *
 * Accuracy (test_sincos.c, 10^7 arguments over the range, against long double sinl / cosl):
 * at most 0.750 ulp for sine and cosine (glibc's 0.515 measured the same way); 0.4% of
 * arguments differ from glibc's bits, by one ulp. So meshes of trig surfaces may differ from
 * libm's where f's last bit decides (a root's last step, a tie of max()'s two branches).
 *
 * Cost: one argument ~90 instructions of SSE2 code (glibc's sincos ~60 a call, gyroid ball
 * under callgrind), four in one AVX2 call ~150: the batched evaluators gain (four lanes at
 * once; the batched gradient also keeps a register's pairs, trig_pair.h's group pairs), the
 * scalar ones' memo misses cost a little more. Gyroid ball at E = 1e-3, one thread,
 * ism_mesh_surface: 2,858.7M instructions with glibc's, 2,741.8M with these (667359f),
 * 2,703.6M with the group pairs (f96a89c).
 *
 * Preconditions: the rounding trick (SC_ROUND), the TwoSum tails and "a lane's bits are
 * ism_sincos's" all need round-to-nearest and no contraction of a * b + c into an FMA. Both
 * hold by construction today: the Makefile builds with -ffp-contract=off (also ISO C's
 * default under GCC) and the AVX2 clones target avx2 without fma; nothing here may be called
 * inside eval_interval_batch.c's directed-rounding region (fesetround there).
 *
 * The interval evaluators do not use this: their bounds stay on libm's sin and cos
 * (interval_ops.h), whose error bound glibc documents (1 ulp), widened by 4 ulp; the measured
 * bound above is not a proof. */
#ifndef ISM_SINCOS_H
#define ISM_SINCOS_H

#include "core/eval/lanes4.h"
#include "core/eval/sincos_table.h"
#include <math.h>
#include <stdint.h>

/* |x| up to which the reduction above is exact: |j| <= 2^17 128/pi < 2^(17 + SC_128_PI_BITS)
 * (128/pi < 2^6: the generated SC_128_PI_BITS, log2 of SC_128_PI rounded up) keeps j Q1, j Q2
 * and j Q3 exact doubles (j's bits + Q's SC_SPLIT_BITS <= 53, asserted). Beyond (or NaN,
 * ±inf): libm. Tapes see far smaller arguments (a box of a few units times a period's
 * scale). SC_Q1 .. SC_Q4 (pi/128 = Q1 + Q2 + Q3 + Q4 - 2.7e-46), SC_128_PI and the
 * polynomials' SC_S1 .. SC_S3, SC_C1, SC_C2: sincos_table.h (generated). */
#define ISM_SINCOS_LIMIT_BITS 17
#define ISM_SINCOS_LIMIT ((double)(1ull << ISM_SINCOS_LIMIT_BITS))
_Static_assert(ISM_SINCOS_LIMIT_BITS + SC_128_PI_BITS + SC_SPLIT_BITS <= 53,
               "j = x 128/pi times a Q is exact up to ISM_SINCOS_LIMIT");
/* 1.5 2^52: v + it, for |v| < 2^51, rounds v to an integer held in the sum's low bits */
#define SC_ROUND 0x1.8p52

typedef unsigned long long sc_v4u __attribute__((vector_size(4 * sizeof(double))));

/* The arithmetic both forms share, for T = double or v4d (GCC's vector extension widens a
 * double constant to every lane), written once so that a lane of ism_sincos4 and ism_sincos
 * do the very same IEEE operations: kr = x 128/pi + SC_ROUND holds j in its low bits; r is the
 * reduced argument, pt sin(r + lo) - r and cm cos(r + lo) - 1. TwoSum (Knuth) keeps the
 * roundings of the reduction's middle subtractions: t - j Q2 = y + e1, y - j Q3 = r + e2. */
#define SC_CORE(T, x, kr, r, pt, cm)                                                        \
    do {                                                                                    \
        T j_ = (kr = (x) * SC_128_PI + SC_ROUND) - SC_ROUND;                                \
        T t_ = (x) - j_ * SC_Q1, w1_ = j_ * SC_Q2, w2_ = j_ * SC_Q3;                        \
        T y_ = t_ - w1_, b1_ = y_ - t_;                                                     \
        T e1_ = (t_ - (y_ - b1_)) - (w1_ + b1_);                                            \
        r = y_ - w2_;                                                                       \
        T b2_ = r - y_;                                                                     \
        T e2_ = (y_ - (r - b2_)) - (w2_ + b2_);                                             \
        T lo_ = (e1_ + e2_) - j_ * SC_Q4, z_ = r * r;                                       \
        pt = (r * z_) * (SC_S1 + z_ * (SC_S2 + z_ * SC_S3)) + lo_;                          \
        cm = ((z_ * z_) * (SC_C1 + z_ * SC_C2) - r * lo_) - 0.5 * z_;                       \
    } while (0)

/* sin x and cos x from the table's entry e = {sin a hi, lo, cos a hi, lo, sin a g, d, cos a
 * g, d} and r, pt, cm: sin a + (sin a cm + cos a (r + pt)), the products of r by g exact */
#define SC_SIN(e0, e1, e2, e6, e7, r, pt, cm)                                               \
    ((e0) + ((e6) * (r) + ((e1) + ((e0) * (cm) + ((e7) * (r) + (e2) * (pt))))))
#define SC_COS(e0, e2, e3, e4, e5, r, pt, cm)                                               \
    ((e2) + (((e3) + ((e2) * (cm) - ((e5) * (r) + (e0) * (pt)))) - (e4) * (r)))

/* |x| within ISM_SINCOS_LIMIT (false for NaN) */
#define SC_NEAR(ax) ((ax) <= ISM_SINCOS_LIMIT)

/* One argument. */
static inline void ism_sincos(double x, double *s, double *c)
{
    if (__builtin_expect(!SC_NEAR(fabs(x)), 0)) {
        sincos(x, s, c);
        return;
    }
    double kr, r, pt, cm;
    SC_CORE(double, x, kr, r, pt, cm);
    uint64_t q;
    __builtin_memcpy(&q, &kr, sizeof q);
    const double *e = ism_sincos_table[q & 255]; /* j mod 256 */
    *s = x == 0 ? x : SC_SIN(e[0], e[1], e[2], e[6], e[7], r, pt, cm); /* sin(-0) = -0 */
    *c = SC_COS(e[0], e[2], e[3], e[4], e[5], r, pt, cm);
}

/* Columns k .. k + 3 of four table rows as four vectors: out[m] = {a[k + m], b[k + m],
 * c[k + m], d[k + m]} (one load per row, eight shuffles). */
INLINE void sc_transpose(const double *a, const double *b, const double *c, const double *d,
                         int k, v4d out[4])
{
    const v4i even = {0, 4, 2, 6}, odd = {1, 5, 3, 7}, low = {0, 1, 4, 5}, high = {2, 3, 6, 7};
    v4d ra = v4_ld(a + k), rb = v4_ld(b + k), rc = v4_ld(c + k), rd = v4_ld(d + k);
    v4d ev_ab = __builtin_shuffle(ra, rb, even), ev_cd = __builtin_shuffle(rc, rd, even);
    v4d od_ab = __builtin_shuffle(ra, rb, odd), od_cd = __builtin_shuffle(rc, rd, odd);
    out[0] = __builtin_shuffle(ev_ab, ev_cd, low);
    out[1] = __builtin_shuffle(od_ab, od_cd, low);
    out[2] = __builtin_shuffle(ev_ab, ev_cd, high);
    out[3] = __builtin_shuffle(od_ab, od_cd, high);
}

/* Four arguments, each lane ism_sincos's. */
INLINE void ism_sincos4(v4d x, v4d *s, v4d *c)
{
    const sc_v4u sign = {1ull << 63, 1ull << 63, 1ull << 63, 1ull << 63};
    v4d kr, r, pt, cm;
    SC_CORE(v4d, x, kr, r, pt, cm);
    sc_v4u i = (sc_v4u)kr & 255; /* j mod 256 */
    v4d e[8];
    sc_transpose(ism_sincos_table[i[0]], ism_sincos_table[i[1]], ism_sincos_table[i[2]],
                 ism_sincos_table[i[3]], 0, e);
    sc_transpose(ism_sincos_table[i[0]], ism_sincos_table[i[1]], ism_sincos_table[i[2]],
                 ism_sincos_table[i[3]], 4, e + 4);
    *s = v4_pick(x == 0.0, x, SC_SIN(e[0], e[1], e[2], e[6], e[7], r, pt, cm)); /* sin(-0) */
    *c = SC_COS(e[0], e[2], e[3], e[4], e[5], r, pt, cm);
    v4i far = ~SC_NEAR((v4d)((sc_v4u)x & ~sign));
    if (__builtin_expect((far[0] | far[1] | far[2] | far[3]) != 0, 0))
        for (int l = 0; l < 4; l++)
            if (far[l]) /* libm's pair, as ism_sincos takes */
                ism_sincos(x[l], &(*s)[l], &(*c)[l]);
}

#endif
