/* test_ival_batch.c — the batched interval evaluator (ism_eval_interval_batch, which runs in
 * round-down mode) on every preset: over random boxes of a fixed seed — ordinary, tiny (2^-30
 * of the preset's box), huge (2^10 times it), straddling a coordinate plane and straddling
 * the surface f = 0 — each result interval holds f's exact range as sampled densely (a 5^3
 * grid and random points, in double through ism_eval_batch and in long double through an
 * interpreter of the tape written here), is never wider than the single-box evaluator's by
 * more than BATCH_WIDTH_FACTOR, and the caller's rounding mode is left as it was. */
#include <criterion/criterion.h>
#include <fenv.h>
#include <math.h>
#include <stdint.h>
#include <stdlib.h>

#include "core/eval/eval.h"
#include "core/expr/tape.h"
#include "proto/presets.h"
#include "tests/unit/proto/preset_tape.h"

enum { BOXES = 48, GRID = 5, RANDOM_POINTS = 64, PTS = GRID * GRID * GRID + RANDOM_POINTS };

/* The batch rounds each bound correctly outward, the single box one ulp further; libm's
 * operations run box by box in both. A batch interval may exceed the single box's width
 * only by the last bits of those. */
#define BATCH_WIDTH_FACTOR (1.0 + 1e-9)

/* Box sizes relative to the preset's box: tiny, then ordinary, then huge. */
#define TINY_LOG2 (-30)
#define HUGE_LOG2 10

typedef struct rng {
    uint64_t s;
} rng;

static double uniform(rng *r, double lo, double hi)
{
    uint64_t z = (r->s += 0x9e3779b97f4a7c15ull);
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
    z ^= z >> 31;
    return lo + (hi - lo) * (double)(z >> 11) * 0x1p-53;
}

/* Long double rounds too (64 bits): its value at a point where a bound is attained exactly
 * may sit this far (relative to the largest intermediate) outside, without a bound being
 * wrong. Far below a double's ulp, so a bound one double ulp too tight is still caught. */
#define LONG_SLACK 0x1p-58

/* f at a point in long double, instruction by instruction (the tape's documented meaning,
 * not its evaluators); *largest gets the largest finite |intermediate|. */
static long double eval_long(const ism_tape *t, long double *r, long double x, long double y,
                             long double z, long double *largest)
{
    *largest = fmaxl(fabsl(x), fmaxl(fabsl(y), fabsl(z)));
    r[ISM_REG_X] = x;
    r[ISM_REG_Y] = y;
    r[ISM_REG_Z] = z;
    for (size_t i = 0; i < t->len; i++) {
        const ism_instr *in = &t->code[i];
        long double a = r[in->a], c = in->imm, b = ism_op_has_reg_b(in->op) ? r[in->b] : 0.0L;
        long double v;
        switch (in->op) {
        case ISM_OP_CONST: v = c; break;
        case ISM_OP_COPY: v = a; break;
        case ISM_OP_ADD_RR: v = a + b; break;
        case ISM_OP_ADD_RC: v = a + c; break;
        case ISM_OP_SUB_RR: v = a - b; break;
        case ISM_OP_SUB_CR: v = c - a; break;
        case ISM_OP_MUL_RR: v = a * b; break;
        case ISM_OP_MUL_RC: v = a * c; break;
        case ISM_OP_DIV_RR: v = a / b; break;
        case ISM_OP_DIV_RC: v = a / c; break;
        case ISM_OP_DIV_CR: v = c / a; break;
        case ISM_OP_MIN_RR: v = fminl(a, b); break;
        case ISM_OP_MIN_RC: v = fminl(a, c); break;
        case ISM_OP_MAX_RR: v = fmaxl(a, b); break;
        case ISM_OP_MAX_RC: v = fmaxl(a, c); break;
        case ISM_OP_NEG: v = -a; break;
        case ISM_OP_SQUARE: v = a * a; break;
        case ISM_OP_POWI: v = powl(a, (long double)in->b); break;
        case ISM_OP_POWC: v = powl(fmaxl(a, 0.0L), c); break;
        case ISM_OP_SQRT: v = sqrtl(fmaxl(a, 0.0L)); break;
        case ISM_OP_SIN: v = sinl(a); break;
        case ISM_OP_COS: v = cosl(a); break;
        case ISM_OP_TAN: v = tanl(a); break;
        case ISM_OP_EXP: v = expl(a); break;
        case ISM_OP_LOG: v = a > 0.0L ? logl(a) : -INFINITY; break;
        case ISM_OP_ABS: v = fabsl(a); break;
        default: v = NAN; break;
        }
        r[in->out] = v;
        if (isfinite(v))
            *largest = fmaxl(*largest, fabsl(v));
    }
    return r[t->result];
}

/* A point where f changes sign between two random points of the box (bisection), or the
 * box's centre when the samples found none. */
static void surface_point(const ism_tape *t, ism_eval_ws *ws, const double *box, rng *g,
                          double p[3])
{
    for (int k = 0; k < 3; k++)
        p[k] = 0.5 * (box[k] + box[k + 3]);
    for (int tries = 0; tries < 32; tries++) {
        double a[3], b[3];
        for (int k = 0; k < 3; k++) {
            a[k] = uniform(g, box[k], box[k + 3]);
            b[k] = uniform(g, box[k], box[k + 3]);
        }
        double fa = ism_eval_point(t, ws, a[0], a[1], a[2]);
        double fb = ism_eval_point(t, ws, b[0], b[1], b[2]);
        if (!(fa * fb < 0.0))
            continue;
        for (int it = 0; it < 60; it++) {
            double m[3] = { 0.5 * (a[0] + b[0]), 0.5 * (a[1] + b[1]), 0.5 * (a[2] + b[2]) };
            double fm = ism_eval_point(t, ws, m[0], m[1], m[2]);
            double *keep = (fm < 0.0) == (fa < 0.0) ? a : b;
            for (int k = 0; k < 3; k++)
                keep[k] = m[k];
        }
        for (int k = 0; k < 3; k++)
            p[k] = a[k];
        return;
    }
}

/* Box b of the preset's sequence: its kind cycles through ordinary, tiny, huge, straddling a
 * coordinate plane, straddling the surface. */
static void make_box(const ism_tape *t, ism_eval_ws *ws, const double *pbox, rng *g, int b,
                     ism_interval out[3])
{
    double centre[3], side[3];
    int kind = b % 5;
    if (kind == 4) {
        surface_point(t, ws, pbox, g, centre);
    } else {
        for (int k = 0; k < 3; k++)
            centre[k] = uniform(g, pbox[k], pbox[k + 3]);
        if (kind == 3)
            centre[b % 3] = uniform(g, -1e-3, 1e-3) * (pbox[b % 3 + 3] - pbox[b % 3]);
    }
    double scale = kind == 1 ? ldexp(1.0, TINY_LOG2) : kind == 2 ? ldexp(1.0, HUGE_LOG2)
                                                                  : ldexp(1.0, -(b % 9));
    for (int k = 0; k < 3; k++) {
        side[k] = scale * (pbox[k + 3] - pbox[k]) * uniform(g, 0.5, 1.0);
        double at = uniform(g, 0.1, 0.9); /* where the centre falls inside the box */
        out[k] = (ism_interval){ centre[k] - at * side[k], centre[k] + (1.0 - at) * side[k] };
    }
}

/* Grid point k of GRID along s, clamped into s (lo + (hi - lo) may round past hi). */
static double grid_at(ism_interval s, int k)
{
    return fmin(s.lo + (s.hi - s.lo) * k / (GRID - 1), s.hi);
}

/* The 5^3 grid of the box (corners and faces included), then random points. */
static void sample(const ism_interval box[3], rng *g, double *x, double *y, double *z)
{
    int i = 0;
    for (int a = 0; a < GRID; a++)
        for (int b = 0; b < GRID; b++)
            for (int c = 0; c < GRID; c++, i++) {
                x[i] = grid_at(box[0], a);
                y[i] = grid_at(box[1], b);
                z[i] = grid_at(box[2], c);
            }
    for (; i < PTS; i++) {
        x[i] = fmin(uniform(g, box[0].lo, box[0].hi), box[0].hi);
        y[i] = fmin(uniform(g, box[1].lo, box[1].hi), box[1].hi);
        z[i] = fmin(uniform(g, box[2].lo, box[2].hi), box[2].hi);
    }
}

static void check_preset(const ism_preset *p, uint64_t seed, size_t *checked)
{
    ism_error err;
    ism_tape *t = test_preset_tape(p, &err);
    cr_assert(t, "%s: %s", p->name, err.message);
    ism_eval_ws *ws = ism_eval_ws_new(t);
    long double *regs = malloc(t->nregs * sizeof *regs);
    cr_assert(ws && regs);
    rng g = { seed };
    ism_interval bx[BOXES], by[BOXES], bz[BOXES], out[BOXES];
    for (int b = 0; b < BOXES; b++) {
        ism_interval box[3];
        make_box(t, ws, p->box, &g, b, box);
        bx[b] = box[0];
        by[b] = box[1];
        bz[b] = box[2];
    }
    ism_eval_interval_batch(t, ws, bx, by, bz, out, BOXES);
    cr_assert_eq(fegetround(), FE_TONEAREST, "%s: the rounding mode is restored", p->name);
    double x[PTS], y[PTS], z[PTS], f[PTS];
    for (int b = 0; b < BOXES; b++) {
        ism_interval r = out[b], box[3] = { bx[b], by[b], bz[b] };
        cr_assert(r.lo <= r.hi, "%s box %d: [%g, %g]", p->name, b, r.lo, r.hi);
        ism_interval single = ism_eval_interval(t, ws, bx[b], by[b], bz[b]);
        if (single.hi - single.lo < INFINITY)
            cr_assert(r.hi - r.lo <= (single.hi - single.lo) * BATCH_WIDTH_FACTOR,
                      "%s box %d: batch [%.17g, %.17g] wider than single [%.17g, %.17g]",
                      p->name, b, r.lo, r.hi, single.lo, single.hi);
        sample(box, &g, x, y, z);
        ism_eval_batch(t, ws, x, y, z, f, PTS);
        for (int i = 0; i < PTS; i++) {
            long double big, v = eval_long(t, regs, x[i], y[i], z[i], &big);
            if (isnan(f[i]) || isnan(v))
                continue;
            (*checked)++;
            cr_assert(r.lo <= f[i] && f[i] <= r.hi,
                      "%s box %d: f(%.17g, %.17g, %.17g) = %.17g outside [%.17g, %.17g]",
                      p->name, b, x[i], y[i], z[i], f[i], r.lo, r.hi);
            cr_assert(r.lo - LONG_SLACK * big <= v && v <= r.hi + LONG_SLACK * big,
                      "%s box %d: long double f(%.17g, %.17g, %.17g) = %.21Lg outside "
                      "[%.17g, %.17g]", p->name, b, x[i], y[i], z[i], v, r.lo, r.hi);
        }
    }
    free(regs);
    ism_eval_ws_free(ws);
    ism_tape_free(t);
}

Test(ival_batch, encloses_every_preset_on_tiny_huge_and_straddling_boxes)
{
    size_t checked = 0;
    for (size_t i = 0; i < ism_preset_count(); i++)
        check_preset(ism_preset_at(i), 2026 + i, &checked);
    cr_expect_geq(checked, ism_preset_count() * BOXES * PTS / 2, "too few finite samples");
}

/* A caller in another rounding mode gets it back, and still an enclosure. */
Test(ival_batch, keeps_the_callers_rounding_mode)
{
    ism_error err;
    ism_tape *t = ism_tape_compile("x*y - z^2 + 0.1*x", NULL, 0, NULL, 0, NULL, &err);
    cr_assert(t);
    ism_eval_ws *ws = ism_eval_ws_new(t);
    ism_interval x = { 0.1, 0.3 }, y = { -0.2, 0.7 }, z = { -1.0 / 3.0, 0.25 }, r;
    cr_assert_eq(fesetround(FE_UPWARD), 0);
    ism_eval_interval_batch(t, ws, &x, &y, &z, &r, 1);
    int mode = fegetround();
    fesetround(FE_TONEAREST);
    cr_expect_eq(mode, FE_UPWARD);
    /* range: x*y in [-0.06, 0.21], -z^2 in [-1/9, 0], 0.1x in [0.01, 0.03] */
    cr_expect(r.lo <= -0.06 - 1.0 / 9.0 + 0.01 && r.hi >= 0.21 + 0.03, "[%.17g, %.17g]", r.lo,
              r.hi);
    ism_eval_ws_free(ws);
    ism_tape_free(t);
}

/* Overflowing intermediates (exp of 800 is beyond double, within long double; log 0 is
 * [-inf, -inf]): the batch keeps every register below +inf, so inf - inf and 0 * inf must
 * still give enclosures, not NaN. Five boxes (one partial vector), each checked at its corners in long double. */
Test(ival_batch, overflowing_intermediates_stay_enclosures)
{
    static const char *const exprs[] = { "exp(x) - exp(y)", "exp(x)*y", "exp(x) + y - exp(z)",
                                         "log(x) - log(y)", "log(x)*y - z" };
    enum { N = 5 };
    const ism_interval x[N] = { { 800, 801 }, { 800, 801 }, { -1, 1 }, { 710, 720 }, { 0, 0 } };
    const ism_interval y[N] = { { 800, 801 }, { 0, 0 }, { -1, 1 }, { -1, 1 }, { 0, 0 } };
    const ism_interval z[N] = { { 800, 801 }, { 800, 801 }, { 800, 801 }, { 1, 2 }, { 0, 0 } };
    for (size_t e = 0; e < sizeof exprs / sizeof exprs[0]; e++) {
        ism_error err;
        ism_tape *t = ism_tape_compile(exprs[e], NULL, 0, NULL, 0, NULL, &err);
        cr_assert(t, "%s: %s", exprs[e], err.message);
        ism_eval_ws *ws = ism_eval_ws_new(t);
        long double *regs = malloc(t->nregs * sizeof *regs);
        cr_assert(ws && regs);
        ism_interval out[N];
        ism_eval_interval_batch(t, ws, x, y, z, out, N);
        for (int b = 0; b < N; b++) {
            ism_interval r = out[b], single = ism_eval_interval(t, ws, x[b], y[b], z[b]);
            cr_assert(r.lo <= r.hi, "%s box %d: [%g, %g]", exprs[e], b, r.lo, r.hi);
            if (single.hi - single.lo < INFINITY)
                cr_expect(r.hi - r.lo <= (single.hi - single.lo) * BATCH_WIDTH_FACTOR,
                          "%s box %d: batch [%g, %g] wider than single [%g, %g]", exprs[e], b,
                          r.lo, r.hi, single.lo, single.hi);
            for (int c = 0; c < 8; c++) {
                long double big, v = eval_long(t, regs, c & 1 ? x[b].hi : x[b].lo,
                                                c & 2 ? y[b].hi : y[b].lo,
                                                c & 4 ? z[b].hi : z[b].lo, &big);
                if (isnan(v))
                    continue;
                cr_expect(r.lo - LONG_SLACK * big <= v && v <= r.hi + LONG_SLACK * big,
                          "%s box %d corner %d: %Lg outside [%g, %g]", exprs[e], b, c, v,
                          r.lo, r.hi);
            }
        }
        free(regs);
        ism_eval_ws_free(ws);
        ism_tape_free(t);
    }
}
