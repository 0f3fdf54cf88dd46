/* deflate.c — Krawczyk on the deflated system of a rank-2 singular point (deflate.h).
 * Unknowns z = (x0 x1 x2, v0 v1 v2, ε), equations G = (∇f(x) − ε n, H(x) v, nᵀv − 1);
 *
 *     K(Z) = z_c − Y G(z_c) + (I − Y J(Z)) (Z − z_c),   Y = mid(J(Z))⁻¹,
 *
 * with z_c = (p, n, 0) and J(Z) = [[H(X), 0, −n], [Σ_k V_k T_k(X), H(X), 0], [0, nᵀ, 0]],
 * T_k(X) the interval Hessian of ∂f/∂x_k: (T_k)_ij = ∂³f/∂x_i∂x_j∂x_k. K ⊂ int Z proves one
 * zero of G in Z. All interval arithmetic is outward rounded (core/eval/interval_ops.h). */
#include "core/singular/deflate.h"
#include "core/singular/jet4.h"
#include "core/singular/overdet.h"
#include "core/eval/interval_ops.h"

#include <string.h>

#define N 7
/* D³f(n, n, n) at most this × the largest third derivative at p counts as 0: the point is an
 * A3 (or worse) singularity, and the deflated Jacobian is as singular as the Hessian was.
 * Not rounding-sized: such a point is only located to ~(rounding of ∇f)^(1/3) (the horn
 * cyclide's to ~1e-6 of its box), where the cubic term is that small but not 0; a cusp's
 * cubic term is of the size of f's other third derivatives (x² + z² − y³: all of it). */
#define DEFLATE_CUBIC_REL 1e-3

/* J(Z) for the x box (jet j) and the v box v. */
static void jacobian(const ism_jet4 *j, const ism_interval v[3], const double n[3],
                     ism_interval J[N][ISM_OD_MAXK])
{
    for (int i = 0; i < N; i++)
        for (int c = 0; c < N; c++)
            J[i][c] = iv(0.0, 0.0);
    for (int i = 0; i < 3; i++) {
        for (int c = 0; c < 3; c++) {
            J[i][c] = j->h[i][c];
            J[3 + i][3 + c] = j->h[i][c];
            ism_interval d = iv(0.0, 0.0);
            for (int k = 0; k < 3; k++)
                d = iv_add(d, iv_mul(v[k], j->t[i][c][k]));
            J[3 + i][c] = d;
        }
        J[i][6] = iv(-n[i], -n[i]);
        J[6][3 + i] = iv(n[i], n[i]);
    }
}

/* G(z_c) with z_c = (p, n, 0): from the jet at the point box [p, p]. */
static void residual(const ism_jet4 *jp, const double n[3], ism_interval g[N])
{
    ism_interval nn = iv(-1.0, -1.0);
    for (int i = 0; i < 3; i++) {
        g[i] = jp->d[i];
        ism_interval hv = iv(0.0, 0.0);
        for (int k = 0; k < 3; k++)
            hv = iv_add(hv, iv_mul_c(jp->h[i][k], n[k]));
        g[3 + i] = hv;
        nn = iv_add(nn, iv_mul_c(iv(n[i], n[i]), n[i]));
    }
    g[6] = nn;
}

static double mid(ism_interval a) { return 0.5 * a.lo + 0.5 * a.hi; }
static double mag(ism_interval a) { return fmax(fabs(a.lo), fabs(a.hi)); }

/* The scales at p (jets jp, third derivatives tp): the Hessian's and the third derivatives'
 * largest entries, and whether the cubic term along n stands above DEFLATE_CUBIC_REL. */
static bool cubic_at(const ism_jet4 *jp, const double n[3], double *h2, double *t3)
{
    double cubic = 0.0;
    *h2 = *t3 = 0.0;
    for (int i = 0; i < 3; i++)
        for (int j = 0; j < 3; j++) {
            *h2 = fmax(*h2, mag(jp->h[i][j]));
            for (int k = 0; k < 3; k++) {
                *t3 = fmax(*t3, mag(jp->t[i][j][k]));
                cubic += n[k] * n[i] * n[j] * mid(jp->t[i][j][k]);
            }
        }
    return *t3 > 0.0 && fabs(cubic) > DEFLATE_CUBIC_REL * *t3 && isfinite(cubic);
}

int ism_deflate_certify(ism_jet4_ws *w, const double p[3], const double n[3],
                        double r_first, double r_max, double growth, ism_deflate_result *out,
                        uint64_t *evals)
{
    ism_interval xp[3];
    ism_jet4 jp;
    for (int k = 0; k < 3; k++)
        xp[k] = iv(p[k], p[k]);
    ism_jet4_eval(w, xp, &jp, evals);
    double h2, t3;
    if (!cubic_at(&jp, n, &h2, &t3))
        return ISM_DEFLATE_SINGULAR;
    ism_interval g[N];
    residual(&jp, n, g);
    double zc[N] = { p[0], p[1], p[2], n[0], n[1], n[2], 0.0 };
    for (double r = r_first; r <= r_max * (1.0 + 1e-12); r *= growth) {
        /* v moves ~ (third / second derivative) × the move of x; ε ~ Hessian × it */
        double rv = r * fmax(1.0, t3 / fmax(h2, 1e-300)), re = r * fmax(h2, t3 * r);
        ism_interval z[N], x[3], v[3], J[N][ISM_OD_MAXK], k[N];
        for (int i = 0; i < N; i++) {
            double rad = i < 3 ? r : i < 6 ? rv : re;
            z[i] = iv(down1(zc[i] - rad), up1(zc[i] + rad));
        }
        memcpy(x, z, sizeof x);
        memcpy(v, z + 3, sizeof v);
        ism_jet4 jf;
        ism_jet4_eval(w, x, &jf, evals);
        jacobian(&jf, v, n, J);
        if (ism_od_krawczyk(N, N, J, g, zc, z, k)) {
            out->radius = r;
            out->f = jf.v;
            out->eps = mag(k[6]);
            return ISM_DEFLATE_CERTIFIED;
        }
    }
    return ISM_DEFLATE_FAILED;
}
