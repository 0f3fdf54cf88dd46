/* test_conform_rim.c — the conformance pass's rim clearance check (cf_rim_clear,
 * core/singular/conform_hole.c) on two parallel planes, f = z (z − h): a rim vertex on z = 0
 * has the other sheet h away along its normal, so it is clear exactly when the clearance is
 * below h. Its samples are evaluated in batches, the last one after the loops: a rim whose
 * last loop is empty (no vertices) must still check the samples of the loops before it. */
#include <criterion/criterion.h>
#include <math.h>
#include <string.h>

#include "core/expr/expr.h"
#include "core/singular/conform_internal.h"
#include "tests/unit/placements.h"

#define H 0.5

static bool rim_clear(const uint32_t *const *loops, const size_t *len, size_t nloops,
                      const double (*pos)[3], size_t nverts, double clearance)
{
    ism_error err;
    ism_tape *t = ism_tape_compile("z*(z - 0.5)", NULL, 0, NULL, 0, NULL, &err);
    cr_assert_not_null(t, "%s", err.message);
    ism_eval_ws *ws = ism_eval_ws_new(t);
    cr_assert_not_null(ws);
    ism_mesh m;
    ism_mesh_init(&m);
    for (size_t i = 0; i < nverts; i++)
        cr_assert_neq(ism_mesh_add_vertex(&m, pos[i], NULL), UINT32_MAX);
    ism_conform_stats st;
    memset(&st, 0, sizeof st);
    cf_ctx c;
    memset(&c, 0, sizeof c);
    c.f = t;
    c.ws = ws;
    c.m = &m;
    c.st = &st;
    cf_loop l[4];
    cr_assert(nloops <= 4);
    for (size_t i = 0; i < nloops; i++)
        l[i] = (cf_loop){.v = (uint32_t *)loops[i], .n = len[i], .closed = true};
    cf_loops ls = {.l = l, .n = nloops, .cap = nloops};
    bool clear = cf_rim_clear(&c, &ls, clearance);
    cr_assert(!c.stopped);
    ism_mesh_free(&m);
    ism_eval_ws_free(ws);
    ism_tape_free(t);
    return clear;
}

/* Vertices on z = 0 (one of them in each box shift: on the lattice, by 1e-3, and by an
 * irrational fraction, PF_IRR / 64: tests/unit/placements.h). */
Test(conform_rim, other_sheet_within_clearance)
{
    const double shifts[] = {0, 1e-3, PF_IRR / 64};
    for (int s = 0; s < 3; s++) {
        double o = shifts[s];
        const double pos[3][3] = {{o, o, 0}, {1 + o, o, 0}, {o, 1 + o, 0}};
        const uint32_t a[] = {0, 1, 2};
        const uint32_t *one[] = {a};
        size_t n3 = 3;
        /* one loop: clear below h, not clear beyond it */
        cr_expect(rim_clear(one, &n3, 1, pos, 3, 0.5 * H), "shift %d", s);
        cr_expect(!rim_clear(one, &n3, 1, pos, 3, 2 * H), "shift %d", s);
        /* a last loop with no vertices after it: the first loop's samples are still checked */
        const uint32_t *two[] = {a, a};
        const size_t len2[] = {3, 0};
        cr_expect(rim_clear(two, len2, 2, pos, 3, 0.5 * H), "shift %d", s);
        cr_expect(!rim_clear(two, len2, 2, pos, 3, 2 * H), "shift %d: empty last loop", s);
        /* enough vertices to fill whole batches (ISM_EVAL_BATCH / 16 each) and one more */
        enum { NV = 2 * ISM_EVAL_BATCH / 16 + 1 };
        uint32_t many[NV];
        for (int i = 0; i < NV; i++)
            many[i] = (uint32_t)(i % 3);
        const uint32_t *big[] = {many, a};
        const size_t lenb[] = {NV, 0};
        cr_expect(rim_clear(big, lenb, 2, pos, 3, 0.5 * H), "shift %d", s);
        cr_expect(!rim_clear(big, lenb, 2, pos, 3, 2 * H), "shift %d: batches", s);
    }
}
