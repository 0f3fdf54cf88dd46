/* test_node_balls.c — the node-ball index (core/octree/node_balls.h) against a scan of every
 * ball written here: random balls of mixed radii and cells, random boxes from much smaller
 * than a ball to the whole region, the same answer for each. */
#include <criterion/criterion.h>
#include <math.h>
#include <stdlib.h>
#include "core/octree/node_balls.h"

/* A deterministic generator (xorshift64*), uniform in [lo, hi). */
static double uniform(uint64_t *s, double lo, double hi)
{
    *s ^= *s >> 12;
    *s ^= *s << 25;
    *s ^= *s >> 27;
    return lo + (hi - lo) * (double)((*s * 0x2545F4914F6CDD1DULL) >> 11) / 9007199254740992.0;
}

/* Does the box meet a ball asking for cells below its longest side (every ball tried)? */
static bool scan(const double (*b)[ISM_NODE_BALL_FIELDS], size_t n, const double lo[3],
                 const double hi[3])
{
    double side = fmax(hi[0] - lo[0], fmax(hi[1] - lo[1], hi[2] - lo[2]));
    for (size_t i = 0; i < n; i++) {
        double d2 = 0;
        for (int a = 0; a < 3; a++) {
            double e = b[i][a] < lo[a] ? lo[a] - b[i][a] : b[i][a] > hi[a] ? b[i][a] - hi[a] : 0;
            d2 += e * e;
        }
        if (b[i][ISM_NODE_BALL_CELL] < side && d2 <= b[i][ISM_NODE_BALL_R] * b[i][ISM_NODE_BALL_R])
            return true;
    }
    return false;
}

Test(node_balls, index_answers_as_a_scan)
{
    enum { N = 2000, QUERIES = 5000 };
    static double ball[N][ISM_NODE_BALL_FIELDS];
    uint64_t s = 0x9e3779b97f4a7c15ULL;
    for (size_t i = 0; i < N; i++) {
        for (int a = 0; a < 3; a++)
            ball[i][a] = uniform(&s, -1, 1);
        ball[i][ISM_NODE_BALL_R] = uniform(&s, 0.002, 0.03);
        ball[i][ISM_NODE_BALL_CELL] = uniform(&s, 0.001, 0.01);
    }
    ism_node_balls x;
    cr_assert(ism_node_balls_init(&x, (const double (*)[ISM_NODE_BALL_FIELDS])ball, N));
    size_t hits = 0;
    for (size_t q = 0; q < QUERIES; q++) {
        double lo[3], hi[3], side = exp(uniform(&s, log(1e-3), log(3)));
        for (int a = 0; a < 3; a++) {
            lo[a] = uniform(&s, -1.2, 1.2);
            hi[a] = lo[a] + side * uniform(&s, 0.5, 1);
        }
        bool want = scan((const double (*)[ISM_NODE_BALL_FIELDS])ball, N, lo, hi);
        hits += want;
        cr_assert_eq(ism_node_balls_split(&x, lo, hi), want, "query %zu (side %g): index %d, "
                     "scan %d", q, side, !want, want);
    }
    cr_expect(hits > QUERIES / 10 && hits < QUERIES - QUERIES / 10, "%zu of %d boxes meet a "
              "ball: the queries should test both answers", hits, QUERIES);
    ism_node_balls_free(&x);
}
