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

/* Over nboxes random boxes: wherever the unforced pass lists the last instruction as a free
 * kink, top_pieces answers and matches the two forced passes to the bit; elsewhere it does
 * not answer. Returns the boxes it answered. */
static size_t pieces_match(const char *src, size_t nboxes, uint64_t seed)
{
    ism_tape *t = compile(src);
    ism_ivjet_ws *jw = ism_ivjet_ws_new(t);
    cr_assert_not_null(jw);
    size_t len = t->len, answered = 0;
    uint8_t kinks[256], force[256];
    cr_assert(len <= sizeof kinks);
    test_rng rng = { seed };
    for (size_t n = 0; n < nboxes; n++) {
        ism_interval b[3];
        random_box(&rng, b);
        ism_ivgrad g, piece[2], forced;
        ism_eval_interval_grad(t, jw, b, NULL, kinks, &g);
        bool ok = ism_ivjet_top_pieces(t, jw, piece);
        cr_assert(!ok || kinks[len - 1], "%s: pieces read where the top is decided", src);
        if (!ok)
            continue;
        answered++;
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
    return answered;
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
        size_t answered = pieces_match(TOPS[i], boxes, 0x51ce + i);
        cr_expect_gt(answered, boxes / 100, "%s: %zu of %zu boxes answered", TOPS[i], answered,
                     boxes);
    }
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
        cr_expect_eq(pieces_match(OTHERS[i], test_scaled(500), 0xab + i), 0, "%s", OTHERS[i]);
}
