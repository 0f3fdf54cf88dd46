/* roman_dist.c — the distance to Steiner's Roman surface x²y² + y²z² + z²x² + xyz = 0 from its
 * parametrisation S(u, v, w) = (−vw, uw, uv) on the unit sphere (S(−s) = S(s): the upper half
 * covers it; f(S(s)) = u²v²w²(u² + v² + w²) − u²v²w² = 0), and the coordinate axes, where
 * f = 0 beyond the pinch points (±½ on each axis) too.
 * The search: S at a Fibonacci set of the sphere's points (about 0.0056 apart; S moves a point
 * at most as far as its parameter moves, so every surface point is within that of a sample),
 * kept in a grid of 0.025 cells; for q, every sample within the nearest sample's distance plus
 * twice the spacing (one lies that near q's nearest surface point, on whichever sheet) starts a
 * pattern search over the sphere down to 1e-10, and the nearest point reached counts. */
#include "tests/unit/core/roman_dist.h"

#include <criterion/criterion.h>
#include <math.h>
#include <stdbool.h>
#include <stdlib.h>

#define SAMPLES_SPHERE 400000 /* Fibonacci points of the whole sphere; half are kept */
#define SPACING 0.0056        /* their spacing on the sphere: √(4π / 400000) */
#define CELL 0.025            /* grid cell: ≥ the farthest candidate of a q within REACH */
#define HALF 0.525            /* the grid's half width: the surface lies in |x|, |y|, |z| ≤ ½ */
#define N_CELLS 42            /* 2 HALF / CELL */
#define REACH (CELL - 2 * SPACING) /* q this near the samples: its candidates are in 27 cells */
#define GOLDEN_ANGLE 2.39996322972865332
/* Candidates closer than this on the sphere to one already searched from are skipped: two
 * samples' spacings, inside one valley of the distance (the sheets through q's neighbourhood
 * are far apart on the sphere: the double curves' two preimages, the pinch points' folds). */
#define START_APART (2 * SPACING)
#define MAX_STARTS 64 /* starts remembered (a few are made: one or two per sheet) */
#define STEP_LAST 1e-10 /* the pattern search's last step on the sphere: far below the 3 digits
                           the tests compare */

struct roman_dist {
    double *s;      /* per sample: its point of the sphere (3) */
    double *p;      /* per sample: S of it (3) */
    size_t *start;  /* per cell: its first sample in order; N_CELLS³ + 1 */
    size_t *order;  /* samples by cell */
    size_t n;
};

static void surface_at(const double s[3], double p[3])
{
    p[0] = -s[1] * s[2];
    p[1] = s[0] * s[2];
    p[2] = s[0] * s[1];
}

static int cell_of(double x)
{
    int c = (int)floor((x + HALF) / CELL);
    return c < 0 ? 0 : c >= N_CELLS ? N_CELLS - 1 : c;
}

static size_t cell_index(const double p[3])
{
    return ((size_t)cell_of(p[0]) * N_CELLS + (size_t)cell_of(p[1])) * N_CELLS +
           (size_t)cell_of(p[2]);
}

roman_dist *roman_dist_new(void)
{
    roman_dist *r = calloc(1, sizeof *r);
    size_t ncells = (size_t)N_CELLS * N_CELLS * N_CELLS;
    if (!r || !(r->s = malloc(SAMPLES_SPHERE / 2 * 3 * sizeof(double) + 48)) ||
        !(r->p = malloc(SAMPLES_SPHERE / 2 * 3 * sizeof(double) + 48)) ||
        !(r->start = calloc(ncells + 1, sizeof(size_t))) ||
        !(r->order = malloc((SAMPLES_SPHERE / 2 + 2) * sizeof(size_t)))) {
        roman_dist_free(r);
        return NULL;
    }
    for (int i = 0; i < SAMPLES_SPHERE; i++) {
        double z = 1 - (2 * i + 1.0) / SAMPLES_SPHERE, rho = sqrt(1 - z * z);
        if (z < 0)
            break; /* the lower half: S(−s) = S(s) */
        double *s = r->s + 3 * r->n;
        s[0] = rho * cos(i * GOLDEN_ANGLE);
        s[1] = rho * sin(i * GOLDEN_ANGLE);
        s[2] = z;
        surface_at(s, r->p + 3 * r->n);
        r->start[cell_index(r->p + 3 * r->n) + 1]++;
        r->n++;
    }
    for (size_t c = 0; c < ncells; c++)
        r->start[c + 1] += r->start[c];
    size_t *fill = malloc(ncells * sizeof *fill);
    if (!fill) {
        roman_dist_free(r);
        return NULL;
    }
    for (size_t c = 0; c < ncells; c++)
        fill[c] = r->start[c];
    for (size_t i = 0; i < r->n; i++)
        r->order[fill[cell_index(r->p + 3 * i)]++] = i;
    free(fill);
    return r;
}

void roman_dist_free(roman_dist *r)
{
    if (!r)
        return;
    free(r->s);
    free(r->p);
    free(r->start);
    free(r->order);
    free(r);
}

static double sq_to(const double s[3], const double q[3])
{
    double p[3];
    surface_at(s, p);
    return (p[0] - q[0]) * (p[0] - q[0]) + (p[1] - q[1]) * (p[1] - q[1]) +
           (p[2] - q[2]) * (p[2] - q[2]);
}

/* The nearest squared distance to q a pattern search over the sphere reaches from s0. */
static double descend(const double s0[3], const double q[3])
{
    /* two unit directions across s0 */
    double a[3] = {fabs(s0[0]) < 0.6 ? 1 : 0, fabs(s0[0]) < 0.6 ? 0 : 1, 0}, e[2][3];
    double c = a[0] * s0[0] + a[1] * s0[1] + a[2] * s0[2], n = 0;
    for (int k = 0; k < 3; k++) {
        e[0][k] = a[k] - c * s0[k];
        n += e[0][k] * e[0][k];
    }
    for (int k = 0; k < 3; k++)
        e[0][k] /= sqrt(n);
    e[1][0] = s0[1] * e[0][2] - s0[2] * e[0][1];
    e[1][1] = s0[2] * e[0][0] - s0[0] * e[0][2];
    e[1][2] = s0[0] * e[0][1] - s0[1] * e[0][0];
    double at[2] = {0, 0}, best = sq_to(s0, q);
    for (double step = 2 * SPACING; step >= STEP_LAST; step *= 0.5) {
        for (bool moved = true; moved;) {
            moved = false;
            for (int k = 0; k < 4; k++) {
                double t[2] = {at[0] + (k == 0 ? step : k == 1 ? -step : 0),
                               at[1] + (k == 2 ? step : k == 3 ? -step : 0)};
                double s[3], len = 0;
                for (int j = 0; j < 3; j++) {
                    s[j] = s0[j] + t[0] * e[0][j] + t[1] * e[1][j];
                    len += s[j] * s[j];
                }
                for (int j = 0; j < 3; j++)
                    s[j] /= sqrt(len);
                double d = sq_to(s, q);
                if (d < best) {
                    best = d;
                    at[0] = t[0];
                    at[1] = t[1];
                    moved = true;
                }
            }
        }
    }
    return best;
}

/* A search started within START_APART of s on the sphere (it descends the same valley). */
static bool started_near(const double *const *starts, int n, const double s[3])
{
    for (int k = 0; k < n; k++) {
        const double *t = starts[k];
        double d = (t[0] - s[0]) * (t[0] - s[0]) + (t[1] - s[1]) * (t[1] - s[1]) +
                   (t[2] - s[2]) * (t[2] - s[2]);
        if (d < START_APART * START_APART)
            return true;
    }
    return false;
}

double roman_dist_at(const roman_dist *r, const double q[3])
{
    int c0[3] = {cell_of(q[0]), cell_of(q[1]), cell_of(q[2])};
    double near = INFINITY; /* the nearest sample's squared distance */
    const double *starts[MAX_STARTS];
    int nstarts = 0;
    for (int pass = 0; pass < 2; pass++) {
        double reach = sqrt(near) + 2 * SPACING, best = near;
        for (int dx = -1; dx <= 1; dx++)
            for (int dy = -1; dy <= 1; dy++)
                for (int dz = -1; dz <= 1; dz++) {
                    int c[3] = {c0[0] + dx, c0[1] + dy, c0[2] + dz};
                    if (c[0] < 0 || c[1] < 0 || c[2] < 0 || c[0] >= N_CELLS ||
                        c[1] >= N_CELLS || c[2] >= N_CELLS)
                        continue;
                    size_t cell = ((size_t)c[0] * N_CELLS + (size_t)c[1]) * N_CELLS +
                                  (size_t)c[2];
                    for (size_t j = r->start[cell]; j < r->start[cell + 1]; j++) {
                        size_t i = r->order[j];
                        double d = sq_to(r->s + 3 * i, q);
                        if (pass == 0)
                            near = fmin(near, d);
                        else if (sqrt(d) <= reach &&
                                 !started_near(starts, nstarts, r->s + 3 * i)) {
                            best = fmin(best, descend(r->s + 3 * i, q));
                            if (nstarts < MAX_STARTS)
                                starts[nstarts++] = r->s + 3 * i;
                        }
                    }
                }
        if (pass == 1) {
            double axes = fmin(hypot(q[1], q[2]), fmin(hypot(q[0], q[2]), hypot(q[0], q[1])));
            return fmin(sqrt(best), axes);
        }
        cr_assert(sqrt(near) <= REACH, "roman_dist: (%g, %g, %g) is %g from the samples, "
                  "beyond the %g the grid's neighbourhood covers", q[0], q[1], q[2],
                  sqrt(near), REACH);
    }
    return INFINITY;
}
