/* fuzz_expr.c — libFuzzer target for the expression engine: parse and compile (with
 * parameters and lets, fuzz_text.h layout), then check what the compiled tape promises:
 * the canonical text is snprintf-like and stable, batch and single-point values agree, the
 * gradient and Hessian evaluators return the same f, every interval encloses the values at
 * points of its box (never NaN, never lo > hi), the batched interval equals the single one,
 * and a shortened tape equals the full one inside its box.
 *
 * Interval promises hold where f is defined. sqrt, log and real powers are clipped (defined
 * everywhere), but 0/0, inf - inf, 0*inf and sin(inf) are not, and min/max may then pass
 * either operand on; such points raise FE_INVALID in the (scalar) point evaluator, and the
 * enclosure and shortening checks skip them. 
 *
 * The regression tests include this file with ISM_FUZZ_NO_ENTRY defined and call
 * ism_fuzz_expr on every committed input. */
#include <fenv.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "core/expr/expr.h"
#include "core/eval/eval.h"
#include "tests/fuzz/fuzz_check.h"
#include "tests/fuzz/fuzz_text.h"

#define EXPR_NPOINTS 8
static const double expr_points[EXPR_NPOINTS][3] = {
    {0, 0, 0},     {1, 0.5, -0.25}, {-0.3, 0.7, 0.2}, {1e-9, -1e-9, 0},
    {2, -3, 5},    {-1, -1, -1},    {0.5, 0.5, 0.5},  {1e3, -1e3, 7},
};

#define EXPR_NBOXES 6
static const double expr_boxes[EXPR_NBOXES][6] = {
    {-1, -1, -1, 1, 1, 1},
    {0.25, -0.5, 1, 0.75, 0.125, 2},
    {0.5, -0.25, 0, 0.5, -0.25, 0},         /* a single point */
    {-1000, -1000, -1000, 1000, 1000, 1000},
    {-1e-8, -1e-8, -1e-8, 1e-8, 1e-8, 1e-8}, /* around the poles of 1/x, log(x) */
    {-3, 0, -0.1, -2, 4, 0.1},
};

/* Points of a box where values are compared: corners, centre and two inside. */
#define EXPR_NSAMPLES 11
static void expr_box_samples(const double b[6], double p[EXPR_NSAMPLES][3])
{
    static const double frac[EXPR_NSAMPLES][3] = {
        {0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {1, 1, 0}, {0, 0, 1}, {1, 0, 1}, {0, 1, 1},
        {1, 1, 1}, {0.5, 0.5, 0.5}, {0.3, 0.7, 0.1}, {0.9, 0.2, 0.6},
    };
    for (int i = 0; i < EXPR_NSAMPLES; i++)
        for (int k = 0; k < 3; k++) {
            double t = frac[i][k];
            p[i][k] = t == 0 ? b[k] : t == 1 ? b[3 + k] : b[k] + t * (b[3 + k] - b[k]);
        }
}

static void expr_check_canonical(const ism_tape *t)
{
    size_t n = ism_tape_canonical(t, NULL, 0);
    FUZZ_CHECK(n > 0, "canonical text is empty");
    char *full = malloc(n + 1);
    FUZZ_CHECK(full != NULL, "out of memory");
    FUZZ_CHECK(ism_tape_canonical(t, full, n + 1) == n, "canonical length changed");
    FUZZ_CHECK(strlen(full) == n, "canonical text has %zu bytes, said %zu", strlen(full), n);
    size_t cut = n / 2 + 1;
    char *part = malloc(cut);
    FUZZ_CHECK(part != NULL, "out of memory");
    FUZZ_CHECK(ism_tape_canonical(t, part, cut) == n, "truncated canonical changed length");
    FUZZ_CHECK(strlen(part) == cut - 1 && memcmp(part, full, cut - 1) == 0,
               "truncated canonical is not a prefix");
    free(part);
    free(full);
}

static int expr_defined_at(const ism_tape *t, ism_eval_ws *ws, const double p[3], double *v,
                           int undefined);

static void expr_check_points(const ism_tape *t, ism_eval_ws *ws)
{
    double x[EXPR_NPOINTS], y[EXPR_NPOINTS], z[EXPR_NPOINTS], out[EXPR_NPOINTS];
    for (int i = 0; i < EXPR_NPOINTS; i++) {
        x[i] = expr_points[i][0];
        y[i] = expr_points[i][1];
        z[i] = expr_points[i][2];
    }
    ism_eval_batch(t, ws, x, y, z, out, EXPR_NPOINTS);
    for (int i = 0; i < EXPR_NPOINTS; i++) {
        double v = ism_eval_point(t, ws, x[i], y[i], z[i]);
        FUZZ_CHECK(fuzz_same(v, out[i]), "point %d: batch %.17g, single %.17g", i, out[i], v);
        double g[3], gh[3], h[6];
        feclearexcept(FE_ALL_EXCEPT);
        double vg = ism_eval_gradient(t, ws, x[i], y[i], z[i], g);
        double vh = ism_eval_hessian(t, ws, x[i], y[i], z[i], gh, h);
        int exact = !fetestexcept(FE_INVALID | FE_DIVBYZERO | FE_OVERFLOW);
        FUZZ_CHECK(fuzz_same(vg, v), "point %d: gradient's f %.17g, f %.17g", i, vg, v);
        FUZZ_CHECK(fuzz_same(vh, v), "point %d: Hessian's f %.17g, f %.17g", i, vh, v);
        /* Both use the same derivative rules, but the Hessian's divisions and products carry
         * more terms: past an overflow (inf/inf, 0*inf) they may disagree, and rightly. */
        for (int k = 0; exact && k < 3; k++)
            FUZZ_CHECK(fuzz_same(gh[k], g[k]), "point %d: Hessian's gradient[%d] %.17g, "
                       "gradient's %.17g", i, k, gh[k], g[k]);

        /* The interval of the box that is just this point holds f there (rounding is
         * outward, so the tightest intervals test it hardest). */
        ism_interval px = {x[i], x[i]}, py = {y[i], y[i]}, pz = {z[i], z[i]};
        ism_interval r = ism_eval_interval(t, ws, px, py, pz);
        double fv;
        int defined = expr_defined_at(t, ws, expr_points[i], &fv, FE_INVALID);
        FUZZ_CHECK(!isnan(r.lo) && !isnan(r.hi) && r.lo <= r.hi && (!defined ||
                   (r.lo <= fv && fv <= r.hi)), "point %d: interval [%.17g, %.17g] of the "
                   "point misses f = %.17g", i, r.lo, r.hi, fv);
    }
}

/* f at p; false when an operation on the way raised one of the exceptions in `undefined`. */
static int expr_defined_at(const ism_tape *t, ism_eval_ws *ws, const double p[3], double *v,
                           int undefined)
{
    feclearexcept(FE_ALL_EXCEPT);
    *v = ism_eval_point(t, ws, p[0], p[1], p[2]);
    return !fetestexcept(undefined);
}

static void expr_check_encloses(const ism_tape *t, ism_eval_ws *ws, ism_interval r,
                                const double p[EXPR_NSAMPLES][3], int box, const char *what)
{
    FUZZ_CHECK(!isnan(r.lo) && !isnan(r.hi) && r.lo <= r.hi,
               "box %d: %s interval [%.17g, %.17g]", box, what, r.lo, r.hi);
    for (int i = 0; i < EXPR_NSAMPLES; i++) {
        double v;
        int defined = expr_defined_at(t, ws, p[i], &v, FE_INVALID);
        FUZZ_CHECK(!defined || (r.lo <= v && v <= r.hi),
                   "box %d: %s interval [%.17g, %.17g] misses f(%.17g, %.17g, %.17g) = %.17g",
                   box, what, r.lo, r.hi, p[i][0], p[i][1], p[i][2], v);
    }
}

static void expr_check_boxes(const ism_tape *t, ism_eval_ws *ws)
{
    ism_interval bx[EXPR_NBOXES], by[EXPR_NBOXES], bz[EXPR_NBOXES], batch[EXPR_NBOXES];
    for (int b = 0; b < EXPR_NBOXES; b++) {
        bx[b] = (ism_interval){expr_boxes[b][0], expr_boxes[b][3]};
        by[b] = (ism_interval){expr_boxes[b][1], expr_boxes[b][4]};
        bz[b] = (ism_interval){expr_boxes[b][2], expr_boxes[b][5]};
    }
    ism_eval_interval_batch(t, ws, bx, by, bz, batch, EXPR_NBOXES);
    ism_tape *shorter = ism_tape_new_like(t);
    FUZZ_CHECK(shorter != NULL, "out of memory");
    for (int b = 0; b < EXPR_NBOXES; b++) {
        double p[EXPR_NSAMPLES][3];
        expr_box_samples(expr_boxes[b], p);
        ism_interval r = ism_eval_interval(t, ws, bx[b], by[b], bz[b]);
        expr_check_encloses(t, ws, r, p, b, "");
        /* The batch rounds each bound correctly outward (round-down mode), the single box
         * one ulp further: it encloses f too and is no wider (but for libm's last bits). */
        expr_check_encloses(t, ws, batch[b], p, b, "batch ");
        FUZZ_CHECK(!(r.hi - r.lo < INFINITY)
                       || (batch[b].lo >= r.lo - 1e-9 * (r.hi - r.lo)
                           && batch[b].hi <= r.hi + 1e-9 * (r.hi - r.lo)),
                   "box %d: batch interval [%.17g, %.17g], single [%.17g, %.17g]", b,
                   batch[b].lo, batch[b].hi, r.lo, r.hi);

        ism_interval range = {NAN, NAN};
        bool cut = ism_tape_shorten(t, ws, bx[b], by[b], bz[b], shorter, &range);
        FUZZ_CHECK(fuzz_same(range.lo, r.lo) && fuzz_same(range.hi, r.hi),
                   "box %d: shorten's range [%.17g, %.17g], interval [%.17g, %.17g]", b,
                   range.lo, range.hi, r.lo, r.hi);
        if (!cut)
            continue;
        FUZZ_CHECK(ism_tape_length(shorter) < ism_tape_length(t),
                   "box %d: shortened tape has %zu instructions, the full one %zu", b,
                   ism_tape_length(shorter), ism_tape_length(t));
        for (int i = 0; i < EXPR_NSAMPLES; i++) {
            double full, part = ism_eval_point(shorter, ws, p[i][0], p[i][1], p[i][2]);
            /* Also skipped: poles (FE_DIVBYZERO). min(0, -0) is +0 or -0 depending on which
             * branch survives, equal as numbers, but 1/(+0) and 1/(-0) are not. */
            FUZZ_CHECK(!expr_defined_at(t, ws, p[i], &full, FE_INVALID | FE_DIVBYZERO) ||
                       fuzz_same(full, part),
                       "box %d: shortened tape gives %.17g at (%.17g, %.17g, %.17g), full %.17g",
                       b, part, p[i][0], p[i][1], p[i][2], full);
        }
        expr_check_encloses(shorter, ws, ism_eval_interval(shorter, ws, bx[b], by[b], bz[b]),
                            p, b, "shortened");
        expr_check_canonical(shorter);
    }
    ism_tape_free(shorter);
}

static void expr_check_error(const ism_error *err)
{
    FUZZ_CHECK(memchr(err->message, 0, sizeof err->message) && err->message[0],
               "compile failed without a message");
    FUZZ_CHECK(memchr(err->where, 0, sizeof err->where) != NULL, "where is not terminated");
    FUZZ_CHECK(err->line >= 0 && err->column >= 0, "negative position %d:%d", err->line,
               err->column);
    char line[512];
    ism_error_format(err, line, sizeof line);
    FUZZ_CHECK(line[0] != '\0', "formatted error is empty");
}

int ism_fuzz_expr(const uint8_t *data, size_t size)
{
    fuzz_text in;
    if (!fuzz_text_parse(&in, data, size))
        return 0;
    ism_expr_limits lim;
    ism_expr_limits_default(&lim);
    lim.max_source = 2000; /* below -max_len, so the limit's error is reachable */
    ism_error err;
    memset(&err, 0, sizeof err);
    ism_tape *t = ism_tape_compile(in.expr, in.params, in.nparams, in.lets, in.nlets, &lim,
                                   &err);
    if (!t) {
        expr_check_error(&err);
        fuzz_text_free(&in);
        return 0;
    }
    FUZZ_CHECK(ism_tape_length(t) > 0 || ism_tape_registers(t) > 0, "empty tape");
    expr_check_canonical(t);

    /* Compiling again gives the same function, written the same way. */
    ism_tape *again = ism_tape_compile(in.expr, in.params, in.nparams, in.lets, in.nlets, &lim,
                                       &err);
    FUZZ_CHECK(again != NULL, "second compile failed: %s", err.message);
    size_t n1 = ism_tape_canonical(t, NULL, 0), n2 = ism_tape_canonical(again, NULL, 0);
    char *c1 = malloc(n1 + 1), *c2 = malloc(n2 + 1);
    FUZZ_CHECK(c1 && c2, "out of memory");
    ism_tape_canonical(t, c1, n1 + 1);
    ism_tape_canonical(again, c2, n2 + 1);
    FUZZ_CHECK(strcmp(c1, c2) == 0, "two compiles of one source differ");
    free(c1);
    free(c2);
    ism_tape_free(again);

    ism_eval_ws *ws = ism_eval_ws_new(t);
    FUZZ_CHECK(ws != NULL, "out of memory");
    expr_check_points(t, ws);
    expr_check_boxes(t, ws);
    ism_eval_ws_free(ws);
    ism_tape_free(t);
    fuzz_text_free(&in);
    return 0;
}

#ifndef ISM_FUZZ_NO_ENTRY
int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);
int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    return ism_fuzz_expr(data, size);
}
#endif
