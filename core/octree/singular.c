/* singular.c — Newton's method on ∇f = 0 (with the Hessian from the tape) to find an
 * isolated singular point of f = 0 inside a node, and the tests that accept it: inside the
 * node, on the surface, Hessian non-degenerate and indefinite. A double line (Steiner's
 * axes, the Klein bottle's self-intersection) has a degenerate Hessian and is left to the
 * face-line machinery. */
#include "core/octree/singular.h"

#include <math.h>
#include <string.h>

#define NEWTON_STEPS 12

/* hess = xx xy xz yy yz zz */
static void full(const double h[6], double m[3][3])
{
    m[0][0] = h[0], m[0][1] = m[1][0] = h[1], m[0][2] = m[2][0] = h[2];
    m[1][1] = h[3], m[1][2] = m[2][1] = h[4], m[2][2] = h[5];
}

static double det3(double m[3][3])
{
    return m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1]) -
           m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0]) +
           m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0]);
}

static double frobenius(double m[3][3])
{
    double s = 0;
    for (int i = 0; i < 3; i++)
        for (int j = 0; j < 3; j++)
            s += m[i][j] * m[i][j];
    return sqrt(s);
}

/* Solves m d = r by Cramer's rule (m known to be well conditioned by the caller). */
static void solve3(double m[3][3], const double r[3], double d[3])
{
    double det = det3(m);
    for (int k = 0; k < 3; k++) {
        double c[3][3];
        memcpy(c, m, sizeof c);
        for (int i = 0; i < 3; i++)
            c[i][k] = r[i];
        d[k] = det3(c) / det;
    }
}

/* Indefinite: the quadratic form takes both signs (a cone, not an isolated point). With a
 * non-zero determinant this holds unless all three eigenvalues share a sign, i.e. unless
 * the leading minors are all positive or alternate starting negative. */
static bool indefinite(double m[3][3])
{
    double d1 = m[0][0], d2 = m[0][0] * m[1][1] - m[0][1] * m[1][0], d3 = det3(m);
    bool positive = d1 > 0 && d2 > 0 && d3 > 0;
    bool negative = d1 < 0 && d2 > 0 && d3 < 0;
    return !positive && !negative;
}

/* A cone's Hessian: non-degenerate and indefinite (relative to its own size). */
static bool cone_hessian(double m[3][3], double hn)
{
    return hn > 0 && isfinite(hn) && fabs(det3(m)) >= 1e-3 * hn * hn * hn && indefinite(m);
}

/* Is p, with f, ∇f and Hessian m there, a singular point of the surface: on it, gradient
 * vanishing, Hessian non-degenerate and indefinite (relative to the Hessian's size and the
 * node size)? */
static bool is_singular(double f, const double g[3], double m[3][3], double hn, double size)
{
    return fabs(f) <= 1e-8 * hn * size * size && ism_norm3(g) <= 1e-6 * hn * size &&
           cone_hessian(m, hn);
}

static void singular_point(const double p[3], ism_fpoint *s)
{
    memcpy(s->p, p, sizeof s->p);
    memset(s->g, 0, sizeof s->g);
    s->flags = ISM_FP_INTERIOR | ISM_FP_SINGULAR;
}

/* f, ∇f and the Hessian at p, with the Hessian's size. */
static double jet_at(ism_sampler *smp, const double p[3], double g[3], double m[3][3],
                     double *hn)
{
    double h[6];
    smp->n_gradient++;
    double f = ism_eval_hessian(smp->tape, smp->ws, p[0], p[1], p[2], g, h);
    full(h, m);
    *hn = frobenius(m);
    return f;
}

/* Accepts p as a singular point (see is_singular). */
static bool accept(ism_sampler *smp, const double p[3], double size, ism_fpoint *s)
{
    double g[3], m[3][3], hn;
    double f = jet_at(smp, p, g, m, &hn);
    if (!is_singular(f, g, m, hn, size))
        return false;
    singular_point(p, s);
    return true;
}

bool ism_find_singular_point(ism_sampler *smp, const double lo[3], const double hi[3],
                             ism_fpoint *s)
{
    double p[3], size = INFINITY;
    for (int k = 0; k < 3; k++) {
        p[k] = 0.5 * (lo[k] + hi[k]);
        if (hi[k] - lo[k] < size)
            size = hi[k] - lo[k];
    }
    double g[3], h[6], m[3][3];
    for (int it = 0; it < NEWTON_STEPS; it++) {
        smp->n_gradient++;
        ism_eval_hessian(smp->tape, smp->ws, p[0], p[1], p[2], g, h);
        full(h, m);
        double hn = frobenius(m);
        if (!(hn > 0) || !isfinite(hn) || fabs(det3(m)) < 1e-3 * hn * hn * hn)
            return false; /* degenerate: a double line, a ridge, or no singularity at all */
        double step[3], minus_g[3] = {-g[0], -g[1], -g[2]};
        solve3(m, minus_g, step);
        for (int k = 0; k < 3; k++) {
            p[k] += step[k];
            if (!(p[k] > lo[k] - size && p[k] < hi[k] + size))
                return false;
        }
        if (ism_norm3(step) < 1e-14 * size)
            break;
    }
    double margin = 1e-9 * size;
    for (int k = 0; k < 3; k++)
        if (!(p[k] > lo[k] + margin && p[k] < hi[k] - margin))
            return false; /* on or outside the boundary: the neighbours could not agree */
    return accept(smp, p, size, s);
}

/* Newton on the in-plane gradient from start, keeping p[axis]; true when it converges
 * strictly inside the rectangle lo..hi. *size is the rectangle's smaller side. */
static bool plane_critical_point(ism_sampler *smp, int axis, const double start[3],
                                 const double lo[2], const double hi[2], double p[3],
                                 double *size)
{
    int u = (axis + 1) % 3, v = (axis + 2) % 3;
    memcpy(p, start, 3 * sizeof *p);
    *size = hi[0] - lo[0] < hi[1] - lo[1] ? hi[0] - lo[0] : hi[1] - lo[1];
    double g[3], h[6], m[3][3];
    for (int it = 0; it < NEWTON_STEPS; it++) {
        smp->n_gradient++;
        ism_eval_hessian(smp->tape, smp->ws, p[0], p[1], p[2], g, h);
        full(h, m);
        double a = m[u][u], b = m[u][v], d = m[v][v];
        double det = a * d - b * b, scale = fabs(a) + fabs(b) + fabs(d);
        if (!(scale > 0) || !isfinite(det) || fabs(det) < 1e-6 * scale * scale)
            return false;
        double su = -(d * g[u] - b * g[v]) / det, sv = -(a * g[v] - b * g[u]) / det;
        p[u] += su;
        p[v] += sv;
        if (!(p[u] > lo[0] - *size && p[u] < hi[0] + *size && p[v] > lo[1] - *size &&
              p[v] < hi[1] + *size))
            return false;
        if (fabs(su) + fabs(sv) < 1e-14 * *size)
            break;
    }
    double margin = 1e-9 * *size;
    return p[u] > lo[0] + margin && p[u] < hi[0] - margin && p[v] > lo[1] + margin &&
           p[v] < hi[1] - margin;
}

int ism_plane_crossing(ism_sampler *smp, int axis, const double start[3], const double lo[2],
                       const double hi[2], ism_fpoint *s)
{
    double p[3], size, g[3], m[3][3], hn;
    if (!plane_critical_point(smp, axis, start, lo, hi, p, &size))
        return 0;
    double f = jet_at(smp, p, g, m, &hn);
    if (is_singular(f, g, m, hn, size)) {
        singular_point(p, s);
        return ISM_PLANE_APEX;
    }
    if (!cone_hessian(m, hn) || !(fabs(f) > 1e-8 * hn * size * size) || !isfinite(f))
        return 0; /* a double line crossing the plane (degenerate Hessian), or no cone */
    return f > 0 ? 1 : -1;
}
