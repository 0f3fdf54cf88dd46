/* test_interval_lanes.c — interval_lanes.h's four-lane operations against interval_ops.h's
 * one-interval ones, lane by lane to the bit (a NaN as a NaN), compiled for the x86-64
 * baseline and, where the CPU has it, as an AVX2 clone (avx2_clone.h): the batched interval
 * gradient pass and the dual mesher's proofs rely on it ("the same bits" in
 * eval_interval_grad_batch.c and dual_cert.c). Special values (signed zeros, infinities,
 * NaN, subnormals, DBL_MAX) in every combination of the operands' bounds and the constant,
 * then random bit patterns. vmin / vmax are written element by element (a < b ? a : b,
 * which compiles to minpd / vminpd), so this also checks that the comparison's order and
 * its NaN and signed-zero cases are ism_min's. */
#include <criterion/criterion.h>
#include <float.h>
#include <math.h>
#include <stdint.h>
#include <string.h>

#include "core/eval/avx2_clone.h"
#include "core/eval/interval_lanes.h"
#include "test_bits.h"
#include "test_eval_surfaces.h"

/* The operations' results per lane: add, sub, neg, mul_c, mul, square, as intervals, then
 * min, max, nan_to (as numbers). */
enum { R_ADD, R_SUB, R_NEG, R_MULC, R_MUL, R_SQUARE, R_IV };
typedef struct lane_out {
    double lo[R_IV][4], hi[R_IV][4];
    double mn[4], mx[4], nz[4];
} lane_out;

INLINE void store_vi(lane_out *o, int k, vi v)
{
    v4_st(o->lo[k], v.lo);
    v4_st(o->hi[k], v.hi);
}

/* Compiled twice (avx2_clone.h): lane_ops runs the copy the CPU takes; where the AVX2 clone
 * is built the test also calls lane_ops_base. */
ISM_AVX2_TWICE(void, lane_ops,
               (const double *alo, const double *ahi, const double *blo, const double *bhi,
                double c, lane_out *o),
               (alo, ahi, blo, bhi, c, o),
    vi a = {v4_ld(alo), v4_ld(ahi)}, b = {v4_ld(blo), v4_ld(bhi)};
    store_vi(o, R_ADD, v_add(a, b));
    store_vi(o, R_SUB, v_sub(a, b));
    store_vi(o, R_NEG, v_neg(a));
    store_vi(o, R_MULC, v_mul_c(a, c));
    store_vi(o, R_MUL, v_mul(a, b));
    store_vi(o, R_SQUARE, v_square(a));
    v4_st(o->mn, vmin(a.lo, b.lo));
    v4_st(o->mx, vmax(a.hi, b.hi));
    v4_st(o->nz, vnan_to(a.lo * b.hi, 0.0));)

#define SAME(what, got, want)                                                               \
    cr_assert(test_same_bits((got), (want)),                                                     \
              "%s lane %d (a=[%a, %a], b=[%a, %a], c=%a): %a, scalar %a", what, j, a.lo,    \
              a.hi, b.lo, b.hi, c, (got), (want))
#define SAME_IV(what, k, want)                                                              \
    do {                                                                                    \
        ism_interval w_ = (want);                                                           \
        SAME(what, o->lo[k][j], w_.lo);                                                     \
        SAME(what, o->hi[k][j], w_.hi);                                                     \
    } while (0)

/* Each lane of o against the scalar operations on lane j's operands. */
static void check_lanes(const double *alo, const double *ahi, const double *blo,
                        const double *bhi, double c, const lane_out *o)
{
    for (int j = 0; j < 4; j++) {
        ism_interval a = iv(alo[j], ahi[j]), b = iv(blo[j], bhi[j]);
        SAME_IV("v_add", R_ADD, iv_add(a, b));
        SAME_IV("v_sub", R_SUB, iv_sub(a, b));
        SAME_IV("v_neg", R_NEG, iv_neg(a));
        SAME_IV("v_mul_c", R_MULC, iv_mul_c(a, c));
        SAME_IV("v_mul", R_MUL, iv_mul_scalar(a, b));
        SAME_IV("v_square", R_SQUARE, iv_square(a));
        SAME("vmin", o->mn[j], ism_min(a.lo, b.lo));
        SAME("vmax", o->mx[j], ism_max(a.hi, b.hi));
        SAME("vnan_to", o->nz[j], nan_to(a.lo * b.hi, 0.0));
    }
}

Test(interval_lanes, every_lane_is_the_scalar_operation)
{
    const double sp[] = { 0.0, -0.0, INFINITY, -INFINITY, NAN, -NAN, 0x1p-1074, -0x1p-1074,
                          0x1p-1022, -0x1.ffffffffffffep-1023, DBL_MAX, -DBL_MAX, 1.0, -1.0,
                          3.0, -0.5 };
    enum { NSP = sizeof sp / sizeof sp[0], NSP4 = NSP * NSP * NSP * NSP, NSP5 = NSP4 * NSP };
    test_rng rng = { 28 };
    /* every 5-tuple of special values, each operand bound its own digit of the lane index
     * q = 4 (i / NSP) + j and c the last, i % NSP; then random bits */
    size_t n = NSP5 / 4 + test_scaled(100000);
    for (size_t i = 0; i < n; i++) {
        double alo[4], ahi[4], blo[4], bhi[4], c;
        for (int j = 0; j < 4; j++) {
            size_t q = 4 * (i / NSP) + (size_t)j;
            if (i < NSP5 / 4) {
                alo[j] = sp[q % NSP];
                ahi[j] = sp[q / NSP % NSP];
                blo[j] = sp[q / NSP / NSP % NSP];
                bhi[j] = sp[q / NSP / NSP / NSP % NSP];
            } else {
                alo[j] = test_any_bits(&rng);
                ahi[j] = test_any_bits(&rng);
                blo[j] = test_any_bits(&rng);
                bhi[j] = test_any_bits(&rng);
            }
        }
        c = i < NSP5 / 4 ? sp[i % NSP] : test_any_bits(&rng);
        if (!(fabs(c) <= DBL_MAX))
            c = -2.5; /* v_mul_c's constant is finite (a tape's immediate) */
        lane_out o;
        lane_ops(alo, ahi, blo, bhi, c, &o); /* the copy this CPU runs */
        check_lanes(alo, ahi, blo, bhi, c, &o);
#if ISM_HAVE_AVX2_CLONE
        lane_ops_base(alo, ahi, blo, bhi, c, &o); /* and the baseline */
        check_lanes(alo, ahi, blo, bhi, c, &o);
#endif
    }
}
