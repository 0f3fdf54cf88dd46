/* critical.c — Newton on the Lagrange system of g_k restricted to f = 0 (and g_j = 0):
 * unknowns p and one multiplier λ_i per constraint c_i, equations ∇g_k − Σ λ_i ∇c_i = 0 and
 * c_i = 0 (4 × 4 or 5 × 5). Its Jacobian is the bordered Hessian [[H_g − Σ λ_i H_ci, −∇c],
 * [∇cᵀ, 0]], regular at a non-degenerate critical point (a saddle of g on f = 0: a node of
 * the curve; a simple tangency of two curves), so Newton converges quadratically. */
#include "core/curves/critical.h"
#include "core/util/vec3.h"
#include <math.h>
#include <string.h>

/* Newton steps before giving up (a start within a cell converges in a handful). */
#define CRIT_NEWTON_ITERS 40
/* A pivot below this × the largest entry of its column makes the system singular (a
 * degenerate critical point: no isolated tangency to certify). */
#define CRIT_SINGULAR_REL 1e-13

typedef struct lagrange {
    int m;           /* constraints: 1 (f) or 2 (f, g_j) */
    double r[5];     /* residual */
    double J[5][5];  /* Jacobian */
    double cdist;    /* worst |c_i| / |∇c_i| */
    double gdist;    /* |g_k| / |∇g_k| */
} lagrange;

static void hess_full(const double h[6], double H[3][3])
{
    const double m[3][3] = {{h[0], h[1], h[2]}, {h[1], h[3], h[4]}, {h[2], h[4], h[5]}};
    memcpy(H, m, sizeof m);
}

/* Residual and Jacobian at x = (p, λ). */
static void system_at(ism_cut_eval *ev, size_t k, size_t j, double h, const double *x,
                      lagrange *L)
{
    double cv[2], cg[2][3], ch[2][6], gg[3], gh[6];
    cv[0] = ism_eval_hessian(ev->f, ev->fws, x[0], x[1], x[2], cg[0], ch[0]);
    if (L->m == 2)
        cv[1] = ism_cut_g_hessian(ev, j, x, h, cg[1], ch[1]);
    double gv = ism_cut_g_hessian(ev, k, x, h, gg, gh);
    double H[3][3];
    hess_full(gh, H);
    L->cdist = 0;
    for (int i = 0; i < L->m; i++) {
        double Hc[3][3], n = ism_norm3(cg[i]), lam = x[3 + i];
        hess_full(ch[i], Hc);
        for (int a = 0; a < 3; a++)
            for (int b = 0; b < 3; b++)
                H[a][b] -= lam * Hc[a][b];
        double d = n > 0 ? fabs(cv[i]) / n : INFINITY;
        L->cdist = d > L->cdist ? d : L->cdist;
    }
    double ng = ism_norm3(gg);
    L->gdist = ng > 0 ? fabs(gv) / ng : INFINITY;
    memset(L->J, 0, sizeof L->J);
    for (int a = 0; a < 3; a++) {
        L->r[a] = gg[a];
        for (int i = 0; i < L->m; i++) {
            L->r[a] -= x[3 + i] * cg[i][a];
            L->J[a][3 + i] = -cg[i][a];
            L->J[3 + i][a] = cg[i][a];
        }
        for (int b = 0; b < 3; b++)
            L->J[a][b] = H[a][b];
    }
    for (int i = 0; i < L->m; i++)
        L->r[3 + i] = cv[i];
}

/* Solves the n × n system A y = b by elimination with partial pivoting (A, b overwritten).
 * False when a pivot is negligible. */
static bool solve(int n, double A[5][5], double b[5], double y[5])
{
    for (int c = 0; c < n; c++) {
        int piv = c;
        double big = 0;
        for (int r = c; r < n; r++) {
            big = fmax(big, fabs(A[r][c]));
            if (fabs(A[r][c]) > fabs(A[piv][c]))
                piv = r;
        }
        if (!(fabs(A[piv][c]) > CRIT_SINGULAR_REL * big) || big == 0)
            return false;
        if (piv != c) {
            for (int k = 0; k < n; k++) {
                double t = A[c][k];
                A[c][k] = A[piv][k];
                A[piv][k] = t;
            }
            double t = b[c];
            b[c] = b[piv];
            b[piv] = t;
        }
        for (int r = c + 1; r < n; r++) {
            double q = A[r][c] / A[c][c];
            for (int k = c; k < n; k++)
                A[r][k] -= q * A[c][k];
            b[r] -= q * b[c];
        }
    }
    for (int r = n - 1; r >= 0; r--) {
        double s = b[r];
        for (int k = r + 1; k < n; k++)
            s -= A[r][k] * y[k];
        y[r] = s / A[r][r];
    }
    return true;
}

/* The multipliers that best fit ∇g_k = Σ λ_i ∇c_i at p (least squares): Newton's start. */
static bool start_multipliers(ism_cut_eval *ev, size_t k, size_t j, int m, double *x)
{
    double cg[2][3], gg[3];
    ism_eval_gradient(ev->f, ev->fws, x[0], x[1], x[2], cg[0]);
    if (m == 2)
        ism_cut_g(ev, j, x, cg[1]);
    ism_cut_g(ev, k, x, gg);
    double A[5][5] = {{0}}, b[5] = {0}, y[5];
    for (int a = 0; a < m; a++) {
        for (int c = 0; c < m; c++)
            for (int i = 0; i < 3; i++)
                A[a][c] += cg[a][i] * cg[c][i];
        for (int i = 0; i < 3; i++)
            b[a] += cg[a][i] * gg[i];
    }
    if (!solve(m, A, b, y))
        return false;
    for (int i = 0; i < m; i++)
        x[3 + i] = y[i];
    return true;
}

bool ism_cut_critical(ism_cut_eval *ev, size_t k, size_t j, double tol, double max_move,
                      double h, double p[3], double *dist)
{
    lagrange L = {.m = j == ISM_CUT_NO_CURVE ? 1 : 2};
    int n = 3 + L.m;
    double x[5] = {p[0], p[1], p[2], 0, 0};
    if (!start_multipliers(ev, k, j, L.m, x))
        return false;
    for (int it = 0; it < CRIT_NEWTON_ITERS; it++) {
        system_at(ev, k, j, h, x, &L);
        double b[5], y[5];
        for (int i = 0; i < n; i++)
            b[i] = -L.r[i];
        if (!solve(n, L.J, b, y))
            return false;
        for (int i = 0; i < n; i++)
            x[i] += y[i];
        double d[3] = {x[0] - p[0], x[1] - p[1], x[2] - p[2]};
        if (!isfinite(x[0] + x[1] + x[2]) || ism_norm3(d) > max_move)
            return false;
        if (ism_norm3(y) <= tol && L.cdist <= tol) {
            system_at(ev, k, j, h, x, &L); /* the distances at the final point */
            if (!(L.cdist <= tol))
                return false;
            memcpy(p, x, 3 * sizeof *p);
            *dist = L.gdist;
            return true;
        }
    }
    return false;
}
