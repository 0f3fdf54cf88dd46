/* test_interval_golden.c — the interval evaluators' output bits pinned to committed digests:
 * the one-box pass (ism_interval_run, its choices too), the batched pass, the interval
 * gradient (plain and kept), its batch, and the interval jet (full, and the Hessian alone
 * after a kept gradient), on three tapes over fixed special and random boxes. These passes
 * are compiled twice (avx2_clone.h): the release build on an AVX2 machine runs the AVX2
 * copies, the sanitizer build (ISM_BASELINE_ONLY) the baseline, both against these numbers,
 * so a change that moves the copies' bits apart (an fma in the clone's target, contraction)
 * fails one lane. Only correctly rounded operations (+ − × ÷, sqrt, min, max, abs, powers)
 * and no libm in the boxes, so the digests hold on any IEEE machine. A digest that changes on
 * purpose (an evaluator's rounding made tighter) is updated here with the commit that says so. */
#include <criterion/criterion.h>
#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "core/eval/interval_eval.h"
#include "core/eval/interval_jet.h"
#include "core/expr/tape.h"
#include "test_eval_surfaces.h"

enum { NBOX = 320, NSPECIAL = 8 };

/* FNV-1a, 64 bits, over bytes. */
typedef struct digest {
    uint64_t h;
} digest;

static void mix_bytes(digest *d, const void *p, size_t n)
{
    const unsigned char *b = p;
    for (size_t i = 0; i < n; i++)
        d->h = (d->h ^ b[i]) * 0x100000001b3ULL;
}

/* Doubles, every NaN as one pattern (a NaN's sign is not part of the contract). */
static void mix_doubles(digest *d, const double *x, size_t n)
{
    for (size_t i = 0; i < n; i++) {
        uint64_t u = 0x7ff8000000000000ULL;
        if (x[i] == x[i])
            memcpy(&u, &x[i], sizeof u);
        mix_bytes(d, &u, sizeof u);
    }
}

/* Box k of a tape's set: the first NSPECIAL fixed (a point, one containing 0 on every axis,
 * a huge one, one touching ±0, a thin one, a whole-line one, a negative one, one at the
 * tape's corner), the rest random in [-2, 2]^3 with sides 2^-U(0, 12) of 4 (a power of two
 * times a uniform: no libm). */
static void box_of(size_t k, test_rng *rng, ism_interval b[3])
{
    static const ism_interval special[NSPECIAL][3] = {
        { { 0.5, 0.5 }, { -0.25, -0.25 }, { 0.125, 0.125 } },
        { { -1, 1 }, { -1, 1 }, { -1, 1 } },
        { { -1e150, 1e150 }, { -1e150, 1e150 }, { -3, 3 } },
        { { -0.0, 0.0 }, { 0.0, 0.5 }, { -0.5, -0.0 } },
        { { 0.3, 0.3 + 0x1p-40 }, { -0.7, -0.7 + 0x1p-40 }, { 0.1, 0.1 + 0x1p-40 } },
        { { -INFINITY, INFINITY }, { -1, 1 }, { 0, 1 } },
        { { -2, -1 }, { -2, -1 }, { -2, -1 } },
        { { 1.5, 2 }, { 1.5, 2 }, { 1.5, 2 } },
    };
    if (k < NSPECIAL) {
        memcpy(b, special[k], sizeof special[k]);
        return;
    }
    for (int a = 0; a < 3; a++) {
        double w = 4.0 * ldexp(test_uniform(rng, 0.5, 1.0), -(int)test_uniform(rng, 0.0, 13.0));
        double lo = test_uniform(rng, -2.0, 2.0 - w);
        b[a] = (ism_interval){ lo, lo + w };
    }
}

/* What each pass gave over every box, one digest a pass. */
enum { D_RUN, D_BATCH, D_GRAD, D_KEPT, D_GBATCH, D_JET, D_HESS, D_N };
static const char *const PASS[D_N] = { "interval_run", "interval_batch", "interval_grad",
                                       "interval_grad_kept", "interval_grad_batch",
                                       "interval_jet", "jet_after_kept" };

static void digests_of(const ism_tape *t, uint64_t out[D_N])
{
    size_t len = ism_tape_length(t);
    ism_eval_ws *ews = ism_eval_ws_new(t);
    ism_ivjet_ws *jws = ism_ivjet_ws_new(t), *fresh = ism_ivjet_ws_new(t);
    uint8_t *buf = malloc(len + 1);
    ism_interval(*boxes)[3] = malloc(NBOX * sizeof *boxes);
    ism_interval *bx = malloc(NBOX * 3 * sizeof *bx), *iv = malloc(NBOX * sizeof *iv);
    cr_assert(ews && jws && fresh && buf && boxes && bx && iv);
    digest d[D_N];
    for (int p = 0; p < D_N; p++)
        d[p].h = 0xcbf29ce484222325ULL;
    test_rng rng = { 2028 };
    for (size_t k = 0; k < NBOX; k++) {
        ism_interval *b = boxes[k];
        box_of(k, &rng, b);
        for (int a = 0; a < 3; a++)
            bx[a * NBOX + k] = b[a];
        memset(buf, 0, len + 1); /* choices are written at min, max and abs only */
        ism_interval r = ism_interval_run(t, ews, b[0], b[1], b[2], buf);
        mix_doubles(&d[D_RUN], &r.lo, 2);
        mix_bytes(&d[D_RUN], buf, len);
        ism_ivgrad g;
        size_t nk = ism_eval_interval_grad(t, jws, b, NULL, buf, &g);
        mix_doubles(&d[D_GRAD], &g.v.lo, sizeof g / sizeof(double));
        mix_bytes(&d[D_GRAD], &nk, sizeof nk);
        mix_bytes(&d[D_GRAD], buf, len);
        ism_ivjet j;
        nk = ism_eval_interval_jet(t, fresh, b, NULL, buf, &j);
        mix_doubles(&d[D_JET], &j.v.lo, sizeof j / sizeof(double));
        mix_bytes(&d[D_JET], &nk, sizeof nk);
        mix_bytes(&d[D_JET], buf, len);
        nk = ism_eval_interval_grad_kept(t, jws, b, &g);
        mix_doubles(&d[D_KEPT], &g.v.lo, sizeof g / sizeof(double));
        mix_bytes(&d[D_KEPT], &nk, sizeof nk);
        nk = ism_eval_interval_jet(t, jws, b, NULL, NULL, &j); /* the Hessian alone */
        mix_doubles(&d[D_HESS], &j.v.lo, sizeof j / sizeof(double));
        mix_bytes(&d[D_HESS], &nk, sizeof nk);
    }
    ism_eval_interval_batch(t, ews, bx, bx + NBOX, bx + 2 * NBOX, iv, NBOX);
    mix_doubles(&d[D_BATCH], &iv[0].lo, 2 * NBOX);
    for (size_t k = 0; k < NBOX; k += ISM_IVGRAD_BATCH) {
        ism_ivgrad gb[ISM_IVGRAD_BATCH];
        size_t n = NBOX - k < ISM_IVGRAD_BATCH ? NBOX - k : ISM_IVGRAD_BATCH;
        bool ok = ism_eval_interval_grad_batch(t, jws, (const ism_interval(*)[3])boxes + k, n, gb);
        mix_bytes(&d[D_GBATCH], &ok, sizeof ok);
        if (ok)
            mix_doubles(&d[D_GBATCH], &gb[0].v.lo, n * sizeof gb[0] / sizeof(double));
    }
    for (int p = 0; p < D_N; p++)
        out[p] = d[p].h;
    free(iv);
    free(bx);
    free(boxes);
    free(buf);
    ism_ivjet_ws_free(fresh);
    ism_ivjet_ws_free(jws);
    ism_eval_ws_free(ews);
}

static const test_surface MIXED = {
    "mixed", "sqrt(x^2 + y^2 + 0.25) / (abs(z) + 0.5) - min(x*y, 1 - z) "
             "+ max(abs(x - y), -1.5*z^3) - 2/(x^2 + 1) + (y - 0.3)^4",
    { { 0 } }, 0, { { 0 } }, 0, { -2, -2, -2, 2, 2, 2 }, 0,
};

static void check_golden(const test_surface *s, const uint64_t want[D_N])
{
    ism_tape *t = test_surface_compile(s);
    uint64_t got[D_N];
    digests_of(t, got);
    for (int p = 0; p < D_N; p++)
        cr_expect_eq(got[p], want[p], "%s %s: digest 0x%016llxULL, committed 0x%016llxULL",
                     s->name, PASS[p], (unsigned long long)got[p],
                     (unsigned long long)want[p]);
    ism_tape_free(t);
}

/* Digests taken with the AVX2 copies (release build; all but interval_run's on main
 * 9b0c06d7's objects, the same after revP 3 and 4) and checked equal by the baseline (SAN=1,
 * ISM_BASELINE_ONLY). */
Test(interval_golden, torus)
{
    static const uint64_t want[D_N] = {
        0x38849cc29f758440ULL, 0x6406c319f93a441fULL, 0xacf87400d42df269ULL, 0x17f0b7a2c0b3ccf9ULL,
        0xd9e33a9a93ea841dULL, 0xfa043194e7829a60ULL, 0xc995e9d5ddd5ba18ULL,
    };
    check_golden(test_surface_named("torus"), want);
}

Test(interval_golden, klein_bottle)
{
    static const uint64_t want[D_N] = {
        0x0793cdf6939bca35ULL, 0xbdeb6c2cf0fea06eULL, 0xfbcc127d9577e2acULL, 0x0082395bca757f4cULL,
        0x46f505cf67940bc6ULL, 0x569304a1cd813b1bULL, 0x147cf9a58ab52bebULL,
    };
    check_golden(test_surface_named("klein-bottle"), want);
}

Test(interval_golden, division_sqrt_min_abs)
{
    static const uint64_t want[D_N] = {
        0x86744fc8fd791e71ULL, 0xe956b464b73aa51eULL, 0x80c36e6f3d4a7280ULL, 0xd06a9f45c6a59e17ULL,
        0x40d69e0cf0f65c45ULL, 0xb6d747724a0990a2ULL, 0x28bd2f0b6cf77529ULL,
    };
    check_golden(&MIXED, want);
}
