/* param_dist.c — the distance to a surface from its parametrisation (param_dist.h lists the
 * surfaces): S at samples of its parameter domain, kept in a grid; for q, every sample within
 * the nearest sample's distance plus twice the spacing's image (one lies that near q's nearest
 * surface point, on whichever sheet) starts a pattern search over the domain down to 1e-10,
 * and the nearest point reached counts, or the surface's axes if nearer.
 * Domains: the unit sphere (Fibonacci points of the upper half: S(−s) = S(s) for the quadratic
 * maps; the pattern search steps in the tangent plane and goes back onto the sphere) or the
 * plane square |u|, |v| ≤ PLANE_HALF (a square lattice). S moves a point at most LIP times
 * as far as its parameter moves (per surface below), so every surface point is within
 * LIP × spacing of a sample's image. */
#include "tests/unit/core/param_dist.h"
#include "core/util/vec3.h"

#include <criterion/criterion.h>
#include <math.h>
#include <stdbool.h>
#include <stdlib.h>

#define SAMPLES_SPHERE 400000 /* Fibonacci points of the whole sphere; half are kept */
#define SPACING_SPHERE 0.0056 /* their spacing on the sphere: √(4π / 400000) */
#define PLANE_HALF 1.1        /* Whitney's (u, v): z = u² ≤ 1 and y = v in the box ±1, and more */
#define SPACING_PLANE 0.004   /* the plane lattice's step (550² samples) */
#define MAX_STARTS 64 /* starts remembered (a few are made: one or two per sheet) */
#define STEP_LAST 1e-10 /* the pattern search's last step in the domain: far below the 3 digits
                           the tests compare */

typedef struct surface_def {
    bool sphere;
    double lip;     /* |dS| ≤ lip |ds| over the domain */
    double half;    /* the image lies in |x|, |y|, |z| ≤ half */
    unsigned axes;  /* bit a: f = 0 on the whole a-th coordinate axis */
} surface_def;

/* Lipschitz factors: Steiner's (−vw, uw, uv) moves a point on the sphere at most as far as it
 * moves (|dS|² = Σ over the three pairs, each ≤ the move's square times the pair's weight);
 * the cross-cap's (ab, 2ac, c² − a²): the three rows' gradients have lengths ≤ 1, 2, 2 on the
 * sphere, so 3; Whitney's (uv, v, u²) with |u|, |v| ≤ 1.1: rows ≤ 1.1√2, 1, 2.2: √8.26 < 3. */
static const surface_def DEFS[] = {
    [PARAM_STEINER] = {true, 1, 0.5, 7},
    [PARAM_CROSS_CAP] = {true, 3, 1, 4},
    [PARAM_WHITNEY] = {false, 3, PLANE_HALF * PLANE_HALF, 4},
};

struct param_dist {
    param_surface which;
    const surface_def *d;
    double spacing; /* the samples' spacing in the domain */
    double cell;    /* grid cell: ≥ the farthest candidate of a q within PARAM_DIST_REACH */
    int ncell;      /* cells per axis */
    double *s;      /* per sample: its parameter (3; the plane's third is 0) */
    double *p;      /* per sample: S of it (3) */
    size_t *start;  /* per cell: its first sample in order; ncell³ + 1 */
    size_t *order;  /* samples by cell */
    size_t n;
};

static void surface_at(param_surface which, const double s[3], double p[3])
{
    switch (which) {
    case PARAM_STEINER:
        p[0] = -s[1] * s[2];
        p[1] = s[0] * s[2];
        p[2] = s[0] * s[1];
        break;
    case PARAM_CROSS_CAP:
        p[0] = s[0] * s[1];
        p[1] = 2 * s[0] * s[2];
        p[2] = s[2] * s[2] - s[0] * s[0];
        break;
    default: /* PARAM_WHITNEY */
        p[0] = s[0] * s[1];
        p[1] = s[1];
        p[2] = s[0] * s[0];
        break;
    }
}

static int cell_of(const param_dist *r, double x)
{
    int c = (int)floor((x + r->d->half + r->cell) / r->cell);
    return c < 0 ? 0 : c >= r->ncell ? r->ncell - 1 : c;
}

/* The grid cell c (each within 0..ncell − 1): its index. */
static size_t cell_at(const param_dist *r, const int c[3])
{
    return ((size_t)c[0] * (size_t)r->ncell + (size_t)c[1]) * (size_t)r->ncell + (size_t)c[2];
}

static size_t cell_index(const param_dist *r, const double p[3])
{
    int c[3] = {cell_of(r, p[0]), cell_of(r, p[1]), cell_of(r, p[2])};
    return cell_at(r, c);
}

/* The domain's samples into r->s (NULL: only counted); returns how many. */
static size_t domain_samples(const param_dist *r, double *s)
{
    size_t n = 0;
    if (r->d->sphere) {
        for (int i = 0; i < SAMPLES_SPHERE; i++) {
            double v[3];
            ism_fibonacci_dir(i, SAMPLES_SPHERE, v);
            if (v[2] < 0)
                break; /* the lower half: S(−s) = S(s) */
            for (int k = 0; s && k < 3; k++)
                s[3 * n + k] = v[k];
            n++;
        }
        return n;
    }
    int side = (int)ceil(2 * PLANE_HALF / SPACING_PLANE) + 1;
    for (int i = 0; i < side; i++)
        for (int j = 0; j < side; j++) {
            if (s) {
                s[3 * n] = -PLANE_HALF + i * SPACING_PLANE;
                s[3 * n + 1] = -PLANE_HALF + j * SPACING_PLANE;
                s[3 * n + 2] = 0;
            }
            n++;
        }
    return n;
}

param_dist *param_dist_new(param_surface which)
{
    param_dist *r = calloc(1, sizeof *r);
    if (!r)
        return NULL;
    r->which = which;
    r->d = &DEFS[which];
    r->spacing = r->d->sphere ? SPACING_SPHERE : SPACING_PLANE;
    r->cell = PARAM_DIST_REACH + 3 * r->d->lip * r->spacing;
    r->ncell = (int)ceil(2 * r->d->half / r->cell) + 2;
    size_t ns = domain_samples(r, NULL), ncells = (size_t)r->ncell * r->ncell * r->ncell;
    if (!(r->s = malloc(ns * 3 * sizeof(double))) || !(r->p = malloc(ns * 3 * sizeof(double))) ||
        !(r->start = calloc(ncells + 1, sizeof(size_t))) ||
        !(r->order = malloc(ns * sizeof(size_t)))) {
        param_dist_free(r);
        return NULL;
    }
    r->n = domain_samples(r, r->s);
    for (size_t i = 0; i < r->n; i++) {
        surface_at(which, r->s + 3 * i, r->p + 3 * i);
        r->start[cell_index(r, r->p + 3 * i) + 1]++;
    }
    for (size_t c = 0; c < ncells; c++)
        r->start[c + 1] += r->start[c];
    size_t *fill = malloc(ncells * sizeof *fill);
    if (!fill) {
        param_dist_free(r);
        return NULL;
    }
    for (size_t c = 0; c < ncells; c++)
        fill[c] = r->start[c];
    for (size_t i = 0; i < r->n; i++)
        r->order[fill[cell_index(r, r->p + 3 * i)]++] = i;
    free(fill);
    return r;
}

void param_dist_free(param_dist *r)
{
    if (!r)
        return;
    free(r->s);
    free(r->p);
    free(r->start);
    free(r->order);
    free(r);
}

static double sq_to(const param_dist *r, const double s[3], const double q[3])
{
    double p[3];
    surface_at(r->which, s, p);
    return ism_sqdist3(p, q);
}

/* Two unit directions of the domain at s0: across s0 on the sphere, u and v on the plane. */
static void domain_frame(const param_dist *r, const double s0[3], double e[2][3])
{
    if (!r->d->sphere) {
        e[0][0] = e[1][1] = 1;
        e[0][1] = e[0][2] = e[1][0] = e[1][2] = 0;
        return;
    }
    ism_across3(s0, e);
}

/* The nearest squared distance to q a pattern search over the domain reaches from s0. */
static double descend(const param_dist *r, const double s0[3], const double q[3])
{
    double e[2][3];
    domain_frame(r, s0, e);
    double at[2] = {0, 0}, best = sq_to(r, s0, q);
    for (double step = 2 * r->spacing; step >= STEP_LAST; step *= 0.5) {
        for (bool moved = true; moved;) {
            moved = false;
            for (int k = 0; k < 4; k++) {
                double t[2] = {at[0] + (k == 0 ? step : k == 1 ? -step : 0),
                               at[1] + (k == 2 ? step : k == 3 ? -step : 0)};
                double s[3];
                for (int j = 0; j < 3; j++)
                    s[j] = s0[j] + t[0] * e[0][j] + t[1] * e[1][j];
                if (r->d->sphere)
                    ism_normalise3(s); /* back onto the sphere */
                double d = sq_to(r, s, q);
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

/* A search started within two spacings of s in the domain (it descends the same valley: the
 * sheets through q's neighbourhood are far apart in the domain, the double curves' two
 * preimages, the pinch points' folds). */
static bool started_near(const param_dist *r, const double *const *starts, int n,
                         const double s[3])
{
    double apart = 2 * r->spacing;
    for (int k = 0; k < n; k++) {
        if (ism_sqdist3(starts[k], s) < apart * apart)
            return true;
    }
    return false;
}

/* The distance from q to the coordinate axes on which f vanishes everywhere. */
static double axes_dist(const param_dist *r, const double q[3])
{
    double d = INFINITY;
    for (int a = 0; a < 3; a++)
        if (r->d->axes >> a & 1)
            d = fmin(d, hypot(q[(a + 1) % 3], q[(a + 2) % 3]));
    return d;
}

/* The samples of the 27 cells round q's: index ranges into r->order; how many ranges. */
static int neighbourhood(const param_dist *r, const double q[3], size_t range[27][2])
{
    int c0[3] = {cell_of(r, q[0]), cell_of(r, q[1]), cell_of(r, q[2])}, n = 0;
    for (int dx = -1; dx <= 1; dx++)
        for (int dy = -1; dy <= 1; dy++)
            for (int dz = -1; dz <= 1; dz++) {
                int c[3] = {c0[0] + dx, c0[1] + dy, c0[2] + dz};
                if (c[0] < 0 || c[1] < 0 || c[2] < 0 || c[0] >= r->ncell ||
                    c[1] >= r->ncell || c[2] >= r->ncell)
                    continue;
                size_t cell = cell_at(r, c);
                range[n][0] = r->start[cell];
                range[n++][1] = r->start[cell + 1];
            }
    return n;
}

/* The nearest sample's squared distance to q among the ranges, that sample into *at. */
static double nearest_sample(const param_dist *r, const double q[3], size_t range[27][2],
                             int nrange, const double **at)
{
    double near = INFINITY;
    *at = NULL;
    for (int k = 0; k < nrange; k++)
        for (size_t j = range[k][0]; j < range[k][1]; j++) {
            const double *s = r->s + 3 * r->order[j];
            double d = sq_to(r, s, q);
            if (d < near) {
                near = d;
                *at = s;
            }
        }
    return near;
}

double param_dist_upper(const param_dist *r, const double q[3])
{
    size_t range[27][2];
    const double *at;
    nearest_sample(r, q, range, neighbourhood(r, q, range), &at);
    return fmin(at ? sqrt(descend(r, at, q)) : INFINITY, axes_dist(r, q));
}

double param_dist_at(const param_dist *r, const double q[3])
{
    size_t range[27][2];
    const double *at;
    int nrange = neighbourhood(r, q, range);
    double lip_sp = r->d->lip * r->spacing, near = nearest_sample(r, q, range, nrange, &at);
    cr_assert(sqrt(near) <= PARAM_DIST_REACH + lip_sp || axes_dist(r, q) <= PARAM_DIST_REACH,
              "param_dist: (%g, %g, %g) is %g from the samples, beyond the %g the grid's "
              "neighbourhood covers", q[0], q[1], q[2], sqrt(near), PARAM_DIST_REACH + lip_sp);
    const double *starts[MAX_STARTS];
    int nstarts = 0;
    double reach = sqrt(near) + 2 * lip_sp, best = near;
    for (int k = 0; k < nrange; k++)
        for (size_t j = range[k][0]; j < range[k][1]; j++) {
            const double *s = r->s + 3 * r->order[j];
            if (sqrt(sq_to(r, s, q)) <= reach && !started_near(r, starts, nstarts, s)) {
                best = fmin(best, descend(r, s, q));
                if (nstarts < MAX_STARTS)
                    starts[nstarts++] = s;
            }
        }
    return fmin(sqrt(best), axes_dist(r, q));
}
