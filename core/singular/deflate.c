/* deflate.c — Krawczyk on the deflated system of a rank-2 singular point (deflate.h).
 * Unknowns z = (x0 x1 x2, v0 v1 v2, ε), equations G = (∇f(x) − ε n, H(x) v, nᵀv − 1);
 *
 *     K(Z) = z_c − Y G(z_c) + (I − Y J(Z)) (Z − z_c),   Y = mid(J(Z))⁻¹,
 *
 * with z_c = (p, n, 0) and J(Z) = [[H(X), 0, −n], [Σ_k V_k T_k(X), H(X), 0], [0, nᵀ, 0]],
 * T_k(X) the interval Hessian of ∂f/∂x_k: (T_k)_ij = ∂³f/∂x_i∂x_j∂x_k. K ⊂ int Z proves one
 * zero of G in Z. All interval arithmetic is outward rounded (core/eval/interval_ops.h). */
#include "core/singular/deflate.h"
#include "core/eval/interval_jet.h"
#include "core/eval/interval_ops.h"
#include "core/eval/tape_partial.h"

#include <stdlib.h>
#include <string.h>

#define N 7
/* D³f(n, n, n) at most this × the largest third derivative at p counts as 0: the point is an
 * A3 (or worse) singularity, and the deflated Jacobian is as singular as the Hessian was.
 * Not rounding-sized: such a point is only located to ~(rounding of ∇f)^(1/3) (the horn
 * cyclide's to ~1e-6 of its box), where the cubic term is that small but not 0; a cusp's
 * cubic term is of the size of f's other third derivatives (x² + z² − y³: all of them). */
#define DEFLATE_CUBIC_REL 1e-3

struct ism_deflate_ws {
    const ism_tape *f;
    ism_tape *df[3];
    ism_ivjet_ws *jw[4]; /* f's, then each partial's */
};

static const int SYM[3][3] = { { 0, 1, 2 }, { 1, 3, 4 }, { 2, 4, 5 } };

ism_deflate_ws *ism_deflate_ws_new(const ism_tape *f)
{
    ism_deflate_ws *w = calloc(1, sizeof *w);
    if (!w)
        return NULL;
    w->f = f;
    bool ok = (w->jw[0] = ism_ivjet_ws_new(f)) != NULL;
    for (int k = 0; ok && k < 3; k++)
        ok = (w->df[k] = ism_tape_partial(f, k)) && (w->jw[k + 1] = ism_ivjet_ws_new(w->df[k]));
    if (!ok) {
        ism_deflate_ws_free(w);
        return NULL;
    }
    return w;
}

void ism_deflate_ws_free(ism_deflate_ws *w)
{
    if (!w)
        return;
    for (int k = 0; k < 4; k++)
        ism_ivjet_ws_free(w->jw[k]);
    for (int k = 0; k < 3; k++)
        ism_tape_free(w->df[k]);
    free(w);
}

/* f's jet and the third derivatives T_k (k = 0..2) over the box x. */
static void jets(ism_deflate_ws *w, const ism_interval x[3], ism_ivjet *jf, ism_interval t[3][6],
                 uint64_t *evals)
{
    ism_eval_interval_jet(w->f, w->jw[0], x, NULL, NULL, jf);
    for (int k = 0; k < 3; k++) {
        ism_ivjet jk;
        ism_eval_interval_jet(w->df[k], w->jw[k + 1], x, NULL, NULL, &jk);
        memcpy(t[k], jk.h, sizeof t[k]);
    }
    if (evals)
        *evals += 4;
}

static double mid(ism_interval a) { return 0.5 * a.lo + 0.5 * a.hi; }

/* y = m⁻¹ by Gauss–Jordan with partial pivoting; false when singular or not finite. */
static bool invert(double m[N][N], double y[N][N])
{
    for (int i = 0; i < N; i++)
        for (int j = 0; j < N; j++)
            y[i][j] = i == j;
    for (int c = 0; c < N; c++) {
        int piv = c;
        for (int r = c + 1; r < N; r++)
            if (fabs(m[r][c]) > fabs(m[piv][c]))
                piv = r;
        if (!(fabs(m[piv][c]) > 0.0) || !isfinite(m[piv][c]))
            return false;
        for (int j = 0; j < N; j++) {
            double t = m[c][j]; m[c][j] = m[piv][j]; m[piv][j] = t;
            t = y[c][j]; y[c][j] = y[piv][j]; y[piv][j] = t;
        }
        double inv = 1.0 / m[c][c];
        for (int j = 0; j < N; j++)
            m[c][j] *= inv, y[c][j] *= inv;
        for (int r = 0; r < N; r++) {
            if (r == c || m[r][c] == 0.0)
                continue;
            double s = m[r][c];
            for (int j = 0; j < N; j++)
                m[r][j] -= s * m[c][j], y[r][j] -= s * y[c][j];
        }
    }
    for (int i = 0; i < N; i++)
        for (int j = 0; j < N; j++)
            if (!isfinite(y[i][j]))
                return false;
    return true;
}

/* J(Z) for the x box (jets jf, t) and the v box v. */
static void jacobian(const ism_ivjet *jf, ism_interval t[3][6], const ism_interval v[3],
                     const double n[3], ism_interval J[N][N])
{
    for (int i = 0; i < N; i++)
        for (int j = 0; j < N; j++)
            J[i][j] = iv(0.0, 0.0);
    for (int i = 0; i < 3; i++) {
        for (int j = 0; j < 3; j++) {
            J[i][j] = jf->h[SYM[i][j]];
            J[3 + i][3 + j] = jf->h[SYM[i][j]];
            ism_interval d = iv(0.0, 0.0);
            for (int k = 0; k < 3; k++)
                d = iv_add(d, iv_mul(v[k], t[k][SYM[i][j]]));
            J[3 + i][j] = d;
        }
        J[i][6] = iv(-n[i], -n[i]);
        J[6][3 + i] = iv(n[i], n[i]);
    }
}

/* G(z_c) with z_c = (p, n, 0): from the jets at the point box [p, p]. */
static void residual(const ism_ivjet *jp, const double n[3], ism_interval g[N])
{
    ism_interval nn = iv(-1.0, -1.0);
    for (int i = 0; i < 3; i++) {
        g[i] = jp->d[i];
        ism_interval hv = iv(0.0, 0.0);
        for (int k = 0; k < 3; k++)
            hv = iv_add(hv, iv_mul_c(jp->h[SYM[i][k]], n[k]));
        g[3 + i] = hv;
        nn = iv_add(nn, iv_mul_c(iv(n[i], n[i]), n[i]));
    }
    g[6] = nn;
}

/* One Krawczyk test on Z (centre zc); true when K ⊂ int Z (k receives K). */
static bool krawczyk7(ism_interval J[N][N], const ism_interval g[N], const double zc[N],
                      const ism_interval z[N], ism_interval k[N])
{
    double m[N][N], y[N][N];
    for (int i = 0; i < N; i++)
        for (int j = 0; j < N; j++)
            m[i][j] = mid(J[i][j]);
    if (!invert(m, y))
        return false;
    bool inner = true;
    for (int i = 0; i < N; i++) {
        ism_interval acc = iv(zc[i], zc[i]);
        for (int q = 0; q < N; q++)
            acc = iv_sub(acc, iv_mul_c(g[q], y[i][q]));
        for (int j = 0; j < N; j++) {
            ism_interval e = iv(i == j ? 1.0 : 0.0, i == j ? 1.0 : 0.0);
            for (int q = 0; q < N; q++)
                e = iv_sub(e, iv_mul_c(J[q][j], y[i][q]));
            acc = iv_add(acc, iv_mul(ism_iv_sane(e), iv_sub(z[j], iv(zc[j], zc[j]))));
        }
        k[i] = ism_iv_sane(acc);
        inner = inner && k[i].lo > z[i].lo && k[i].hi < z[i].hi;
    }
    return inner;
}

static double mag(ism_interval a) { return fmax(fabs(a.lo), fabs(a.hi)); }

/* The scales at p (jets jp, third derivatives tp): the Hessian's and the third derivatives'
 * largest entries, and whether the cubic term along n stands above DEFLATE_CUBIC_REL. */
static bool cubic_at(const ism_ivjet *jp, ism_interval tp[3][6], const double n[3], double *h2,
                     double *t3)
{
    double cubic = 0.0;
    *h2 = *t3 = 0.0;
    for (int e = 0; e < 6; e++) {
        *h2 = fmax(*h2, mag(jp->h[e]));
        for (int k = 0; k < 3; k++)
            *t3 = fmax(*t3, mag(tp[k][e]));
    }
    for (int k = 0; k < 3; k++)
        for (int i = 0; i < 3; i++)
            for (int j = 0; j < 3; j++)
                cubic += n[k] * n[i] * n[j] * mid(tp[k][SYM[i][j]]);
    return *t3 > 0.0 && fabs(cubic) > DEFLATE_CUBIC_REL * *t3 && isfinite(cubic);
}

int ism_deflate_certify(ism_deflate_ws *w, const double p[3], const double n[3],
                        double r_first, double r_max, double growth, ism_deflate_result *out,
                        uint64_t *evals)
{
    ism_interval xp[3], tp[3][6];
    ism_ivjet jp;
    for (int k = 0; k < 3; k++)
        xp[k] = iv(p[k], p[k]);
    jets(w, xp, &jp, tp, evals);
    double h2, t3;
    if (!cubic_at(&jp, tp, n, &h2, &t3))
        return ISM_DEFLATE_SINGULAR;
    ism_interval g[N];
    residual(&jp, n, g);
    double zc[N] = { p[0], p[1], p[2], n[0], n[1], n[2], 0.0 };
    for (double r = r_first; r <= r_max * (1.0 + 1e-12); r *= growth) {
        /* v moves ~ (third / second derivative) × the move of x; ε ~ Hessian × it */
        double rv = r * fmax(1.0, t3 / fmax(h2, 1e-300)), re = r * fmax(h2, t3 * r);
        ism_interval z[N], x[3], v[3], J[N][N], k[N];
        for (int i = 0; i < N; i++) {
            double rad = i < 3 ? r : i < 6 ? rv : re;
            z[i] = iv(down1(zc[i] - rad), up1(zc[i] + rad));
        }
        memcpy(x, z, sizeof x);
        memcpy(v, z + 3, sizeof v);
        ism_ivjet jf;
        ism_interval t[3][6];
        jets(w, x, &jf, t, evals);
        jacobian(&jf, t, v, n, J);
        if (krawczyk7(J, g, zc, z, k)) {
            out->radius = r;
            out->f = jf.v;
            out->eps = mag(k[6]);
            return ISM_DEFLATE_CERTIFIED;
        }
    }
    return ISM_DEFLATE_FAILED;
}
