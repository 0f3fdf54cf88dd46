/* test_ivjet_top_pieces.c — ism_ivjet_top_pieces (interval_jet.h): after an unforced interval
 * gradient pass over a box where the tape's last instruction, a min or max, is a free kink,
 * the two pieces it reads from the registers are bit for bit the passes with that instruction
 * forced onto A and onto B (run beside it, the reference); it reads nothing where the top is
 * decided by the box, is no min or max, or lacks a variable. */
#include <criterion/criterion.h>
#include <math.h>
#include <string.h>

#include "core/eval/interval_jet.h"
#include "core/expr/tape.h"
#include "test_eval_surfaces.h"

static ism_tape *compile(const char *src)
{
    ism_error err;
    ism_tape *t = ism_tape_compile(src, NULL, 0, NULL, 0, NULL, &err);
    cr_assert_not_null(t, "%s: %s", src, err.message);
    return t;
}

/* A random box in [-2, 2]³, each side 2^-U(0, 10) of the whole. */
static void random_box(test_rng *rng, ism_interval b[3])
{
    for (int k = 0; k < 3; k++) {
        double w = 4.0 * exp2(-test_uniform(rng, 0.0, 10.0));
        double a = test_uniform(rng, -2.0, 2.0 - w);
        b[k] = (ism_interval){ a, a + w };
    }
}

/* Boxes top_pieces answered in: all, and those where the unforced pass found one free kink
 * (the callers' nk == 1) or more (the top's and one below it). */
typedef struct answers {
    size_t all, one_kink, more_kinks;
} answers;

/* Over nboxes random boxes: wherever top_pieces answers it matches the two forced passes to
 * the bit, and only where the unforced pass lists the last instruction as a free kink; with
 * every_top_kink (a top min/max depending on x, y and z, its result a register of its own)
 * it answers at every such box. */
static answers pieces_match(const char *src, size_t nboxes, uint64_t seed, bool every_top_kink)
{
    ism_tape *t = compile(src);
    ism_ivjet_ws *jw = ism_ivjet_ws_new(t);
    cr_assert_not_null(jw);
    size_t len = t->len;
    answers got = { 0 };
    uint8_t kinks[256], force[256];
    cr_assert(len <= sizeof kinks);
    test_rng rng = { seed };
    for (size_t n = 0; n < nboxes; n++) {
        ism_interval b[3];
        random_box(&rng, b);
        ism_ivgrad g, piece[2], forced;
        size_t nk = ism_eval_interval_grad(t, jw, b, NULL, kinks, &g);
        bool ok = ism_ivjet_top_pieces(t, jw, b, piece);
        cr_assert(!ok || kinks[len - 1], "%s: pieces read where the top is decided", src);
        if (every_top_kink)
            cr_assert(ok || !kinks[len - 1],
                      "%s: nothing read at a free top kink over [%g %g]x[%g %g]x[%g %g]", src,
                      b[0].lo, b[0].hi, b[1].lo, b[1].hi, b[2].lo, b[2].hi);
        if (!ok)
            continue;
        got.all++;
        got.one_kink += nk == 1;
        got.more_kinks += nk > 1;
        for (int p = 0; p < 2; p++) {
            memset(force, ISM_BRANCH_FREE, len);
            force[len - 1] = p ? ISM_BRANCH_B : ISM_BRANCH_A;
            ism_eval_interval_grad(t, jw, b, force, NULL, &forced);
            cr_assert(memcmp(&forced, &piece[p], sizeof forced) == 0,
                      "%s: piece %d over [%g %g]x[%g %g]x[%g %g] differs from the forced pass",
                      src, p, b[0].lo, b[0].hi, b[1].lo, b[1].hi, b[2].lo, b[2].hi);
        }
    }
    ism_ivjet_ws_free(jw);
    ism_tape_free(t);
    return got;
}

Test(eval_top_pieces, read_pieces_are_the_forced_passes)
{
    static const char *const TOPS[] = {
        /* Barth's sextic in its ball (bench_error's barth-sextic, phi written out) */
        "max(4*(2.6180339887498949*x^2 - y^2)*(2.6180339887498949*y^2 - z^2)*"
        "(2.6180339887498949*z^2 - x^2) - 4.2360679774997898*(x^2 + y^2 + z^2 - 1)^2, "
        "x^2 + y^2 + z^2 - 2.25)",
        "max(sin(3*x)*cos(3*y) + sin(3*y)*cos(3*z) + sin(3*z)*cos(3*x), x^2 + y^2 + z^2 - 2)",
        "min(x^2 + y^2 - 1, z)",         /* an input register as an operand */
        "max(x*y*z, 0.25)",              /* a constant operand: its partials 0 */
        "max(min(x, y) + z, x*x - z)",   /* a kink below the top, free in some boxes */
    };
    size_t boxes = test_scaled(3000);
    for (size_t i = 0; i < sizeof TOPS / sizeof *TOPS; i++) {
        answers got = pieces_match(TOPS[i], boxes, 0x51ce + i, true);
        /* the callers' case, one free kink (the top's), met in more than 1% of the boxes */
        cr_expect_gt(got.one_kink, boxes / 100, "%s: %zu of %zu boxes answered with one kink",
                     TOPS[i], got.one_kink, boxes);
        if (i == 4) /* and the read checked where the kink below is free too */
            cr_expect_gt(got.more_kinks, 0, "%s: no box with both kinks free", TOPS[i]);
    }
}

/* The pieces are read only from the registers of an unforced gradient pass of the same tape
 * over the same box: after any other pass, top_pieces answers nothing. */
Test(eval_top_pieces, nothing_read_after_another_pass)
{
    const char *src = "max(x^2 + y^2 + z^2 - 1, z)", *other_src = "max(x^2 + y^2 + z^2 - 1, y)";
    ism_tape *t = compile(src), *other = compile(other_src);
    ism_ivjet_ws *jw = ism_ivjet_ws_new(t);
    cr_assert_not_null(jw);
    cr_assert_eq(other->nregs, t->nregs);
    /* x² + y² + z² − 1 in [−1, 0.5] and z in [−1, 0.5]: the top kink is free */
    ism_interval b[3] = { { -0.5, 0.5 }, { -0.5, 0.5 }, { -1.0, 0.5 } };
    ism_interval b2[3] = { { -0.5, 0.5 }, { -0.5, 0.5 }, { -1.0, 0.6 } };
    uint8_t force[64];
    cr_assert(t->len <= sizeof force);
    memset(force, ISM_BRANCH_FREE, t->len);
    ism_ivgrad g, piece[2];
    ism_ivjet j;
    ism_eval_interval_grad(t, jw, b, NULL, NULL, &g);
    cr_assert(ism_ivjet_top_pieces(t, jw, b, piece), "the unforced pass itself is read");
    cr_expect_not(ism_ivjet_top_pieces(t, jw, b2, piece), "another box");
    cr_expect_not(ism_ivjet_top_pieces(other, jw, b, piece), "another tape");
    ism_eval_interval_grad(t, jw, b, force, NULL, &g); /* a force, even one forcing nothing */
    cr_expect_not(ism_ivjet_top_pieces(t, jw, b, piece), "after a forced pass");
    ism_eval_interval_grad(t, jw, b2, NULL, NULL, &g);
    cr_expect_not(ism_ivjet_top_pieces(t, jw, b, piece), "after a pass over another box");
    ism_eval_interval_grad(other, jw, b, NULL, NULL, &g);
    cr_expect_not(ism_ivjet_top_pieces(t, jw, b, piece), "after a pass of another tape");
    ism_eval_interval_jet(t, jw, b, NULL, NULL, &j);
    cr_expect_not(ism_ivjet_top_pieces(t, jw, b, piece), "after a second-order pass");
    ism_eval_interval_grad_kept(t, jw, b, &g);
    ism_eval_interval_jet(t, jw, b, NULL, NULL, &j); /* the Hessian from the kept record */
    cr_expect_not(ism_ivjet_top_pieces(t, jw, b, piece), "after a kept record's jet");
    ism_ivjet_ws_free(jw);
    ism_tape_free(other);
    ism_tape_free(t);
}

Test(eval_top_pieces, nothing_read_where_the_top_is_no_full_min_or_max)
{
    static const char *const OTHERS[] = {
        "abs(x^2 + y^2 + z^2 - 1)",      /* abs: not read */
        "max(x^2 - 1, y)",               /* no z: a partial the pass did not take */
        "x^2 + y^2 + z^2 - 1",           /* no kink */
        "max(x, y) * z",                 /* the kink below the top */
    };
    for (size_t i = 0; i < sizeof OTHERS / sizeof *OTHERS; i++)
        cr_expect_eq(pieces_match(OTHERS[i], test_scaled(500), 0xab + i, false).all, 0, "%s",
                     OTHERS[i]);
}
