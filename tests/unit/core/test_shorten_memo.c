/* test_shorten_memo.c — the shortenings a level build has met (shorten_memo.h, shorten.h):
 * over an octree of boxes, each child shortened from its parent's shortened tape as the
 * level build does, the number the memo gives for a tape and its pass's choices is the
 * number of the tape ism_tape_shorten makes afresh there (tapes numbered by their canonical
 * text, a second method), and the two-step shortening's range is the one-step one's bit for
 * bit; on solids with one and several min/max (keyed) and with more than the key holds, in
 * the three placements of the box. */
#include <criterion/criterion.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "core/eval/shorten.h"
#include "core/expr/tape.h"
#include "core/octree/shorten_memo.h"
#include "poly_fixture.h"

#define MAX_TAPES 4096
#define TEXT 16384
#define LEVELS 5 /* boxes of the octree's levels 0..4 */

/* The distinct tapes met, numbered from 1 by content (0: f); what the memo is checked by. */
typedef struct table {
    const ism_tape *f;
    ism_tape *t[MAX_TAPES];
    char *text[MAX_TAPES];
    size_t n;
} table;

static const ism_tape *tape_at(const table *tb, uint32_t id)
{
    return id ? tb->t[id - 1] : tb->f;
}

/* The number of the tape in *s by its canonical text (taking *s into the table when new:
 * *s is then a fresh tape). */
static uint32_t number_of(table *tb, ism_tape **s)
{
    char *text = malloc(TEXT);
    cr_assert_not_null(text);
    cr_assert_lt(ism_tape_canonical(*s, text, TEXT), (size_t)TEXT);
    for (size_t i = 0; i < tb->n; i++)
        if (strcmp(tb->text[i], text) == 0) {
            free(text);
            return (uint32_t)i + 1;
        }
    cr_assert_lt(tb->n, (size_t)MAX_TAPES);
    tb->t[tb->n] = *s;
    tb->text[tb->n++] = text;
    *s = ism_tape_new_like(tb->f);
    cr_assert_not_null(*s);
    return (uint32_t)tb->n;
}

typedef struct walk {
    table tb;
    ism_shorten_memo memo;
    ism_eval_ws *ws;
    ism_tape *fresh, *twostep; /* scratch tapes */
    bool f_keyed; /* f has at most ISM_SHORTEN_MEMO_MAX_KINKS min/max */
    size_t boxes, hits, shortened;
} walk;

/* Box (lo, hi) below a node on tape number id: the memo's number against the fresh one,
 * then its 8 octants on the fresh tape, down to LEVELS. */
static void visit(walk *w, const double lo[3], const double hi[3], uint32_t id, int level)
{
    const ism_tape *t = tape_at(&w->tb, id);
    ism_interval x = {lo[0], hi[0]}, y = {lo[1], hi[1]}, z = {lo[2], hi[2]}, r1, r2;
    bool shorter = ism_tape_shorten(t, w->ws, x, y, z, w->fresh, &r1);
    uint32_t fresh = shorter ? number_of(&w->tb, &w->fresh) : id;
    w->shortened += shorter;
    w->boxes++;
    cr_assert(ism_tape_shorten_pass(t, w->ws, x, y, z, &r2));
    cr_assert(r1.lo == r2.lo && r1.hi == r2.hi, "the pass's range differs from the shortening's");
    uint64_t key;
    uint32_t got;
    enum ism_shorten_memo_found met =
        ism_shorten_memo_get(&w->memo, id, t, ism_tape_shorten_choices(w->ws), &key, &got);
    bool keyed = met != ISM_SHORTEN_MEMO_UNKEYED;
    if (id == 0)
        cr_assert_eq(keyed, w->f_keyed, "f keyed: %d, expected %d", keyed, w->f_keyed);
    if (met == ISM_SHORTEN_MEMO_HIT) {
        w->hits++;
        cr_assert_eq(got, fresh, "level %d, below tape %u: the memo gives tape %u, shortening "
                     "afresh tape %u", level, id, got, fresh);
    } else {
        bool two = ism_tape_shorten_recorded(t, w->ws, w->twostep);
        cr_assert_eq(two, shorter, "the two steps shorten where the one does not, or back");
        uint32_t made = two ? number_of(&w->tb, &w->twostep) : id;
        cr_assert_eq(made, fresh, "the two steps give tape %u, the one tape %u", made, fresh);
        if (keyed)
            cr_assert(ism_shorten_memo_add(&w->memo, id, key, made));
    }
    if (level + 1 >= LEVELS)
        return;
    for (int k = 0; k < 8; k++) {
        double clo[3], chi[3];
        for (int a = 0; a < 3; a++) {
            double mid = 0.5 * (lo[a] + hi[a]);
            clo[a] = (k >> a & 1) ? mid : lo[a];
            chi[a] = (k >> a & 1) ? hi[a] : mid;
        }
        visit(w, clo, chi, fresh, level + 1);
    }
}

/* min of n balls on a line along x, overlapping their neighbours. */
static void balls(char *out, size_t cap, int n)
{
    size_t len = (size_t)snprintf(out, cap, "min(");
    for (int i = 0; i < n; i++)
        len += (size_t)snprintf(out + len, cap - len, "%s(x - %.4f)^2 + (y - %.4f)^2 + z^2 - %.4f",
                                i ? ", " : "", -1.4 + 2.8 * i / (n - 1), 0.3 * (i % 3 - 1),
                                0.05 + 0.01 * (i % 5));
    cr_assert_lt(len + 2, cap);
    snprintf(out + len, cap - len, ")");
}

/* The whole walk of expression e in placement which; its hits and the shortenings. */
static void run(const char *e, int which, size_t min_hits, bool f_keyed)
{
    static const double base[6] = {-1.6, -1.6, -1.6, 1.6, 1.6, 1.6};
    double box[6];
    pf_sweep_box(base, LEVELS + 2, which, box);
    ism_error err;
    ism_tape *f = ism_tape_compile(e, NULL, 0, NULL, 0, NULL, &err);
    cr_assert_not_null(f, "%s", err.message);
    walk *w = calloc(1, sizeof *w);
    cr_assert_not_null(w);
    w->tb.f = f;
    w->f_keyed = f_keyed;
    w->ws = ism_eval_ws_new(f);
    w->fresh = ism_tape_new_like(f);
    w->twostep = ism_tape_new_like(f);
    cr_assert(w->ws && w->fresh && w->twostep);
    visit(w, box, box + 3, 0, 0);
    cr_expect_gt(w->shortened, w->boxes / 10, "%s: %zu of %zu boxes shortened", e,
                 w->shortened, w->boxes);
    cr_expect_geq(w->hits, min_hits, "%s (placement %d): %zu hits of %zu boxes", e, which,
                  w->hits, w->boxes);
    for (size_t i = 0; i < w->tb.n; i++) {
        ism_tape_free(w->tb.t[i]);
        free(w->tb.text[i]);
    }
    ism_shorten_memo_free(&w->memo);
    ism_tape_free(w->fresh);
    ism_tape_free(w->twostep);
    ism_eval_ws_free(w->ws);
    free(w);
    ism_tape_free(f);
}

/* Barth's sextic as the bench meshes it (one max), a solid of several min/max (and an abs,
 * whose choice is no part of the key), and a union of 40 balls: 39 min, past the key (its
 * shortened tapes, of fewer balls, are keyed). */
Test(shorten_memo, memo_names_the_fresh_shortening, .timeout = 240)
{
    static char many[8192];
    balls(many, sizeof many, 40);
    const char *keyed[] = {
        "max(4*(2.618034*x^2 - y^2)*(2.618034*y^2 - z^2)*(2.618034*z^2 - x^2) - "
        "4.236068*(x^2 + y^2 + z^2 - 1)^2, x^2 + y^2 + z^2 - 2.4)",
        "max(min(x^2 + y^2 - 0.3, (x - 0.8)^2 + z^2 - 0.2), -(x^2 + y^2 + z^2 - 1.5), "
        "abs(z) - 0.9, min(y - 0.2, x*x - 0.1))",
    };
    for (int which = -1; which <= 1; which++) {
        for (size_t i = 0; i < sizeof keyed / sizeof keyed[0]; i++)
            run(keyed[i], which, 1000, true);
        run(many, which, 1000, false);
    }
}

/* f of n balls (n - 1 min), its min/max counted. */
static ism_tape *balls_tape(int n, char *text, size_t cap)
{
    balls(text, cap, n);
    ism_error err;
    ism_tape *f = ism_tape_compile(text, NULL, 0, NULL, 0, NULL, &err);
    cr_assert_not_null(f, "%s", err.message);
    size_t k = 0;
    for (size_t i = 0; i < f->len; i++)
        k += ism_op_is_min_max(f->code[i].op);
    cr_assert_eq(k, (size_t)n - 1, "%d balls: %zu min/max", n, k);
    return f;
}

/* The key's limit, ISM_SHORTEN_MEMO_MAX_KINKS = 32 (two bits each in 64): a union of 33
 * balls (32 min) is keyed, its memo's numbers those of the fresh shortenings, with hits; one
 * of 34 balls (33 min) is not, in the three placements. */
Test(shorten_memo, the_key_holds_32_min_max_not_33, .timeout = 240)
{
    cr_assert_eq(ISM_SHORTEN_MEMO_MAX_KINKS, 32);
    static char text[8192];
    for (int n = 33; n <= 34; n++)
        ism_tape_free(balls_tape(n, text, sizeof text));
    for (int which = -1; which <= 1; which++) {
        balls(text, sizeof text, 33);
        run(text, which, 1, true);
        balls(text, sizeof text, 34);
        run(text, which, 0, false);
    }
}

/* Every one of a 32-min tape's min/max is in its key, the last (bits 62, 63) and the first
 * alike: choices that differ at one of them alone, each of 1 and 2 against 0 and each other,
 * are not the key met (a key of fewer min/max, or one that folds two choices, would give
 * the number met for another shortening). */
Test(shorten_memo, each_min_max_is_in_the_key)
{
    static char text[8192];
    ism_tape *f = balls_tape(33, text, sizeof text);
    size_t first = f->len, last = 0;
    for (size_t i = 0; i < f->len; i++)
        if (ism_op_is_min_max(f->code[i].op)) {
            first = i < first ? i : first;
            last = i;
        }
    uint8_t *choice = calloc(f->len, 1);
    cr_assert_not_null(choice);
    size_t at[2] = {first, last};
    for (int p = 0; p < 2; p++)
        for (uint8_t was = 0; was < 3; was++)
            for (uint8_t now = 0; now < 3; now++) {
                if (was == now)
                    continue;
                ism_shorten_memo m = {0};
                uint64_t key, key2;
                uint32_t to = 0;
                choice[at[p]] = was;
                cr_assert_eq(ism_shorten_memo_get(&m, 0, f, choice, &key, &to),
                             ISM_SHORTEN_MEMO_MISS);
                cr_assert(ism_shorten_memo_add(&m, 0, key, 7));
                cr_assert_eq(ism_shorten_memo_get(&m, 0, f, choice, &key2, &to),
                             ISM_SHORTEN_MEMO_HIT);
                cr_assert_eq(to, 7u);
                choice[at[p]] = now;
                cr_assert_eq(ism_shorten_memo_get(&m, 0, f, choice, &key2, &to),
                             ISM_SHORTEN_MEMO_MISS, "min/max %zu: choice %u met as %u", at[p],
                             now, was);
                choice[at[p]] = 0;
                ism_shorten_memo_free(&m);
            }
    free(choice);
    ism_tape_free(f);
}

/* A number is one tape: asking the memo with another tape (here of another length) under a
 * number it has learnt is a caller's bug, caught by the assert. */
Test(shorten_memo, another_tape_under_a_number_aborts, .signal = SIGABRT)
{
    static char text[8192];
    ism_tape *a = balls_tape(3, text, sizeof text), *b = balls_tape(4, text, sizeof text);
    uint8_t choice[256] = {0};
    cr_assert_lt(b->len, sizeof choice);
    ism_shorten_memo m = {0};
    uint64_t key;
    uint32_t to;
    cr_assert_eq(ism_shorten_memo_get(&m, 0, a, choice, &key, &to), ISM_SHORTEN_MEMO_MISS);
    ism_shorten_memo_get(&m, 0, b, choice, &key, &to); /* aborts */
}
