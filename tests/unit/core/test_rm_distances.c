/* test_rm_distances.c — rm_bound_distances (core/remesh/rm_bound.c: a list of points'
 * first steps in one batch, then the second steps they need in another, no memo) against
 * rm_distance one point at a time, which the found mesh's farthest centroid and midpoint
 * (rm_collapse.c) measured before: the same distance for every point bit for bit, under an
 * error bound (two Newton steps, the second only past half the bound) and without one
 * (|f|/|∇f|, with |∇f| as rm_cbound_distance gives it). The points are a polygonised ring
 * torus's centroids and edge midpoints, each also pushed off the surface by 0.3, 0.8 and 3
 * bounds along its triangle's normal (one step, two steps, beyond the bound), the origin
 * (∇f vanishes) and a point where f overflows; lists of every length from 1 to past two
 * chunks. In the box on the lattice and both shifted ones (placements.h); the test counts
 * each kind of measure and asserts it met them all. */
#include <criterion/criterion.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "core/expr/tape.h"
#include "core/remesh/rm_bound.h"
#include "core/remesh/rm_cbound.h"
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
            if (len == n) /* a measure within half the bound is its first step alone */
                kinds[isinf(one) ? 2 : one <= 0.5 * LIMIT ? 0 : 1]++;
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
        double box[6];
        ism_mesh m;
        ism_poly_stats st;
        pf_sweep_box(BOX, DEPTH, which, box);
        pf_run(t, box, 3, DEPTH, 1, &m, &st);
        double (*q)[3] = malloc((2 * NPUSH * m.ntris + 2) * sizeof *q);
        cr_assert_not_null(q);
        size_t n = points(&m, q);
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
                "infinite", kinds[1][0], kinds[1][1], kinds[1][2], kinds[0][0] + kinds[0][1],
                kinds[0][2]);
    for (int k = 0; k < 3; k++)
        cr_expect_gt(kinds[1][k], 0, "bounded: no measure of kind %d: a path is not met", k);
    cr_expect_gt(kinds[0][2], 0, "unbounded: no infinite measure");
    ism_tape_free(t);
}
