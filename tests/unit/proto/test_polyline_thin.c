/* test_polyline_thin.c — the crease arcs' thinning (proto/polyline_thin.h), checked against
 * closed forms: on a circle of radius R sampled at an irrational angular step, every dropped
 * vertex lies within tol of the whole kept polyline (measured here against every kept segment,
 * not only the two neighbours the thinning looked at), and the number kept is between the
 * fewest any polyline through the samples can have (chords whose sagitta R (1 - cos(a / 2))
 * is <= tol: a <= 2 acos(1 - tol / R)) and twice that (Douglas-Peucker halves a circle's arcs);
 * a finer tol keeps more; an open helix keeps its ends; collinear points keep two; a
 * zigzag farther than tol from every chord that skips a vertex keeps every point; tol <= 0 keeps every point;
 * no index (NULL) keeps what the identity index keeps. */
#include <criterion/criterion.h>
#include <math.h>
#include <stdlib.h>

#include "core/util/vec3.h"
#include "proto/polyline_thin.h"

/* The largest distance of a dropped vertex to the nearest segment of the kept polyline. */
static double worst_dropped(const double *pos, const uint32_t *idx, size_t n,
                            const uint8_t *keep)
{
    double worst = 0;
    for (size_t i = 0; i < n; i++) {
        if (keep[i])
            continue;
        double best = INFINITY;
        size_t prev = 0;
        for (size_t j = 1; j < n; j++) {
            if (!keep[j])
                continue;
            best = fmin(best, sqrt(ism_sqdist_segment3(pos + 3 * idx[i], pos + 3 * idx[prev],
                                                       pos + 3 * idx[j])));
            prev = j;
        }
        worst = fmax(worst, best);
    }
    return worst;
}

#define NCIRCLE 2000

Test(polyline_thin, circle_within_tol_and_near_the_fewest_points)
{
    const double R = 0.7, centre[3] = {0.1, -0.2, 0.3};
    double *pos = malloc(3 * NCIRCLE * sizeof *pos);
    uint32_t idx[NCIRCLE + 1];
    uint8_t keep[NCIRCLE + 1];
    /* an irrational step: no sample at a rational angle, uneven last gap */
    double step = 2 * M_PI / (NCIRCLE - 1 + (sqrt(5) - 1) / 2);
    for (int i = 0; i < NCIRCLE; i++) {
        pos[3 * i] = centre[0] + R * cos(i * step);
        pos[3 * i + 1] = centre[1] + R * sin(i * step);
        pos[3 * i + 2] = centre[2];
        idx[i] = (uint32_t)i;
    }
    idx[NCIRCLE] = 0; /* closed: the first vertex again */
    const size_t n = NCIRCLE + 1;
    size_t last = 0;
    for (double rel = 3e-2; rel >= 3e-5; rel /= 10) {
        double tol = rel * R;
        size_t kept = ism_polyline_thin(pos, idx, n, tol, keep);
        size_t count = 0;
        for (size_t i = 0; i < n; i++)
            count += keep[i];
        cr_assert_eq(kept, count);
        cr_assert(keep[0] && keep[n - 1]);
        double worst = worst_dropped(pos, idx, n, keep);
        cr_assert_leq(worst, tol, "tol %g: a dropped vertex %g off", tol, worst);
        double fewest = 2 * M_PI / (2 * acos(1 - tol / R)); /* chords, then +1 to close */
        cr_assert_geq((double)kept, fewest, "tol %g: %zu kept, fewer than %g", tol, kept, fewest);
        cr_assert_leq((double)kept, 2 * fewest + 3, "tol %g: %zu kept for %g", tol, kept, fewest);
        cr_assert_gt(kept, last, "tol %g: %zu kept, %zu at the coarser", tol, kept, last);
        last = kept;
    }
    free(pos);
}

Test(polyline_thin, open_helix_keeps_its_ends_and_collinear_points_keep_two)
{
    enum { N = 500 };
    double pos[3 * N];
    uint32_t idx[N];
    uint8_t keep[N];
    for (int i = 0; i < N; i++) {
        double t = i * 0.0123456789;
        pos[3 * i] = cos(t);
        pos[3 * i + 1] = sin(t);
        pos[3 * i + 2] = 0.1 * t;
        idx[i] = (uint32_t)(N - 1 - i); /* the chain runs through pos backwards */
    }
    double tol = 1e-3;
    size_t kept = ism_polyline_thin(pos, idx, N, tol, keep);
    cr_assert(keep[0] && keep[N - 1]);
    cr_assert_lt(kept, N / 4);
    cr_assert_leq(worst_dropped(pos, idx, N, keep), tol);
    for (int i = 0; i < N; i++) { /* a line through irrational points, 1e-12 of noise */
        pos[3 * i] = 0.3 + i * M_SQRT2 * 1e-3;
        pos[3 * i + 1] = -0.1 + i * M_PI * 1e-3 + (i % 2 ? 1e-12 : 0);
        pos[3 * i + 2] = i * M_E * 1e-3;
        idx[i] = (uint32_t)i;
    }
    cr_assert_eq(ism_polyline_thin(pos, idx, N, 1e-9, keep), 2);
    cr_assert(keep[0] && keep[N - 1]);
}

Test(polyline_thin, zigzag_above_tol_and_tol_zero_keep_every_point)
{
    enum { N = 64 };
    double pos[3 * N];
    uint32_t idx[N];
    uint8_t keep[N];
    for (int i = 0; i < N; i++) {
        pos[3 * i] = i * 0.01;
        pos[3 * i + 1] = i % 2 ? 2.5e-3 : 0; /* the closest chord past a vertex, to the vertex
                                                three on, passes 1.66e-3 from it */
        pos[3 * i + 2] = 0;
        idx[i] = (uint32_t)i;
    }
    cr_assert_eq(ism_polyline_thin(pos, idx, N, 1.6e-3, keep), N);
    cr_assert_eq(ism_polyline_thin(pos, idx, N, 0, keep), N);
    cr_assert_eq(ism_polyline_thin(pos, idx, N, -1, keep), N);
    for (int i = 0; i < N; i++)
        cr_assert(keep[i]);
    cr_assert_eq(ism_polyline_thin(pos, idx, 0, 1, keep), 0);
    cr_assert_lt(ism_polyline_thin(pos, idx, N, 1.7e-3, keep), N);
}

Test(polyline_thin, no_index_is_the_identity)
{
    enum { N = 300 };
    double pos[3 * N];
    uint32_t idx[N];
    uint8_t keep[N], keep_null[N];
    for (int i = 0; i < N; i++) { /* an open helix at an irrational step, as above */
        double t = i * 0.0234567891;
        pos[3 * i] = cos(t);
        pos[3 * i + 1] = sin(t);
        pos[3 * i + 2] = 0.07 * t;
        idx[i] = (uint32_t)i;
    }
    double tol = 2e-3; /* a chord of sagitta tol spans 2 acos(1 - tol) = 5.4 steps */
    size_t kept = ism_polyline_thin(pos, idx, N, tol, keep);
    cr_assert_eq(ism_polyline_thin(pos, NULL, N, tol, keep_null), kept);
    cr_assert_lt(kept, N / 2);
    for (int i = 0; i < N; i++)
        cr_assert_eq(keep_null[i], keep[i], "vertex %d", i);
    cr_assert_leq(worst_dropped(pos, idx, N, keep_null), tol);
}
