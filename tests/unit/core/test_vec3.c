/* test_vec3.c — vec3.h's frames across a direction (ism_across3 against its closed form,
 * ism_across_least3 normal to the axis least along it), and the Fibonacci sphere's directions
 * (ism_fibonacci_dir): unit, evenly spaced heights, and the covering nearest.c's 64 rays rely
 * on (every direction within 19.6° of a ray), measured on a latitude-longitude grid of
 * probes, not on the set's own construction; a box's diagonal against integer closed forms. */
#include <criterion/criterion.h>
#include <math.h>
#include "core/util/vec3.h"

/* A frame's tolerance: a few roundings of unit-length arithmetic. */
#define FRAME_TOL 1e-14
/* nearest.c's ray count and the covering it needs: a sheet at 0.94 r meets a ray within r
 * when every direction is within acos(0.94) = 19.9° of a ray (measured: 19.52°). */
#define RAYS 64
#define RAYS_COVER_COS 0.94
/* The probes' grid step in degrees (the covering measured to within ~0.25°). */
#define PROBE_STEP 0.5

/* e: orthonormal across u, u · (e[0] × e[1]) = 1 (right-handed). */
static void check_orthonormal(const double u[3], const double e[2][3])
{
    cr_assert(fabs(ism_norm3(e[0]) - 1) < FRAME_TOL && fabs(ism_norm3(e[1]) - 1) < FRAME_TOL);
    cr_assert(fabs(ism_dot3(u, e[0])) < FRAME_TOL && fabs(ism_dot3(u, e[1])) < FRAME_TOL &&
                  fabs(ism_dot3(e[0], e[1])) < FRAME_TOL,
              "u (%g, %g, %g)", u[0], u[1], u[2]);
    double x[3] = {e[0][1] * e[1][2] - e[0][2] * e[1][1], e[0][2] * e[1][0] - e[0][0] * e[1][2],
                   e[0][0] * e[1][1] - e[0][1] * e[1][0]};
    cr_assert(fabs(ism_dot3(u, x) - 1) < FRAME_TOL, "right-handed: u · (e0 × e1) = %g",
              ism_dot3(u, x));
}

static void check_frame(const double u[3])
{
    double e[2][3];
    ism_across3(u, e);
    check_orthonormal(u, e);
    /* e0: the axis a (x, or y when |u_x| ≥ 0.6) minus its part along u, normalised:
     * (δ_ka − u_a u_k) / √(1 − u_a²) */
    int a = fabs(u[0]) < 0.6 ? 0 : 1;
    double s = sqrt(1 - u[a] * u[a]);
    for (int k = 0; k < 3; k++)
        cr_assert(fabs(e[0][k] - ((k == a) - u[a] * u[k]) / s) < FRAME_TOL,
                  "u (%g, %g, %g): e0[%d] %.17g", u[0], u[1], u[2], k, e[0][k]);
}

Test(vec3, across_is_a_right_handed_orthonormal_frame)
{
    /* the axes both ways, the seed's switch at |u_x| = 0.6 and beside it, a spread of others */
    const double fixed[][3] = {{1, 0, 0},     {-1, 0, 0},     {0, 1, 0},
                               {0, -1, 0},    {0, 0, 1},      {0, 0, -1},
                               {0.6, 0.8, 0}, {-0.6, 0, 0.8}, {0.6, 0, -0.8},
                               {0.5999999, 0.8000001, 0}};
    for (size_t i = 0; i < sizeof fixed / sizeof fixed[0]; i++) {
        double u[3] = {fixed[i][0], fixed[i][1], fixed[i][2]};
        ism_normalise3(u);
        check_frame(u);
    }
    for (int i = 0; i < 997; i++) {
        double u[3];
        ism_fibonacci_dir(i, 997, u);
        check_frame(u);
    }
}

/* ism_across_least3: e[0] normal to the axis a least along u (the first of equals), so a
 * lies in the plane of u and e[1]. */
static void check_least(const double u[3])
{
    double e[2][3];
    ism_across_least3(u, e);
    check_orthonormal(u, e);
    int a = 0;
    for (int k = 1; k < 3; k++)
        a = fabs(u[k]) < fabs(u[a]) ? k : a;
    cr_assert(fabs(e[0][a]) < FRAME_TOL, "u (%g, %g, %g): e0 along axis %d: %g", u[0], u[1],
              u[2], a, e[0][a]);
    /* e1 = u × (u × a) / |u × a| = (u_a u − a) / √(1 − u_a²): its a-th part −√(1 − u_a²) */
    cr_assert(fabs(e[1][a] + sqrt(1 - u[a] * u[a])) < FRAME_TOL, "u (%g, %g, %g): e1[%d] %g",
              u[0], u[1], u[2], a, e[1][a]);
}

Test(vec3, across_least_is_normal_to_the_least_axis)
{
    const double fixed[][3] = {{1, 0, 0},  {0, -1, 0},   {0, 0, 1},
                               {1, 1, 0},  {0, 1, 1},    {1, 1, 1},
                               {0.3, -0.3, 0.9}, {-0.9, 0.2, 0.2}};
    for (size_t i = 0; i < sizeof fixed / sizeof fixed[0]; i++) {
        double u[3] = {fixed[i][0], fixed[i][1], fixed[i][2]};
        ism_normalise3(u);
        check_least(u);
    }
    for (int i = 0; i < 997; i++) {
        double u[3];
        ism_fibonacci_dir(i, 997, u);
        check_least(u);
    }
}

Test(vec3, fibonacci_directions_spread_over_the_sphere)
{
    double d[RAYS][3];
    for (int i = 0; i < RAYS; i++) {
        ism_fibonacci_dir(i, RAYS, d[i]);
        cr_assert(fabs(ism_norm3(d[i]) - 1) < FRAME_TOL);
        cr_assert(fabs(d[i][2] - (double)(RAYS - 2 * i - 1) / RAYS) < 1e-15, "height %d", i);
    }
    double worst = 1;
    for (double th = 0; th <= 180; th += PROBE_STEP)
        for (double ph = 0; ph < 360; ph += PROBE_STEP) {
            double t = th * M_PI / 180, p = ph * M_PI / 180, best = -1;
            double q[3] = {sin(t) * cos(p), sin(t) * sin(p), cos(t)};
            for (int i = 0; i < RAYS; i++)
                best = fmax(best, ism_dot3(q, d[i]));
            worst = fmin(worst, best);
        }
    cr_assert(worst >= RAYS_COVER_COS, "a probe %.2f° from every ray",
              acos(worst) * 180 / M_PI);
}

/* ism_tri_cross3 / ism_tri_area3 against closed forms: the triangle (0,0,0) (a,0,0) (0,b,0)
 * turned about z by θ and moved by t has normal (0, 0, ab) whatever θ and t (wound
 * counter-clockwise seen from +z), area ab/2; the reversed winding flips the normal; a
 * degenerate triangle (three points on a line) has none. The tolerance: a few roundings of
 * coordinates of size |t| + max(a, b). */
Test(vec3, triangle_cross_and_area_closed_forms)
{
    const double sizes[][2] = {{1, 1}, {3, 0.5}, {1e-3, 2e-3}, {0.25, 7}};
    const double moves[][3] = {{0, 0, 0}, {1e-3, -2e-3, 0.5}, {10, 10, -10}};
    for (size_t i = 0; i < sizeof sizes / sizeof sizes[0]; i++)
        for (size_t j = 0; j < sizeof moves / sizeof moves[0]; j++)
            for (int k = 0; k < 12; k++) {
                double a = sizes[i][0], b = sizes[i][1], th = k * M_PI / 6 + 0.1;
                const double *t = moves[j];
                double p[3][3] = {{0, 0, 0}, {a, 0, 0}, {0, b, 0}};
                for (int v = 0; v < 3; v++) {
                    double x = p[v][0], y = p[v][1];
                    p[v][0] = cos(th) * x - sin(th) * y + t[0];
                    p[v][1] = sin(th) * x + cos(th) * y + t[1];
                    p[v][2] += t[2];
                }
                double tol = 1e-14 * (ism_norm3(t) + fmax(a, b)) * fmax(a, b), n[3], r[3];
                ism_tri_cross3(p[0], p[1], p[2], n);
                cr_assert(fabs(n[0]) < tol && fabs(n[1]) < tol && fabs(n[2] - a * b) < tol,
                          "a %g b %g θ %g: n (%g, %g, %g)", a, b, th, n[0], n[1], n[2]);
                ism_tri_cross3(p[0], p[2], p[1], r);
                cr_assert(fabs(r[2] + a * b) < tol, "reversed: %g", r[2]);
                cr_assert(fabs(ism_tri_area3(p[0], p[1], p[2]) - 0.5 * a * b) < tol);
            }
    const double l[3][3] = {{1, 2, 3}, {2, 4, 6}, {-1, -2, -3}};
    cr_assert(ism_tri_area3(l[0], l[1], l[2]) == 0, "collinear: %g",
              ism_tri_area3(l[0], l[1], l[2]));
}

/* ism_sqdist_box3 against the distance to the nearest point of the box, found another way:
 * p clamped into the box (fmin/fmax per axis), |p − clamp(p)|²; 0 inside and on the faces, the
 * corner's distance beyond a corner, an edge's beyond an edge. */
Test(vec3, box_distance_is_the_distance_to_the_clamped_point)
{
    const double lo[3] = {-1, 0.5, 2}, hi[3] = {1, 0.75, 5};
    int n = 0;
    for (double x = -3; x <= 3; x += 0.25)
        for (double y = -0.5; y <= 1.5; y += 0.125)
            for (double z = 0; z <= 7; z += 0.5) {
                double p[3] = {x, y, z}, c[3];
                for (int a = 0; a < 3; a++)
                    c[a] = fmin(hi[a], fmax(lo[a], p[a]));
                double want = ism_sqdist3(p, c), got = ism_sqdist_box3(p, lo, hi);
                cr_assert(got == want, "p (%g, %g, %g): %.17g, clamped %.17g", x, y, z, got,
                          want);
                n += got == 0;
            }
    cr_assert(n > 0, "some probes inside");
    const double corner[3] = {2, 2, 8}; /* beyond hi on every axis: (1, 1.25, 3) away */
    cr_assert(ism_sqdist_box3(corner, lo, hi) == 1 + 1.5625 + 9);
}

/* ism_box_diagonal on boxes whose diagonal is an integer (Pythagorean quadruples: 1² + 2² +
 * 2² = 3², 2² + 3² + 6² = 7²), in any corner order of the widths and off the origin, and the
 * same bits as the sum of the squared widths in x, y, z order then sqrt (what proto/request.c
 * and the tolerances it scales computed before it was shared). */
Test(vec3, box_diagonal_closed_forms)
{
    static const double boxes[][6] = {{0, 0, 0, 1, 2, 2}, {-1, -2, -2, 0, 0, 0},
                                      {10, -3, 0.5, 12, 0, 6.5}, {-1.5, -1.5, -1.5, 1.5, 1.5, 1.5}};
    static const double want[] = {3, 3, 7, 3 * 1.7320508075688772};
    for (int i = 0; i < 4; i++) {
        const double *b = boxes[i];
        double d = ism_box_diagonal(b), d2 = 0;
        for (int k = 0; k < 3; k++)
            d2 += (b[k + 3] - b[k]) * (b[k + 3] - b[k]);
        cr_assert(fabs(d - want[i]) <= 1e-15 * want[i], "box %d: %.17g, want %.17g", i, d,
                  want[i]);
        cr_assert(d == sqrt(d2), "box %d: %.17g, the loop's %.17g", i, d, sqrt(d2));
    }
}
