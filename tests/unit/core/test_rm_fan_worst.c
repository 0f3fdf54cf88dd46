/* test_rm_fan_worst.c — rm_bound_fan_worst's batch (core/remesh/rm_bound.c: the fan's first
 * steps taken at once and kept in the memo, each point's slot peeked once and read while it
 * holds the point) against the one-point path it replaces (x, then each triangle's centroid
 * and midpoint measured in turn with rm_bound_distance, which claims its slot itself): the
 * same distance from every call, bit for bit, and — where no stop cuts a fan short — the
 * same memo afterwards, slot by slot. The memo is shared across calls, so the run meets each
 * collision the split must survive: two points of one fan in one slot, a batch point
 * evicting a point an earlier fan left, a measure evicting a later point's slot; the test
 * counts the first two and asserts it met them. On a polygonised ring torus (a tape of 10
 * instructions: over RM_FAN_BATCH_MIN_TAPE) in the box on the lattice and both shifted ones
 * (placements.h), each vertex measured where it is and moved along its fan. */
#include <criterion/criterion.h>
#include <math.h>
#include <string.h>

#include "core/expr/tape.h"
#include "core/remesh/rm_bound.h"
#include "core/remesh/rm_memo.h"
#include "core/remesh/rm_pass.h"
#include "tests/unit/core/poly_fixture.h"

static const double BOX[6] = {-1.5, -1.5, -1.5, 1.5, 1.5, 1.5};
#define DEPTH 5
/* The bound the distances are measured against: 1e-3 of the box, the quality pass's order. */
#define LIMIT 3e-3

static void open_pass(rm_pass *p, ism_mesh *m, const ism_tape *t)
{
    ism_remesh_options o = {.f = t, .max_error = LIMIT};
    cr_assert(rm_pass_open(p, m, &o, 0));
    p->bounded = true;
    p->memo = rm_memo_new();
    cr_assert_not_null(p->memo);
}

static void close_pass(rm_pass *p, ism_mesh *m)
{
    rm_memo_free(p->memo);
    p->memo = NULL;
    rm_pass_close(p, m->nverts, m->ntris, NULL);
}

/* rm_bound_fan_worst without a batch: each point measured as it comes. */
static double one_by_one(rm_pass *p, uint32_t v, const double *x, double limit, double stop)
{
    double worst = rm_bound_distance(p, x, limit);
    for (uint32_t i = 0; i < p->r.count[v] && worst <= stop; i++) {
        uint32_t t;
        int k;
        double g[3], m[3];
        rm_fan_point(p, v, i, x, &t, &k, g, m);
        double dg = rm_bound_distance(p, g, limit);
        worst = dg > worst ? dg : worst;
        if (worst <= stop) {
            double dm = rm_bound_distance(p, m, limit);
            worst = dm > worst ? dm : worst;
        }
    }
    return worst;
}

/* Counts, before a call at v with v at x: pairs of the fan's points in one slot, and points
 * whose slot holds another point. */
static void count_collisions(const rm_pass *p, uint32_t v, const double *x, size_t *pairs,
                             size_t *held)
{
    double q[64][3];
    size_t n = 1;
    memcpy(q[0], x, sizeof q[0]);
    for (uint32_t i = 0; i < p->r.count[v] && n + 2 <= 64; i++, n += 2) {
        uint32_t t;
        int k;
        rm_fan_point(p, v, i, x, &t, &k, q[n], q[n + 1]);
    }
    for (size_t j = 0; j < n; j++) {
        rm_memo_entry *e = rm_memo_peek(p->memo, q[j]);
        if (e->state != RM_MEMO_EMPTY && !rm_memo_holds(e, q[j]))
            (*held)++;
        for (size_t i = 0; i < j; i++)
            if (rm_memo_peek(p->memo, q[i]) == e && memcmp(q[i], q[j], sizeof q[j]) != 0)
                (*pairs)++;
    }
}

/* The two memos slot by slot: the same state, point and what the state says is known. */
static void same_memo(const rm_memo *a, const rm_memo *b, const char *what)
{
    cr_assert_eq(a->bits, b->bits);
    for (size_t i = 0; i < (size_t)1 << a->bits; i++) {
        const rm_memo_entry *x = &a->e[i], *y = &b->e[i];
        cr_assert_eq(x->state, y->state, "%s: slot %zu: state %u vs %u", what, i, x->state,
                     y->state);
        if (x->state == RM_MEMO_EMPTY)
            continue;
        bool ok = memcmp(x->x, y->x, sizeof x->x) == 0;
        if (x->state != RM_MEMO_FAIL1)
            ok = ok && memcmp(&x->s1, &y->s1, sizeof x->s1) == 0 &&
                 memcmp(x->g, y->g, sizeof x->g) == 0 && memcmp(x->y, y->y, sizeof x->y) == 0;
        if (x->state == RM_MEMO_S2)
            ok = ok && memcmp(&x->s2, &y->s2, sizeof x->s2) == 0;
        cr_assert(ok, "%s: slot %zu holds another point or other measures", what, i);
    }
}

Test(rm_fan_worst, the_batch_measures_and_keeps_what_one_by_one_does)
{
    ism_tape *t = pf_compile(&pf_ring_torus);
    cr_assert_geq(t->len, 7, "the torus's tape must take the batch");
    size_t pairs = 0, held = 0, calls = 0;
    for (int which = pf_first_box() - 1; which < 2; which++) {
        double box[6];
        ism_mesh ma, mb;
        ism_poly_stats st;
        pf_sweep_box(BOX, DEPTH, which, box);
        pf_run(t, box, 3, DEPTH, 1, &ma, &st);
        pf_run(t, box, 3, DEPTH, 1, &mb, &st);
        rm_pass a, b;
        open_pass(&a, &ma, t);
        open_pass(&b, &mb, t);
        /* three sweeps: no stop (the memos must then agree), a stop at LIMIT, none again */
        for (int sweep = 0; sweep < 3; sweep++) {
            double stop = sweep == 1 ? LIMIT : INFINITY;
            for (uint32_t v = 0; v < ma.nverts; v++) {
                if (!a.r.count[v])
                    continue;
                /* v where it is, then moved a third of the way to its first triangle's
                   centroid (a relaxation's trial: points no fan has met) */
                double x[2][3], g[3], m[3];
                uint32_t tt;
                int k;
                memcpy(x[0], ma.pos + 3 * (size_t)v, sizeof x[0]);
                rm_fan_point(&a, v, 0, x[0], &tt, &k, g, m);
                for (int c = 0; c < 3; c++)
                    x[1][c] = x[0][c] + (g[c] - x[0][c]) / 3;
                for (int w = 0; w < 2; w++) {
                    count_collisions(&a, v, x[w], &pairs, &held);
                    double da = rm_bound_fan_worst(&a, v, x[w], LIMIT, stop);
                    double db = one_by_one(&b, v, x[w], LIMIT, stop);
                    cr_assert(memcmp(&da, &db, sizeof da) == 0,
                              "box %d sweep %d vertex %u move %d: batch %.17g, one by one %.17g",
                              which, sweep, v, w, da, db);
                    calls++;
                }
            }
            if (sweep != 1)
                same_memo(a.memo, b.memo, "after a sweep without stops");
            else /* the stops leave the batch's later claims: start both afresh */
                for (rm_pass *p = &a; p; p = p == &a ? &b : NULL) {
                    rm_memo_free(p->memo);
                    p->memo = rm_memo_new();
                    cr_assert_not_null(p->memo);
                }
        }
        close_pass(&a, &ma);
        close_pass(&b, &mb);
        ism_mesh_free(&ma);
        ism_mesh_free(&mb);
    }
    cr_log_info("%zu calls, %zu pairs of a fan's points in one slot, %zu points whose slot "
                "held another", calls, pairs, held);
    cr_expect_gt(pairs, 0, "no two points of a fan shared a slot: the test misses that path");
    cr_expect_gt(held, 0, "no batch point evicted a held one: the test misses that path");
    ism_tape_free(t);
}
