/* test_conform_grid.c — the conformance pass's triangle grid (conform_grid.c): what a query
 * gathers is every triangle whose box meets the query's, against a brute-force scan of the
 * mesh, while the grid files the polygoniser's triangles lazily, one pass per widening of the
 * covered box; and a locus met one small query at a time, each a widening, costs passes
 * logarithmic in the spread (the growth from CF_COVER_PLAIN_PASSES passes on), not one each. */
#include <criterion/criterion.h>
#include <math.h>
#include <stdlib.h>

#include "core/singular/conform_internal.h"
#include "poly_fixture.h"

static int cmp_u32(const void *a, const void *b)
{
    uint32_t x = *(const uint32_t *)a, y = *(const uint32_t *)b;
    return (x > y) - (x < y);
}

/* The triangles of m whose bounding box meets [lo, hi], in order, into out. */
static size_t brute_gather(const ism_mesh *m, const double lo[3], const double hi[3],
                           uint32_t *out)
{
    size_t n = 0;
    for (size_t t = 0; t < m->ntris; t++) {
        bool meets = true;
        for (int k = 0; k < 3 && meets; k++) {
            double a = INFINITY, b = -INFINITY;
            for (int c = 0; c < 3; c++) {
                double x = m->pos[3 * (size_t)m->tri[3 * t + c] + k];
                a = fmin(a, x);
                b = fmax(b, x);
            }
            meets = a <= hi[k] && b >= lo[k];
        }
        if (meets)
            out[n++] = (uint32_t)t;
    }
    return n;
}

/* Queries walking once round a wavy line on the unit sphere, each a box of half side H:
 * NQ of them, each beyond the ones before along the walk's first three quarters, so without
 * the growth most would be a pass of their own. */
#define NQ 120
#define H 0.05

static void query_box(int i, double lo[3], double hi[3])
{
    double a = 2.0 * M_PI * (i + 0.5) / NQ, z = 0.2 * sin(3.0 * a), r = sqrt(1.0 - z * z);
    double c[3] = { r * cos(a), r * sin(a), z };
    for (int k = 0; k < 3; k++) {
        lo[k] = c[k] - H;
        hi[k] = c[k] + H;
    }
}

static bool inside(const double lo[3], const double hi[3], const double box[6])
{
    for (int k = 0; k < 3; k++)
        if (lo[k] < box[k] || hi[k] > box[k + 3])
            return false;
    return true;
}

/* A bound on the passes, from the growth alone. Write M_p for the covered box's largest side
 * after pass p, g for CF_COVER_GROWTH, P for CF_COVER_PLAIN_PASSES. A pass p > P grows the
 * query by at least g·M_{p−1} on every side, so every side after it is at least 2g·M_{p−1},
 * and the side the next pass is for (its query reaches past the box there) gains more than
 * g·M_p: M_{p+1} ≥ 3g·M_{p−1}. After such a pass with g·M_{p−1} ≥ R (the largest side of the
 * box holding every query) the box holds them all. So with q the first query's side (M_P ≥
 * q), passes ≤ P + 2 + 2⌈log_{3g}(R / (g·q))⌉. */
static double pass_bound(double R, double q)
{
    double g = CF_COVER_GROWTH;
    cr_assert_gt(3.0 * g, 1.0, "the bound needs a growth factor above 1");
    return CF_COVER_PLAIN_PASSES + 2 + 2 * ceil(log(R / (g * q)) / log(3.0 * g));
}

Test(conform_grid, gathers_every_meeting_triangle_in_few_passes)
{
    pf_surface s = { "x^2 + y^2 + z^2 - 1", NULL, 0, NULL, 0 };
    ism_tape *t = pf_compile(&s);
    const double base[6] = { -1.5, -1.5, -1.5, 1.5, 1.5, 1.5 };
    int d = 6 - pf_quick();
    for (int which = -1; which <= 1; which++) {
        double box[6];
        ism_mesh m;
        pf_props p;
        pf_run_placed(t, base, d, which, box, &m, &p);
        cr_assert_gt(m.ntris, 1000);
        cf_tgrid g;
        cr_assert(cf_tgrid_init(&g, box, box[3] - box[0], pf_cell(box, d), m.ntris));
        g.threads = 1;
        uint8_t *dead = calloc(m.ntris, 1);
        uint32_t *want = malloc(m.ntris * sizeof *want);
        cr_assert(dead && want);
        cf_tris got = { 0 };
        /* the box holding every query so far: the covered box without the growth */
        double all[6] = { INFINITY, INFINITY, INFINITY, -INFINITY, -INFINITY, -INFINITY };
        size_t widenings = 0;
        for (int i = 0; i < NQ; i++) {
            double lo[3], hi[3];
            query_box(i, lo, hi);
            widenings += !inside(lo, hi, all);
            for (int k = 0; k < 3; k++) {
                all[k] = fmin(all[k], lo[k]);
                all[k + 3] = fmax(all[k + 3], hi[k]);
            }
            got.n = 0;
            cf_tgrid_begin(&g);
            cr_assert(cf_tgrid_gather(&g, &m, lo, hi, dead, &got));
            size_t n = brute_gather(&m, lo, hi, want);
            cr_assert_gt(n, 0, "query %d meets the sphere", i);
            qsort(got.t, got.n, sizeof *got.t, cmp_u32);
            cr_assert_eq(got.n, n, "box %d, query %d: %zu gathered, %zu meet it", which, i,
                         got.n, n);
            for (size_t j = 0; j < n; j++)
                cr_assert_eq(got.t[j], want[j], "box %d, query %d: triangle %zu", which, i, j);
        }
        double R = 0;
        for (int k = 0; k < 3; k++)
            R = fmax(R, all[k + 3] - all[k]);
        double bound = pass_bound(R, 2 * H);
        /* the walk widens the plain box far more often than the bound: the test can fail */
        cr_assert_gt((double)widenings, bound + CF_COVER_PLAIN_PASSES, "%zu widenings", widenings);
        cr_log_info("box %d: passes %zu widenings %zu bound %g", which, g.cover_passes, widenings, bound);
        cr_expect_leq((double)g.cover_passes, bound, "box %d: %zu passes for %zu widenings",
                      which, g.cover_passes, widenings);
        cr_expect_gt(g.cover_passes, CF_COVER_PLAIN_PASSES + 3,
                     "box %d: at least 4 queries grew the box (%zu passes)", which,
                     g.cover_passes);
        free(got.t);
        free(want);
        free(dead);
        cf_tgrid_free(&g);
        ism_mesh_free(&m);
    }
    ism_tape_free(t);
}
