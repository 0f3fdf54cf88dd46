/* test_quiet.c — the quiet-ball index (core/octree/quiet.h) against scans of every ball
 * written here: ism_quiet_holds (the box inside a ball) and ism_quiet_near (the box within
 * max(radius, reach) of a centre), for random boxes from far below a ball to the whole
 * region, and reaches from 0 to many grid cells. Two layouts: balls in a cube, and balls along
 * a line 3,000 grid cells long (the grid keeps 10 bits an axis: its cells wrap past 1,024,
 * and queries reach cells left of the origin, which wrap the other way). */
#include <criterion/criterion.h>
#include <math.h>
#include <stdlib.h>
#include "core/octree/quiet.h"

/* A deterministic generator (xorshift64*), uniform in [lo, hi). */
static double uniform(uint64_t *s, double lo, double hi)
{
    *s ^= *s >> 12;
    *s ^= *s << 25;
    *s ^= *s >> 27;
    return lo + (hi - lo) * (double)((*s * 0x2545F4914F6CDD1DULL) >> 11) / 9007199254740992.0;
}

/* Every ball tried: one holding the box (its farthest corner inside), or one whose centre
 * lies within max(radius, reach) of the box. */
static void scan(const double (*b)[4], size_t n, const double lo[3], const double hi[3],
                 double reach, bool *holds, bool *near)
{
    *holds = *near = false;
    for (size_t i = 0; i < n; i++) {
        double far = 0, d2 = 0, r = fmax(b[i][3], reach);
        for (int a = 0; a < 3; a++) {
            double f = fmax(fabs(lo[a] - b[i][a]), fabs(hi[a] - b[i][a]));
            double e = b[i][a] < lo[a] ? lo[a] - b[i][a] : b[i][a] > hi[a] ? b[i][a] - hi[a] : 0;
            far += f * f;
            d2 += e * e;
        }
        *holds |= far < b[i][3] * b[i][3];
        *near |= d2 < r * r;
    }
}

/* n balls of radii rmin..rmax with centres in lo..hi per axis; queries of boxes from 1e-3 to
 * 3 largest radii wide, half placed over the region grown by a tenth, half beside a ball's
 * centre; both answers of both queries must be seen. */
static void check_layout(size_t n, const double lo[3], const double hi[3], double rmin,
                         double rmax, uint64_t seed)
{
    enum { QUERIES = 4000 };
    double (*ball)[4] = malloc(n * sizeof *ball);
    cr_assert(ball);
    uint64_t s = seed;
    for (size_t i = 0; i < n; i++) {
        for (int a = 0; a < 3; a++)
            ball[i][a] = uniform(&s, lo[a], hi[a]);
        ball[i][3] = uniform(&s, rmin, rmax);
    }
    ism_quiet q;
    cr_assert(ism_quiet_init(&q, (const double (*)[4])ball, n));
    size_t held = 0, near = 0;
    for (size_t k = 0; k < QUERIES; k++) {
        double blo[3], bhi[3], side = rmax * exp(uniform(&s, log(1e-3), log(3)));
        double reach = k % 4 == 0 ? 0 : rmax * uniform(&s, 0, 6);
        /* every other box near a ball's centre (within its radius), where both answers
         * turn */
        const double *at = ball[(size_t)uniform(&s, 0, (double)n)];
        for (int a = 0; a < 3; a++) {
            double grow = 0.1 * (hi[a] - lo[a]) + rmax;
            blo[a] = k % 2 ? at[a] + uniform(&s, -at[3], at[3]) - 0.5 * side
                           : uniform(&s, lo[a] - grow, hi[a] + grow);
            bhi[a] = blo[a] + side * uniform(&s, 0.5, 1);
        }
        bool want_holds, want_near;
        scan((const double (*)[4])ball, n, blo, bhi, reach, &want_holds, &want_near);
        held += want_holds;
        near += want_near;
        cr_assert_eq(ism_quiet_holds(&q, blo, bhi), want_holds, "query %zu: holds %d, the scan "
                     "%d", k, !want_holds, want_holds);
        cr_assert_eq(ism_quiet_near(&q, blo, bhi, reach), want_near, "query %zu (reach %g): "
                     "near %d, the scan %d", k, reach, !want_near, want_near);
    }
    cr_log_info("%zu held, %zu near", held, near);
    cr_expect(held > QUERIES / 10 && held < QUERIES / 2 && near > QUERIES / 10 &&
              near < QUERIES - QUERIES / 10,
              "%zu held, %zu near of %d boxes: the queries should test both answers", held,
              near, QUERIES);
    ism_quiet_free(&q);
    free(ball);
}

Test(quiet, index_answers_as_a_scan)
{
    check_layout(3000, (const double[3]){-1, -1, -1}, (const double[3]){1, 1, 1}, 0.005, 0.02,
                 0x9e3779b97f4a7c15ULL);
}

Test(quiet, index_answers_as_a_scan_past_the_grid_wrap)
{
    /* radii up to 1e-3 (the grid's cell) along 3 units of x: 3,000 cells, wrapped twice */
    check_layout(3000, (const double[3]){0, -2e-3, -2e-3}, (const double[3]){3, 2e-3, 2e-3},
                 2e-4, 1e-3, 0x2545F4914F6CDD1DULL);
}
