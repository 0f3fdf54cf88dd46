/* test_rm_distances.c — rm_bound_distances (core/remesh/rm_bound.c: a list of points'
 * first steps in one batch, then the second steps they need in another, no memo) against
 * rm_distance one point at a time, which the found mesh's farthest centroid and midpoint
 * (rm_collapse.c) measured before: the same distance for every point bit for bit, under an
 * error bound (two Newton steps, the second only past half the bound) and without one
 * (|f|/|∇f|, with |∇f| as rm_cbound_distance gives it). The points are a polygonised ring
 * torus's centroids and edge midpoints, each also pushed off the surface by 0.3, 0.8 and 3
 * bounds along its triangle's normal (one step, two steps, beyond the bound), the origin
 * (∇f vanishes) and a point where f overflows; lists of every length from 1 to past two
 * chunks. Each finite measure is also the torus's closed-form distance to second order (the
 * shared step formulas checked against geometry, not against themselves). With a memo
 * filled and then spoiled, the batch gives the memo-less figures and leaves the table as it
 * was. In the box on the lattice and both shifted ones (placements.h); the test counts each
 * kind of measure and asserts it met them all. */
#include <criterion/criterion.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "core/expr/tape.h"
#include "core/remesh/rm_bound.h"
#include "core/remesh/rm_cbound.h"
#include "core/remesh/rm_memo.h"
#include "core/remesh/rm_pass.h"
#include "core/util/vec3.h"
#include "tests/unit/core/poly_fixture.h"

static const double BOX[6] = {-1.5, -1.5, -1.5, 1.5, 1.5, 1.5};
#define DEPTH 5
/* The bound: 1e-3 of the box, the quality pass's order. */
#define LIMIT 3e-3
/* Offsets off the surface, in bounds: within the one-step share, past it, past the bound. */
static const double PUSH[] = {0, 0.3, 0.8, 3};
#define NPUSH (sizeof PUSH / sizeof PUSH[0])

/* The points measured: every triangle's centroid and its first edge's midpoint, each pushed
 * along the triangle's normal by PUSH × LIMIT, then the origin and an overflowing point.
 * Returns how many (q has room for 2 NPUSH ntris + 2). */
static size_t points(const ism_mesh *m, double (*q)[3])
{
    size_t n = 0;
    for (size_t t = 0; t < m->ntris; t++) {
        const uint32_t *v = m->tri + 3 * t;
        const double *a = m->pos + 3 * (size_t)v[0], *b = m->pos + 3 * (size_t)v[1],
                     *c = m->pos + 3 * (size_t)v[2];
        double nrm[3], at[2][3];
        double len = sqrt(fmax(rm_cross(a, b, c, nrm), 1e-300));
        rm_centroid(a, b, c, at[0]);
        rm_midpoint(a, b, at[1]);
        for (int w = 0; w < 2; w++)
            for (size_t k = 0; k < NPUSH; k++, n++)
                for (int j = 0; j < 3; j++)
                    q[n][j] = at[w][j] + PUSH[k] * LIMIT * nrm[j] / len;
    }
    memset(q[n++], 0, sizeof q[0]);
    q[n][0] = 1e200, q[n][1] = 0, q[n][2] = 0;
    return n + 1;
}

static double worst_ratio; /* the largest |measure - distance| / distance² met, logged */

/* A finite measure at x is the distance d from x to the ring torus (closed form,
 * pf_ring_torus_dist) to second order. f = g h, g = s² - r² (s the distance to the core
 * circle), h = (ρ + R)² + z² - r² (the mirrored tube): a Newton step runs across the tube and
 * its length |f|/|∇f| misses d by (1 / (2r) + |∇h| / h) d² to second order, at most 2.9 d²
 * here (|∇h| / h <= 1.25, at the inner equator); the two-step sum can count that twice
 * (5.8 d²), and d stays under 4% of r, so third-order terms are small: 8 d² allowed. A
 * step's length wrong to first order (f/|∇f|², a missing square root) misses by a share of
 * d, some 100 times that at these d (~1e-2). */
static void check_true_distance(const double x[3], double measure)
{
    double d = pf_ring_torus_dist(x), err = fabs(measure - d);
    cr_assert(err <= 8 * d * d + 1e-15,
              "at (%.17g, %.17g, %.17g): measure %.17g, distance %.17g", x[0], x[1], x[2],
              measure, d);
    if (d > 1e-6) /* (nearer, rounding's 1e-15 is more than d²) */
        worst_ratio = fmax(worst_ratio, err / (d * d));
}

/* The torus polygonised in placement which (pf_sweep_box) into *m, and its points (points)
 * in a new array, how many into *n. */
static double (*torus_points(const ism_tape *t, int which, ism_mesh *m, size_t *n))[3]
{
    double box[6];
    ism_poly_stats st;
    pf_sweep_box(BOX, DEPTH, which, box);
    pf_run(t, box, 3, DEPTH, 1, m, &st);
    double (*q)[3] = malloc((2 * NPUSH * m->ntris + 2) * sizeof *q);
    cr_assert_not_null(q);
    *n = points(m, q);
    return q;
}

/* Every list q[0..len) for len = 1 .. 2 chunks and more, then the whole of q, measured
 * both ways and compared; one-step / two-step / infinite measures counted into kinds. */
static void compare(rm_pass *p, const double (*q)[3], size_t n, size_t kinds[3])
{
    double *d = malloc(n * sizeof *d), *gn = malloc(n * sizeof *gn);
    cr_assert(d && gn);
    for (size_t len = 1; len <= n; len = len < 130 ? len + 1 : (len == n ? n + 1 : n)) {
        size_t from = len < 130 ? (len * 37) % (n - len + 1) : 0;
        rm_bound_distances(p, q + from, len, d, gn);
        for (size_t i = 0; i < len; i++) {
            double one = rm_distance(p, q[from + i]), g = 0;
            if (!p->bounded) {
                double again = rm_cbound_distance(p, q[from + i], &g);
                cr_assert(memcmp(&again, &one, sizeof one) == 0);
            }
            cr_assert(memcmp(&d[i], &one, sizeof one) == 0,
                      "%s, point %zu of %zu: batch %.17g, one by one %.17g",
                      p->bounded ? "bounded" : "unbounded", from + i, len, d[i], one);
            cr_assert(memcmp(&gn[i], &g, sizeof g) == 0, "point %zu: |grad f| %.17g vs %.17g",
                      from + i, gn[i], g);
            if (len != n)
                continue;
            /* a measure within the one-step share of the bound is its first step alone */
            kinds[isinf(one) ? 2 : one <= RM_BOUND_ONE_STEP_SHARE * LIMIT ? 0 : 1]++;
            if (!isinf(one))
                check_true_distance(q[i], d[i]);
        }
    }
    free(d);
    free(gn);
}

Test(rm_distances, the_batch_measures_what_one_by_one_does)
{
    ism_tape *t = pf_compile(&pf_ring_torus);
    size_t kinds[2][3] = {{0}};
    for (int which = pf_first_box() - 1; which < 2; which++) {
        ism_mesh m;
        size_t n;
        double (*q)[3] = torus_points(t, which, &m, &n);
        cr_assert_gt(n, 130);
        for (int bounded = 0; bounded < 2; bounded++) {
            rm_pass p;
            ism_remesh_options o = {.f = t, .max_error = bounded ? LIMIT : 0};
            cr_assert(rm_pass_open(&p, &m, &o, 0));
            p.bounded = bounded; /* no memo: rm_distance measures afresh each time */
            compare(&p, (const double (*)[3])q, n, kinds[bounded]);
            rm_pass_close(&p, m.nverts, m.ntris, NULL);
        }
        free(q);
        ism_mesh_free(&m);
    }
    cr_log_info("bounded: %zu one step, %zu two, %zu infinite; unbounded: %zu finite, %zu "
                "infinite; worst |measure - distance| / distance^2 %.3g", kinds[1][0],
                kinds[1][1], kinds[1][2], kinds[0][0] + kinds[0][1], kinds[0][2], worst_ratio);
    for (int k = 0; k < 3; k++)
        cr_expect_gt(kinds[1][k], 0, "bounded: no measure of kind %d: a path is not met", k);
    cr_expect_gt(kinds[0][2], 0, "unbounded: no infinite measure");
    ism_tape_free(t);
}

/* With the pass's memo (the production pass has one: remesh.c), the batch neither reads it
 * nor writes it (rm_bound.h): the memo filled by rm_distance at every point and then its
 * figures spoiled (every kept step length doubled), the batch still gives the memo-less
 * figures bit for bit, and the table is byte for byte as it was. */
Test(rm_distances, the_batch_neither_reads_nor_writes_the_memo)
{
    ism_tape *t = pf_compile(&pf_ring_torus);
    for (int which = pf_first_box() - 1; which < 2; which++) {
        ism_mesh m;
        size_t n;
        double (*q)[3] = torus_points(t, which, &m, &n);
        double *fresh = malloc(n * sizeof *fresh), *d = malloc(n * sizeof *d);
        cr_assert(fresh && d);
        rm_pass p;
        ism_remesh_options o = {.f = t, .max_error = LIMIT};
        cr_assert(rm_pass_open(&p, &m, &o, 0));
        p.bounded = true;
        for (size_t i = 0; i < n; i++)
            fresh[i] = rm_distance(&p, q[i]); /* no memo yet */
        p.memo = rm_memo_new();
        cr_assert_not_null(p.memo);
        for (size_t i = 0; i < n; i++)
            rm_distance(&p, q[i]);
        size_t slots = (size_t)1 << p.memo->bits, spoiled = 0;
        for (size_t s = 0; s < slots; s++) {
            rm_memo_entry *e = &p.memo->e[s];
            if (e->state >= RM_MEMO_S1)
                e->s1 *= 2, e->s2 *= 2, spoiled++;
        }
        cr_assert_gt(spoiled, slots / 2, "the memo was hardly filled: %zu of %zu", spoiled,
                     slots);
        rm_memo_entry *was = malloc(slots * sizeof *was);
        cr_assert_not_null(was);
        memcpy(was, p.memo->e, slots * sizeof *was);
        rm_bound_distances(&p, (const double (*)[3])q, n, d, NULL);
        for (size_t i = 0; i < n; i++)
            cr_assert(memcmp(&d[i], &fresh[i], sizeof d[i]) == 0,
                      "point %zu: batch %.17g with the memo, %.17g without", i, d[i], fresh[i]);
        cr_assert(memcmp(was, p.memo->e, slots * sizeof *was) == 0, "the batch wrote the memo");
        free(was);
        rm_memo_free(p.memo);
        p.memo = NULL;
        rm_pass_close(&p, m.nverts, m.ntris, NULL);
        free(fresh);
        free(d);
        free(q);
        ism_mesh_free(&m);
    }
    ism_tape_free(t);
}
