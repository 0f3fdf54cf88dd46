/* nearest.c — the distance from a point q to f = 0 by finding points of the surface near q:
 * Newton's projection from q (the foot along ∇f, exact to second order on a smooth sheet) and
 * rays from q in fixed directions on which f changes sign (a zero between, narrowed by
 * bisection), the best ray's direction then tilted while it finds a nearer zero. Beside a
 * singular point or curve ∇f vanishes on the surface, so |f| / |∇f| at q can be several times
 * the distance (Steiner's surface beside its pinch points: 1.11 E estimated where the nearest
 * point is 0.25 E away) and Newton's steps follow the gradient of the wrong sheet; the rays
 * find the nearer sheet whichever it is. */
#include "core/analysis/nearest.h"
#include "core/util/vec3.h"

#include <math.h>

/* Newton steps from q: a smooth sheet's foot converges in 3-4; beyond 8 the start is
 * beside a singular point, where the rays decide. */
#define NEWTON_STEPS 8
/* Newton's point is on f = 0 when its own first-order distance is below this fraction of
 * q's: the foot is then exact far below what the figures print (3 digits). */
#define ON_SURFACE 1e-6
/* Stop Newton where |∇f| fell below this fraction of its value at q (a singular point). */
#define NEWTON_STALL 1e-6
/* Ray directions, a Fibonacci sphere (22-25° apart, every direction within 19.6° of one:
 * vec3/fibonacci_directions_spread_over_the_sphere): a sheet whose nearest point is t from q
 * crosses the rays within acos(t / r) of its normal before radius r, so a sheet at 0.94 r or
 * nearer meets a ray. */
#define RAY_DIRECTIONS 64
/* Bisection steps along a ray: the zero to 2^-16 ≈ 1.5e-5 of the radius (the figures are
 * printed to 3 digits). */
#define BISECTIONS 16
/* The tilts of the best ray's direction: from 1/4 (14°) halving down to 1/256 (0.22°): the
 * distance along a tilted ray exceeds the nearest one by 1 / cos of the angle left, 7.6e-6. */
#define TILT_FIRST 0.25
#define TILT_LAST (1.0 / 256)
/* Moves at one tilt before the next, half as large: a cap on the work; the angle left after a
 * tilt's moves is within one of its steps, two of the next's, so 8 are never short. */
#define TILT_MOVES 8

typedef struct seeker {
    const ism_tape *f;
    ism_eval_ws *ws;
    const double *q;
    bool neg;         /* f(q) < 0: the side a sign change leaves */
    uint64_t *counts; /* [0] points, [1] gradients evaluated (nearest.h) */
} seeker;

static bool other_side(const seeker *s, const double u[3], double t)
{
    s->counts[0]++;
    double v = ism_eval_point(s->f, s->ws, s->q[0] + t * u[0], s->q[1] + t * u[1],
                              s->q[2] + t * u[2]);
    return !isnan(v) && (v < 0) != s->neg;
}

/* f changes sign between q and q + hi u: the end of the bracket narrowed round a zero. */
static double bisect(const seeker *s, const double u[3], double hi)
{
    double lo = 0;
    for (int i = 0; i < BISECTIONS; i++) {
        double mid = 0.5 * (lo + hi);
        if (other_side(s, u, mid))
            hi = mid;
        else
            lo = mid;
    }
    return hi;
}

/* The distance to the Newton foot from q, INFINITY when Newton does not reach f = 0; |∇f(q)|
 * into *gq. */
static double newton_foot(const seeker *s, double d0, double *gq)
{
    double p[3] = {s->q[0], s->q[1], s->q[2]}, g[3], g_start = 0;
    *gq = NAN;
    for (int i = 0; i <= NEWTON_STEPS; i++) {
        s->counts[1]++;
        double fv = ism_eval_gradient(s->f, s->ws, p[0], p[1], p[2], g), gn = ism_norm3(g);
        if (i == 0)
            *gq = g_start = gn;
        if (!isfinite(fv) || !(gn > NEWTON_STALL * g_start))
            return INFINITY;
        if (fabs(fv) / gn <= ON_SURFACE * d0)
            return ism_dist3(p, s->q);
        if (i == NEWTON_STEPS)
            break;
        double k = fv / (gn * gn);
        for (int a = 0; a < 3; a++)
            p[a] -= k * g[a];
    }
    return INFINITY;
}

/* The first two samples of rays from..RAY_DIRECTIONS at radius r (r / 2 and r: nearest_ray's
 * order) evaluated in one ism_eval_points batch, each lane bit for bit ism_eval_point's value:
 * half[i] and full[i] are other_side's answers there. Not counted: nearest_ray counts the
 * samples its one-by-one order asks for. One at a time the rays cost the Klein bottle at
 * E 3.27e-3 (bench_error mesh klein-bottle 0.00327 10, one thread, callgrind) 131.9M of its
 * 3,983M instructions (2,370 searches, ~128 samples each, ~420 instructions a sample). */
static void sample_rays(const seeker *s, const double (*dir)[3], int from, double r, bool *half,
                        bool *full)
{
    double x[2 * RAY_DIRECTIONS], y[2 * RAY_DIRECTIONS], z[2 * RAY_DIRECTIONS],
        v[2 * RAY_DIRECTIONS];
    size_t n = 0;
    for (int i = from; i < RAY_DIRECTIONS; i++)
        for (int k = 0; k < 2; k++, n++) {
            double t = k ? r : 0.5 * r; /* the same t, so the same point, as other_side's */
            x[n] = s->q[0] + t * dir[i][0];
            y[n] = s->q[1] + t * dir[i][1];
            z[n] = s->q[2] + t * dir[i][2];
        }
    ism_eval_points(s->f, s->ws, x, y, z, v, n);
    for (int i = from, j = 0; i < RAY_DIRECTIONS; i++, j += 2) {
        half[i] = !isnan(v[j]) && (v[j] < 0) != s->neg;
        full[i] = !isnan(v[j + 1]) && (v[j + 1] < 0) != s->neg;
    }
}

/* The nearest zero on a ray of the fixed directions within r (at r / 2 or r: a ray that
 * crosses two sheets within r has its sign back at r), *u its direction; r when none. The
 * rays' samples come from sample_rays, taken again for the rays left whenever a ray finds a
 * nearer zero (rarely: most searches find none nearer than Newton's foot), so the answer and
 * the counts are those of asking other_side ray by ray. */
static double nearest_ray(const seeker *s, double r, double u[3])
{
    double best = r, dir[RAY_DIRECTIONS][3], sampled = NAN;
    bool half[RAY_DIRECTIONS], full[RAY_DIRECTIONS];
    for (int i = 0; i < RAY_DIRECTIONS; i++)
        ism_fibonacci_dir(i, RAY_DIRECTIONS, dir[i]);
    for (int i = 0; i < RAY_DIRECTIONS; i++) {
        if (!(best == sampled)) {
            sample_rays(s, (const double (*)[3])dir, i, best, half, full);
            sampled = best;
        }
        s->counts[0] += half[i] ? 1 : 2;
        double t = half[i]   ? bisect(s, dir[i], 0.5 * best)
                   : full[i] ? bisect(s, dir[i], best)
                             : INFINITY;
        if (t < best) {
            best = t;
            for (int a = 0; a < 3; a++)
                u[a] = dir[i][a];
        }
    }
    return best;
}

/* Tilts u toward ± two directions across it while a ray finds a zero nearer than t. */
static double tilt(const seeker *s, double u[3], double t)
{
    double e[2][3];
    ism_across3(u, e);
    for (double step = TILT_FIRST; step >= TILT_LAST; step *= 0.5) {
        bool nearer = true;
        for (int moves = 0; nearer && moves < TILT_MOVES; moves++) {
            nearer = false;
            for (int k = 0; k < 4 && !nearer; k++) {
                double v[3], sg = k & 1 ? -step : step;
                for (int a = 0; a < 3; a++)
                    v[a] = u[a] + sg * e[k >> 1][a];
                ism_normalise3(v);
                if (!other_side(s, v, t))
                    continue;
                double t2 = bisect(s, v, t);
                if (t2 < t) {
                    t = t2;
                    nearer = true;
                    for (int a = 0; a < 3; a++)
                        u[a] = v[a];
                }
            }
        }
    }
    return t;
}

double ism_an_nearest_zero(const ism_tape *f, ism_eval_ws *ws, const double q[3], double d0,
                           double rays_below, uint64_t counts[2])
{
    if (!(d0 > 0) || !isfinite(d0))
        return d0;
    uint64_t own[2] = {0, 0};
    if (!counts)
        counts = own;
    counts[0]++;
    double fq = ism_eval_point(f, ws, q[0], q[1], q[2]);
    if (isnan(fq))
        return d0;
    seeker s = {f, ws, q, fq < 0, counts};
    double gq, best = fmin(d0, newton_foot(&s, d0, &gq)), u[3];
    if (!(gq < rays_below))
        return best;
    double t = nearest_ray(&s, best, u);
    return t < best ? tilt(&s, u, t) : best;
}
