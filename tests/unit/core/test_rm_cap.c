/* test_rm_cap.c — rm_is_cap (core/remesh/rm_mesh.c): a triangle is a cap when its largest
 * angle is at least ISM_RM_CAP_DEG, at every scale the arc tangent itself holds at. Its
 * quick screen (a corner whose cosine's square is well under cos² 160° is no cap) must agree
 * with the arc tangent it stands for: angles 150°-170° and 160° ± 1e-12°, sides 1, 1e±30,
 * ~1e-75 and ~1e75. The reference is the angle of the unscaled sides, from atan2 of the
 * cross product's length and the dot product. (Under ~1e-77 rm_angle's squared cross
 * product is subnormal as the screen's |u|²|w|² is: at 2^-262 160° ± 1e-12° come out
 * wrong, at 2^-270 a 150° corner reads as a cap, screen or not. No mesh has such sides;
 * rm_mesh.c says so.) */
#include <criterion/criterion.h>
#include <math.h>

#include "core/remesh/rm_mesh.h"

/* Whether the angle theta (radians) between sides of lengths 1 and len is a cap: the
 * arctangent form on the unit-scale sides. */
static bool cap_reference(double theta, double len)
{
    double u[3] = {1, 0, 0}, w[3] = {len * cos(theta), len * sin(theta), 0};
    double cr = u[0] * w[1] - u[1] * w[0];
    double angle = atan2(fabs(cr), u[0] * w[0] + u[1] * w[1]);
    return cos(angle) < cos(ISM_RM_CAP_DEG * M_PI / 180);
}

Test(rm_cap, screen_agrees_with_the_arctangent_at_every_scale)
{
    /* powers of two: scaling the corners is exact, so every scale has the unit triangle's
       angles bit for bit; ±100 are 1e±30 */
    const int scale2[] = {0, -100, 100, -250, 250};
    const double lens[] = {1.0, 1.7, 0.55};
    const double eps_deg[] = {1e-12, -1e-12};
    int caps = 0, runs = 0;
    for (size_t si = 0; si < sizeof scale2 / sizeof *scale2; si++)
        for (size_t li = 0; li < sizeof lens / sizeof *lens; li++) {
            for (int step = 0; step < 40 + 2; step++) {
                /* 150.25°-169.75° in half degrees, then 160° ± 1e-12° (160° itself is the
                   rounding's: either answer is right) */
                double deg = step < 40 ? 150.25 + 0.5 * step : 160 + eps_deg[step - 40];
                double th = deg * M_PI / 180, s = ldexp(1, scale2[si]);
                double o[3] = {ldexp(0.375, scale2[si]), ldexp(-0.25, scale2[si]),
                               ldexp(0.125, scale2[si])};
                double a[3] = {o[0], o[1], o[2]};
                double b[3] = {o[0] + s, o[1], o[2]};
                double c[3] = {o[0] + s * lens[li] * cos(th), o[1] + s * lens[li] * sin(th),
                               o[2]};
                bool want = cap_reference(th, lens[li]);
                caps += want;
                runs++;
                cr_expect_eq(rm_is_cap(a, b, c), want,
                             "%.13f deg, sides 1 and %g, scale 2^%d: cap %d expected", deg,
                             lens[li], scale2[si], want);
                cr_expect_eq(rm_is_cap(b, c, a), want, "rotated corners, %.13f deg", deg);
            }
        }
    cr_assert(caps > 0 && caps < runs, "both caps and non-caps among the angles");
}
