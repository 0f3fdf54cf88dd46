/* curve_jet.c — Newton's corrector onto a singular curve within a plane, and the frame of a
 * curve point (tangent, normal plane, normal-plane Hessian) from the Hessian's eigenvectors.
 * See curve_jet.h. */
#include "core/singular/curve_jet.h"

#include <string.h>
#include "core/util/sym3.h"
#include "core/singular/search.h"

/* A 2×2 Jacobian whose determinant is below this fraction of its squared norm is singular
 * to working precision (the step would be rounding noise). Near a pinch point the normal
 * Hessian has one eigenvalue → 0 linearly; at 1e-10 × the box diagonal from it the ratio is
 * still ~1e-10, far above this. */
#define CJET_DET_REL 1e-24

/* Near a pinch point two Hessian eigenvalues are small (the tangent's, exactly 0 on the
 * curve, and the one crossing 0); when the larger of them is below this fraction of the
 * Hessian's scale their eigenvectors may mix, so the tangent is taken as the previous
 * tangent projected onto both. 1e-6 is far above the tangent eigenvalue's size at a point
 * within Newton's tolerance (~1e-11 relative), far below a normal eigenvalue a cell away
 * from a pinch. */
#define CJET_MIX_REL 1e-6

static void hess_mul(const double h[6], const double v[3], double out[3])
{
    out[0] = h[0] * v[0] + h[1] * v[1] + h[2] * v[2];
    out[1] = h[1] * v[0] + h[3] * v[1] + h[4] * v[2];
    out[2] = h[2] * v[0] + h[4] * v[1] + h[5] * v[2];
}

double ism_dist_segment(const double p[3], const double a[3], const double b[3], double *u)
{
    double d[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]};
    double w[3] = {p[0] - a[0], p[1] - a[1], p[2] - a[2]};
    double dd = ism_dot3(d, d), s = dd > 0 ? ism_dot3(w, d) / dd : 0.0;
    s = s < 0 ? 0 : s > 1 ? 1 : s;
    if (u)
        *u = s;
    double c[3] = {a[0] + s * d[0], a[1] + s * d[1], a[2] + s * d[2]};
    return ism_dist3(p, c);
}

bool ism_cjet_correct(ism_cjet *j, const double start[3], const double P[2][3],
                      const double E[2][3], double maxmove, int maxit, double out[3],
                      int *iters)
{
    double p[3] = {start[0], start[1], start[2]};
    for (int it = 1; it <= maxit; it++) {
        double g[3], h[6], hp0[3], hp1[3];
        ism_eval_hessian(j->f, j->ws, p[0], p[1], p[2], g, h);
        j->evals++;
        hess_mul(h, P[0], hp0);
        hess_mul(h, P[1], hp1);
        double r0 = ism_dot3(E[0], g), r1 = ism_dot3(E[1], g);
        double a = ism_dot3(E[0], hp0), b = ism_dot3(E[0], hp1);
        double c = ism_dot3(E[1], hp0), d = ism_dot3(E[1], hp1);
        double det = a * d - b * c, norm2 = a * a + b * b + c * c + d * d;
        double u0, u1;
        if (r0 == 0.0 && r1 == 0.0) {
            u0 = u1 = 0.0;
        } else {
            if (!(fabs(det) > CJET_DET_REL * norm2))
                return false; /* singular, or NaN */
            u0 = (-r0 * d + r1 * b) / det;
            u1 = (-r1 * a + r0 * c) / det;
        }
        for (int k = 0; k < 3; k++)
            p[k] += u0 * P[0][k] + u1 * P[1][k];
        if (!(ism_dist3(p, start) <= maxmove))
            return false;
        if (hypot(u0, u1) <= j->tol) {
            memcpy(out, p, sizeof p);
            if (iters)
                *iters = it;
            return true;
        }
    }
    return false;
}

double ism_cjet_normal_dot(const ism_cpoint *a, const ism_cpoint *b)
{
    const double *x = a->hn, *y = b->hn;
    return x[0] * y[0] + x[3] * y[3] + x[5] * y[5] + 2.0 * (x[1] * y[1] + x[2] * y[2] + x[4] * y[4]);
}

void ism_cjet_reverse(ism_cpoint *c)
{
    for (int k = 0; k < 3; k++)
        c->t[k] = -c->t[k];
}

/* The tangent from the Hessian's eigen-decomposition (eigenvalues ascending). */
static void pick_tangent(const double eig[3], double vec[3][3], const double *prev,
                         double t[3])
{
    int i0 = 0, i1 = 1, i2 = 2; /* indices by ascending |eigenvalue| */
    int o[3] = {0, 1, 2};
    for (int a = 0; a < 3; a++)
        for (int b = a; b > 0 && fabs(eig[o[b]]) < fabs(eig[o[b - 1]]); b--) {
            int s = o[b];
            o[b] = o[b - 1];
            o[b - 1] = s;
        }
    i0 = o[0], i1 = o[1], i2 = o[2];
    memcpy(t, vec[i0], 3 * sizeof *t);
    if (!prev)
        return;
    double c0 = ism_dot3(prev, vec[i0]), c1 = ism_dot3(prev, vec[i1]);
    bool mixed = fabs(eig[i1]) <= CJET_MIX_REL * fabs(eig[i2]) || fabs(c0) < fabs(c1);
    if (mixed) {
        double m[3], l;
        for (int k = 0; k < 3; k++)
            m[k] = c0 * vec[i0][k] + c1 * vec[i1][k];
        l = sqrt(ism_dot3(m, m));
        if (l > 0.5) /* prev lies (nearly) in their span: continue it */
            for (int k = 0; k < 3; k++)
                t[k] = m[k] / l;
    }
    if (ism_dot3(t, prev) < 0)
        for (int k = 0; k < 3; k++)
            t[k] = -t[k];
}

void ism_cjet_frame(ism_cjet *j, const double p[3], const double *prev_t, ism_cpoint *out)
{
    double g[3], h[6], vec[3][3];
    memcpy(out->p, p, sizeof out->p);
    out->f = ism_eval_hessian(j->f, j->ws, p[0], p[1], p[2], g, h);
    j->evals++;
    out->grad = sqrt(ism_dot3(g, g));
    ism_sym3_eigen(h, out->eig, vec);
    out->hnorm = fmax(fabs(out->eig[0]), fabs(out->eig[2]));
    pick_tangent(out->eig, vec, prev_t, out->t);
    ism_across_least3(out->t, out->n);
    double h0[3], h1[3];
    hess_mul(h, out->n[0], h0);
    hess_mul(h, out->n[1], h1);
    double a = ism_dot3(out->n[0], h0), b = ism_dot3(out->n[0], h1);
    double d = ism_dot3(out->n[1], h1);
    out->D = a * d - b * b;
    /* (I − ttᵀ) H (I − ttᵀ) = H − t uᵀ − u tᵀ + (tᵀHt) t tᵀ with u = Ht */
    double u[3], tht;
    hess_mul(h, out->t, u);
    tht = ism_dot3(out->t, u);
    static const int row[6] = {0, 0, 0, 1, 1, 2}, col[6] = {0, 1, 2, 1, 2, 2};
    for (int e = 0; e < 6; e++) {
        int i = row[e], k = col[e];
        out->hn[e] = h[e] - out->t[i] * u[k] - u[i] * out->t[k] + tht * out->t[i] * out->t[k];
    }
    out->sigma = 0.5 * fabs(a + d) + sqrt(0.25 * (a - d) * (a - d) + b * b);
}

/* A seed's curve is on the zero set when |f| ≤ this × Hessian scale × diagonal²: f is
 * constant along a curve of critical points, and a critical curve at that level lies within
 * ~√(2·1e-14) ≈ 1.4e-7 × diagonal of the surface — below any mesh's resolution, while
 * rounding of f is ~1e-16 of its terms. */
#define CJET_SEED_F_REL 1e-14

/* A seed must show the Hessian's rank 2: its smaller eigenvalue across the curve at least
 * this fraction of the larger. Rank 1 is a double sheet (f = g²: a plane of null
 * directions, no curve to follow) or a pinch point (seeds a little off it serve). */
#define CJET_SEED_RANK_REL 1e-6

bool ism_cjet_seed_ok(const ism_cpoint *s, double hessian_scale, double diag,
                      double rank_margin)
{
    double fscale = s->hnorm * diag * diag;
    double zero = ISM_SING_HZERO_REL * hessian_scale; /* both eigenvalues across */
    return s->sigma > zero && fabs(s->D) > zero * s->sigma &&
           fabs(s->D) >= rank_margin * CJET_SEED_RANK_REL * s->sigma * s->sigma &&
           fabs(s->f) <= CJET_SEED_F_REL * fscale &&
           s->grad <= ISM_CURVE_GRAD_REL * s->hnorm * diag;
}
