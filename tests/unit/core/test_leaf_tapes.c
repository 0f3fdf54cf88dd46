/* test_leaf_tapes.c — the table of the leaves' shortened tapes (leaf_tapes.h, octree.h):
 * unions of 64 and of 200 balls, whose leaves shorten f to hundreds of distinct tapes (past
 * the 63 the table once held), give bit for bit the mesh of the path where every leaf
 * evaluates f itself (full_tape), on 1, 2 and 4 threads, with every such leaf on a short
 * tape; under an error bound, leaves whose short tape decides f's top min/max skip the
 * crease split (fewer evaluations, the same mesh); and the table itself: one number per
 * distinct tape whichever thread asks first, and 0 past its limit. */
#include <criterion/criterion.h>
#include <pthread.h>
#include <stdio.h>
#include <string.h>
#include "core/expr/tape.h"
#include "core/octree/leaf_tapes.h"
#include "poly_fixture.h"

#define SHIFT_CELLS PF_IRR
#define EXPR_MAX (1 << 15)

/* min of n balls on a jittered grid of the cube [-0.8, 0.8]^3 (LCG from seed 2024), radii
 * 0.55-0.85 of the grid's spacing: neighbours overlap, so a leaf shortens f to the few
 * balls that reach it — different few from leaf to leaf. */
static ism_tape *union_of_balls(int n)
{
    static char expr[EXPR_MAX];
    unsigned long long s = 2024;
    int k = 1;
    while (k * k * k < n)
        k++;
    size_t len = (size_t)snprintf(expr, sizeof expr, "min(");
    for (int i = 0; i < n; i++) {
        int g[3] = {i % k, i / k % k, i / (k * k)};
        double c[3], u;
        for (int a = 0; a < 4; a++) {
            s = s * 6364136223846793005ull + 1442695040888963407ull;
            u = (double)(s >> 11) * 0x1p-53;
            if (a < 3)
                c[a] = -0.8 + 1.6 * (g[a] + 0.5) / k + (u - 0.5) * 0.8 / k;
        }
        double r = (0.55 + 0.3 * u) * 1.6 / k;
        len += (size_t)snprintf(expr + len, sizeof expr - len,
                                "%s(x-%.6f)^2+(y-%.6f)^2+(z-%.6f)^2-%.6f", i ? ", " : "",
                                c[0], c[1], c[2], r * r);
        cr_assert_lt(len, sizeof expr - 2);
    }
    snprintf(expr + len, sizeof expr - len, ")");
    ism_error err;
    ism_tape *t = ism_tape_compile(expr, NULL, 0, NULL, 0, NULL, &err);
    cr_assert_not_null(t, "%s", err.message);
    return t;
}

static void mesh_of(const ism_tape *t, const double box[6], int dmax, double max_error,
                    int threads, bool full_tape, ism_mesh *m, ism_poly_stats *st)
{
    ism_poly_options o;
    pf_options(&o, box, 2, dmax);
    o.max_error = max_error;
    o.threads = threads;
    o.full_tape = full_tape;
    pf_run_options(t, &o, m, st);
}

/* The full-tape mesh on one thread against the short-tape one on 1, 2 and 4. */
static void check(int nballs, int dmax, double shift_cells)
{
    ism_tape *t = union_of_balls(nballs);
    double box[6] = {-1, -1, -1, 1, 1, 1};
    for (int k = 0; k < 6; k++)
        box[k] += shift_cells * 2.0 / (1 << dmax);
    ism_mesh ref, m;
    ism_poly_stats st;
    mesh_of(t, box, dmax, 0, 1, true, &ref, &st);
    cr_assert_gt(ref.ntris, 1000, "%d balls: %zu triangles", nballs, ref.ntris);
    cr_assert_eq(st.short_tape_leaves + st.leaf_tapes, 0, "full_tape: leaves on short tapes");
    const int threads[] = {1, 2, 4};
    for (size_t i = 0; i < sizeof threads / sizeof threads[0]; i++) {
        mesh_of(t, box, dmax, 0, threads[i], false, &m, &st);
        char what[96];
        snprintf(what, sizeof what, "%d balls, d%d, shift %g, %d threads", nballs, dmax,
                 shift_cells, threads[i]);
        pf_same_mesh(&ref, &m, what);
        /* far more distinct tapes than the old table's 63, every one kept */
        cr_expect_gt(st.leaf_tapes, 200, "%s: %llu tapes", what,
                     (unsigned long long)st.leaf_tapes);
        cr_expect_eq(st.tape_misses, 0, "%s: %llu leaves found no room", what,
                     (unsigned long long)st.tape_misses);
        /* all but the leaves no min/max is decided over (none here: the balls are small)
         * or that are zero-free evaluate a short tape */
        cr_expect_gt(st.short_tape_leaves, st.plotting_nodes * 9 / 10, "%s: %llu of %llu",
                     what, (unsigned long long)st.short_tape_leaves,
                     (unsigned long long)st.plotting_nodes);
        ism_mesh_free(&m);
    }
    ism_mesh_free(&ref);
    ism_tape_free(t);
}

Test(leaf_tapes, union_of_64_balls)
{
    check(64, 4 - pf_quick(), 0);
    if (!pf_quick())
        check(64, 3, SHIFT_CELLS);
}

Test(leaf_tapes, union_of_200_balls)
{
    check(200, 3, 0);
}

/* CSG surfaces under an error bound (the crease split runs): gyroid ∩ ball, whose leaves
 * away from the sphere have the top max decided, and a cube minus a ball. */
Test(leaf_tapes, crease_split_skipped_where_the_top_is_decided)
{
    static const struct {
        const char *expr;
        double k, half, max_error;
    } cases[] = {
        {"max(sin(k*x)*cos(k*y) + sin(k*y)*cos(k*z) + sin(k*z)*cos(k*x), x^2 + y^2 + z^2 - 1.96)",
         4, 1.5, 1e-2},
        {"max(max(abs(x), abs(y), abs(z)) - 1, k^2 - (x^2 + y^2 + z^2))", 1.2, 1.3, 3e-3},
    };
    int dmax = 7 - pf_quick();
    for (size_t c = 0; c < sizeof cases / sizeof cases[0]; c++) {
        ism_param k = {"k", cases[c].k};
        ism_error err;
        ism_tape *t = ism_tape_compile(cases[c].expr, &k, 1, NULL, 0, NULL, &err);
        cr_assert_not_null(t, "%s", err.message);
        for (int placed = pf_first_box(); placed < 3; placed += 2) { /* as given, PF_IRR off */
            double h = cases[c].half, shift = placed ? SHIFT_CELLS * 2 * h / (1 << dmax) : 0;
            double box[6] = {-h + shift, -h + shift, -h + shift, h + shift, h + shift, h + shift};
            ism_mesh ref, m;
            ism_poly_stats sref, st;
            mesh_of(t, box, dmax, cases[c].max_error, 1, true, &ref, &sref);
            mesh_of(t, box, dmax, cases[c].max_error, 1, false, &m, &st);
            char what[64];
            snprintf(what, sizeof what, "case %zu, shift %g", c, shift);
            pf_same_mesh(&ref, &m, what);
            cr_expect_gt(st.short_tape_leaves, 0, "%s: no short tapes", what);
            /* without the skip both label every vertex: as many point evaluations */
            cr_expect_lt(st.evals_point, sref.evals_point, "%s: %llu point evaluations, %llu "
                         "on f alone", what, (unsigned long long)st.evals_point,
                         (unsigned long long)sref.evals_point);
            ism_mesh_free(&ref);
            ism_mesh_free(&m);
        }
        ism_tape_free(t);
    }
}

/* A one-instruction tape out = c (distinct c: distinct tapes). */
static ism_tape *constant(double c)
{
    ism_tape *t = ism_tape_alloc(1, ISM_FIRST_FREE_REG + 1);
    cr_assert_not_null(t);
    t->code[0] = (ism_instr){.op = ISM_OP_CONST, .out = ISM_FIRST_FREE_REG, .imm = c};
    t->len = 1;
    t->result = ISM_FIRST_FREE_REG;
    t->origin_len = 1;
    return t;
}

#define SHARED_TAPES 3000
#define ASKERS 4

typedef struct asker {
    ism_leaf_tapes *lt;
    ism_tape **tapes;
    unsigned number[SHARED_TAPES];
    int stride;
} asker;

/* Numbers every tape, in an order of its own (stride coprime to SHARED_TAPES), twice. */
static void *ask(void *arg)
{
    asker *a = arg;
    ism_leaf_tapes_cache *cache = calloc(1, sizeof *cache);
    for (int round = 0; round < 2; round++)
        for (int i = 0; i < SHARED_TAPES; i++) {
            int k = (int)((long)i * a->stride % SHARED_TAPES);
            unsigned n = ism_leaf_tapes_number(a->lt, cache, a->tapes[k]);
            if (round == 0)
                a->number[k] = n;
            else if (n != a->number[k])
                a->number[k] = 0; /* a tape that changed number: caught below */
        }
    free(cache);
    return NULL;
}

Test(leaf_tapes, one_number_per_tape_across_threads)
{
    static ism_tape *tapes[SHARED_TAPES];
    for (int i = 0; i < SHARED_TAPES; i++)
        tapes[i] = constant(i);
    ism_leaf_tapes lt;
    cr_assert(ism_leaf_tapes_init(&lt, NULL));
    static asker askers[ASKERS];
    pthread_t th[ASKERS];
    const int strides[ASKERS] = {1, 7, 11, 2999};
    for (int k = 0; k < ASKERS; k++) {
        askers[k] = (asker){.lt = &lt, .tapes = tapes, .stride = strides[k]};
        cr_assert_eq(pthread_create(&th[k], NULL, ask, &askers[k]), 0);
    }
    for (int k = 0; k < ASKERS; k++)
        pthread_join(th[k], NULL);
    cr_assert_eq(lt.n, SHARED_TAPES, "%zu tapes kept for %d distinct", lt.n, SHARED_TAPES);
    static bool seen[SHARED_TAPES + 1];
    for (int i = 0; i < SHARED_TAPES; i++) {
        unsigned n = askers[0].number[i];
        cr_assert(n >= 1 && n <= SHARED_TAPES && !seen[n], "tape %d: number %u", i, n);
        seen[n] = true;
        for (int k = 1; k < ASKERS; k++)
            cr_assert_eq(askers[k].number[i], n, "tape %d: thread %d says %u, thread 0 %u", i,
                         k, askers[k].number[i], n);
        cr_assert_eq(lt.v[n - 1]->code[0].imm, (double)i, "tape %d kept as %g", i,
                     lt.v[n - 1]->code[0].imm);
    }
    ism_leaf_tapes_free(&lt);
    for (int i = 0; i < SHARED_TAPES; i++)
        ism_tape_free(tapes[i]);
}

Test(leaf_tapes, no_room_past_the_limit)
{
    ism_leaf_tapes lt;
    cr_assert(ism_leaf_tapes_init(&lt, NULL));
    ism_leaf_tapes_cache *cache = calloc(1, sizeof *cache);
    for (unsigned i = 0; i < ISM_OCTREE_TAPES; i++) {
        ism_tape *t = constant(i);
        cr_assert_eq(ism_leaf_tapes_number(&lt, cache, t), i + 1);
        ism_tape_free(t);
    }
    ism_tape *extra = constant(-1), *first = constant(0);
    cr_expect_eq(ism_leaf_tapes_number(&lt, cache, extra), 0, "a tape past the limit");
    cr_expect_eq(ism_leaf_tapes_number(&lt, cache, first), 1, "a known tape still found");
    ism_leaf_tapes_cache *other = calloc(1, sizeof *other); /* by the index, not a cache */
    cr_expect_eq(ism_leaf_tapes_number(&lt, other, first), 1, "a known tape, from the index");
    ism_tape_free(extra);
    ism_tape_free(first);
    free(cache);
    free(other);
    ism_leaf_tapes_free(&lt);
}
