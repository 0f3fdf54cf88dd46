/* typecert.c — the defining systems of degenerate singular points and their certificate
 * (typecert.h). Notation: H = D²f, T = D³f, Q = D⁴f at x; a system's Jacobian J must have
 * full column rank at the point for Krawczyk on P G to contract (overdet.h).
 *
 *   type         example            system G (unknowns)                   J full rank iff
 *   ───────────  ─────────────────  ────────────────────────────────────  ─────────────────
 *   rank 0       xyz, Steiner's 0   ∇f, H                (x)      9 × 3   dx ↦ T[dx] is 1-1
 *   rank 1       x² − zy² (pinch)   ∇f, h_ee H_NN − b bᵀ (x)      6 × 3   T[dx]|_NN rank 2
 *   A3           horn cyclide       ∇f, Hv, nᵀv − 1, T[v,v,v]     8 × 6   q₄ ≠ 0
 *                                                        (x, v)
 * rank 0: J = [H; T[·]] and H = 0, so J is the map dx ↦ T[dx] (the Hessian of f's cubic
 *   term along dx): 1-1 for three sheets meeting transversally (cubic ℓ₁ℓ₂ℓ₃: xyz ↦
 *   [[0,dz,dy],[dz,0,dx],[dy,dx,0]]) and at the cross-cap's (0, 0, −1) (cubic −w(4x² + 2y²)).
 * rank 1: in a fixed orthonormal frame (e, N = n₁ n₂) with h_ee = eᵀHe ≠ 0 and b = H_Ne,
 *   rank H ≤ 1 ⇔ the Schur complement h_ee H_NN − b bᵀ = 0 (3 equations, any such frame).
 *   Whitney u² − vw²: rows ∇f → du; S_vw = −4w·h.., S_ww ∝ v → dv, dw: rank 3.
 * A3: a null vector (dx, dv) of J has H dx = 0 → dx = a n; then H dv = −a T[n,n,·] and
 *   nᵀdv = 0 give dv = −a H⁺T[n,n,·]; the last row leaves a·q₄ = 0 with
 *       q₄ = Q[n,n,n,n] − 3 T[n,n,·]ᵀ H⁺ T[n,n,·],
 *   24 × the quartic coefficient of f along its critical curve. Horn cyclide at (10, 0, 0):
 *   f ≈ 384u² + 384z² + 40uy² + y⁴, q₄/24 = 1 − 40²/(4·384) = −1/24 ≠ 0.
 *
 * Not certifiable, and why (reported as such, points.c):
 *   contact   (two spheres touching, (x² + y² + z²)² − 4x²: H = diag(−8, 0, 0), T = 0):
 *             the rank-1 system is singular — the two sheets also meet in the complex lines
 *             y = ±iz, along which ∇f = 0 and the rank conditions vanish to second order, so
 *             J kills their (complex, hence two real) tangents. Nor can double precision
 *             place such a point to 1e-9: ∇f is cubic across it, so its rounding (~1e-16 of
 *             f's terms) hides it within ~(1e-16)^(1/3) ≈ 5e-6 of f's scale.
 *   A4 or worse, and points of curves: the A3 system is singular (q₄ = 0).
 *
 * Procedure: frame (e, N or n) from H at the start; Gauss–Newton z ← z − P G(z) on the
 * point jets until the step stops shrinking; then Krawczyk on X = x ± r (V = v ± r_v) for
 * growing r; the residual is |G| over the contracted K. */
#include "core/singular/typecert.h"
#include "core/singular/overdet.h"
#include "core/eval/interval_ops.h"
#include "core/util/sym3.h"

#include <math.h>
#include <string.h>

/* Gauss–Newton steps at most (quadratic convergence at a regular solution: a dozen reach
 * rounding from a start ~1e-6 off; the rest is slack). */
#define TC_GN_ITERS 40
/* Converged: the x step below this × diagonal — Krawczyk's smallest box is 1e-6 of the
 * 0.5e-9 bound (~5e-16), and the centre must sit well inside it. */
#define TC_GN_TOL 1e-16
/* ... and it counts as converged up to this × diagonal (the rounding floor of a step). */
#define TC_GN_DONE 1e-13
/* Certificate boxes from TC_FIRST × rmax, growing by TC_GROWTH (the smallest that works is
 * the best enclosure), as points.c does for nodes. */
#define TC_FIRST 1e-6
#define TC_GROWTH 10.0
/* A solution of P G = 0 is one of G = 0 only when its residual (typecert.h) is at most this:
 * P G also vanishes at least-squares points of an inconsistent G (a point of a whisker
 * circle solves the rank-1 system only to ~1e-4). The same relative size as the 1e-9
 * position bound; the certified points seen have 1e-14 or less. */
#define TC_RESIDUAL_MAX 1e-9
/* Above this condition of the scaled Jacobian (overdet.h) at the refined point a failed
 * certificate is put down to a singular system rather than to Krawczyk: the regular systems
 * seen stay under ~1e3 (the horn cyclide's A3 system 530), singular ones start at ~2e4. Only
 * the reason reported depends on it, never a certificate. */
#define TC_COND_MAX 1e4

/* A system: its sizes and the frame fixed at the start. */
typedef struct sys {
    int kind, m, k;
    double R[3][3]; /* rank 1: rows e, n₁, n₂ */
    double n[3];    /* A3: the start's null vector */
} sys;

static const ism_interval ZERO = { 0.0, 0.0 };

static double mid(ism_interval a) { return 0.5 * a.lo + 0.5 * a.hi; }
static double mag(ism_interval a) { return fmax(fabs(a.lo), fabs(a.hi)); }
static ism_interval pt(double a) { return iv(a, a); }

/* Σ_ij R_ai R_bj M_ij for an interval matrix M (entries m(i, j) of a 3×3 grid). */
static ism_interval rotate(const double R[3][3], int a, int b, const ism_interval M[3][3])
{
    ism_interval s = ZERO;
    for (int i = 0; i < 3; i++)
        for (int j = 0; j < 3; j++)
            s = iv_add(s, iv_mul_c(M[i][j], R[a][i] * R[b][j]));
    return s;
}

static void rank0(const ism_jet4 *j, ism_interval g[], ism_interval J[][ISM_OD_MAXK])
{
    static const int P[6][2] = { { 0, 0 }, { 0, 1 }, { 0, 2 }, { 1, 1 }, { 1, 2 }, { 2, 2 } };
    for (int i = 0; i < 3; i++) {
        g[i] = j->d[i];
        for (int c = 0; c < 3; c++)
            J[i][c] = j->h[i][c];
    }
    for (int r = 0; r < 6; r++) {
        g[3 + r] = j->h[P[r][0]][P[r][1]];
        for (int c = 0; c < 3; c++)
            J[3 + r][c] = j->t[P[r][0]][P[r][1]][c];
    }
}

static void rank1(const sys *s, const ism_jet4 *j, ism_interval g[], ism_interval J[][ISM_OD_MAXK])
{
    static const int P[3][2] = { { 1, 1 }, { 1, 2 }, { 2, 2 } };
    ism_interval H[3][3], dH[3][3][3], T[3][3]; /* H' and dH'/dx_c in the frame */
    for (int a = 0; a < 3; a++)
        for (int b = 0; b < 3; b++)
            H[a][b] = rotate(s->R, a, b, j->h);
    for (int c = 0; c < 3; c++) {
        for (int i = 0; i < 3; i++)
            for (int k = 0; k < 3; k++)
                T[i][k] = j->t[i][k][c];
        for (int a = 0; a < 3; a++)
            for (int b = 0; b < 3; b++)
                dH[c][a][b] = rotate(s->R, a, b, T);
    }
    for (int i = 0; i < 3; i++) {
        g[i] = j->d[i];
        for (int c = 0; c < 3; c++)
            J[i][c] = j->h[i][c];
    }
    for (int r = 0; r < 3; r++) {
        int a = P[r][0], b = P[r][1];
        g[3 + r] = iv_sub(iv_mul(H[0][0], H[a][b]), iv_mul(H[0][a], H[0][b]));
        for (int c = 0; c < 3; c++)
            J[3 + r][c] = iv_sub(iv_add(iv_mul(dH[c][0][0], H[a][b]), iv_mul(H[0][0], dH[c][a][b])),
                                 iv_add(iv_mul(dH[c][0][a], H[0][b]), iv_mul(H[0][a], dH[c][0][b])));
    }
}

/* Σ_kl v_k v_l t[i][k][l] (i fixed: D³f[e_i, v, v]) and Σ_klm v_k v_l v_m q[k][l][m][i]. */
static void along_v(const ism_jet4 *j, int i, const ism_interval v[3], ism_interval *t2,
                    ism_interval *q3)
{
    *t2 = *q3 = ZERO;
    for (int k = 0; k < 3; k++)
        for (int l = 0; l < 3; l++) {
            ism_interval vv = iv_mul(v[k], v[l]);
            *t2 = iv_add(*t2, iv_mul(vv, j->t[i][k][l]));
            for (int m = 0; m < 3; m++)
                *q3 = iv_add(*q3, iv_mul(iv_mul(vv, v[m]), j->q[k][l][m][i]));
        }
}

static void a3(const sys *s, const ism_jet4 *j, const ism_interval v[3], ism_interval g[],
               ism_interval J[][ISM_OD_MAXK])
{
    for (int r = 0; r < 8; r++)
        for (int c = 0; c < 6; c++)
            J[r][c] = ZERO;
    ism_interval nv = pt(-1.0), cubic = ZERO;
    for (int i = 0; i < 3; i++) {
        g[i] = j->d[i];
        ism_interval hv = ZERO, t2, q3;
        for (int c = 0; c < 3; c++) {
            J[i][c] = J[3 + i][3 + c] = j->h[i][c];
            hv = iv_add(hv, iv_mul(j->h[i][c], v[c]));
            ism_interval d = ZERO;
            for (int k = 0; k < 3; k++)
                d = iv_add(d, iv_mul(v[k], j->t[i][c][k]));
            J[3 + i][c] = d;
        }
        g[3 + i] = hv;
        nv = iv_add(nv, iv_mul_c(v[i], s->n[i]));
        J[6][3 + i] = pt(s->n[i]);
        along_v(j, i, v, &t2, &q3);
        J[7][i] = q3;
        J[7][3 + i] = iv_mul_c(t2, 3.0);
        cubic = iv_add(cubic, iv_mul(v[i], t2));
    }
    g[6] = nv;
    g[7] = cubic;
}

/* G and J over the jet's box, with the auxiliary unknowns z[3..k). */
static void build(const sys *s, const ism_jet4 *j, const ism_interval z[], ism_interval g[],
                  ism_interval J[][ISM_OD_MAXK])
{
    if (s->kind == ISM_TC_RANK0)
        rank0(j, g, J);
    else if (s->kind == ISM_TC_RANK1)
        rank1(s, j, g, J);
    else
        a3(s, j, z + 3, g, J);
}

static void eval_at(ism_jet4_ws *w, const sys *s, const ism_interval z[], ism_jet4 *j,
                    ism_interval g[], ism_interval J[][ISM_OD_MAXK], uint64_t *evals)
{
    ism_jet4_eval(w, z, j, evals);
    build(s, j, z, g, J);
}

/* The system's sizes and frame from the Hessian at p. */
static void setup(ism_jet4_ws *w, int kind, const double p[3], sys *s, double zc[],
                  uint64_t *evals)
{
    ism_interval x[3] = { pt(p[0]), pt(p[1]), pt(p[2]) };
    ism_jet4 j;
    ism_jet4_eval(w, x, &j, evals);
    double h[6] = { mid(j.h[0][0]), mid(j.h[0][1]), mid(j.h[0][2]),
                    mid(j.h[1][1]), mid(j.h[1][2]), mid(j.h[2][2]) };
    double eig[3], vec[3][3];
    ism_sym3_eigen(h, eig, vec);
    int big = fabs(eig[0]) > fabs(eig[2]) ? 0 : 2, small = 0;
    for (int i = 1; i < 3; i++)
        if (fabs(eig[i]) < fabs(eig[small]))
            small = i;
    memset(s, 0, sizeof *s);
    s->kind = kind;
    s->m = kind == ISM_TC_RANK0 ? 9 : kind == ISM_TC_RANK1 ? 6 : 8;
    s->k = kind == ISM_TC_A3 ? 6 : 3;
    for (int r = 0; r < 3; r++)
        memcpy(s->R[r], vec[(big + r) % 3], sizeof s->R[r]);
    memcpy(s->n, vec[small], sizeof s->n);
    memcpy(zc, p, 3 * sizeof *zc);
    memcpy(zc + 3, s->n, 3 * sizeof *zc);
}

/* Gauss–Newton on G from zc; false when it leaves reach or does not settle. *cond: the
 * scaled Jacobian's condition at the last point. */
static bool refine(ism_jet4_ws *w, const sys *s, double zc[], double reach, double diag,
                   double *cond, uint64_t *evals)
{
    double start[3] = { zc[0], zc[1], zc[2] }, last = INFINITY;
    for (int it = 0; it < TC_GN_ITERS; it++) {
        ism_interval z[ISM_OD_MAXK], g[ISM_OD_MAXM], J[ISM_OD_MAXM][ISM_OD_MAXK];
        double a[ISM_OD_MAXM][ISM_OD_MAXK], P[ISM_OD_MAXK][ISM_OD_MAXM];
        ism_jet4 j;
        for (int i = 0; i < s->k; i++)
            z[i] = pt(zc[i]);
        eval_at(w, s, z, &j, g, J, evals);
        for (int r = 0; r < s->m; r++)
            for (int c = 0; c < s->k; c++)
                a[r][c] = mid(J[r][c]);
        if (!ism_od_left_inverse(s->m, s->k, a, P, cond))
            return false;
        double step = 0.0;
        for (int i = 0; i < s->k; i++) {
            double d = 0.0;
            for (int r = 0; r < s->m; r++)
                d += P[i][r] * mid(g[r]);
            zc[i] -= d;
            if (i < 3)
                step = fmax(step, fabs(d));
        }
        double moved = sqrt((zc[0] - start[0]) * (zc[0] - start[0]) +
                            (zc[1] - start[1]) * (zc[1] - start[1]) +
                            (zc[2] - start[2]) * (zc[2] - start[2]));
        if (!(moved <= reach))
            return false;
        if (step <= TC_GN_TOL * diag || (step >= last && step <= TC_GN_DONE * diag))
            return true;
        last = step;
    }
    return last <= TC_GN_DONE * diag;
}

/* The natural size of row r's equation: f's derivative of that order at the Hessian scale
 * hs of the box (gradient hs·diag, Hessian hs, third derivative hs/diag; a Schur entry
 * hs²; nᵀv − 1 is 1). */
static double row_scale(const sys *s, int r, double diag, double hs)
{
    if (r < 3)
        return hs * diag;
    if (s->kind == ISM_TC_RANK0 || (s->kind == ISM_TC_A3 && r < 6))
        return hs;
    if (s->kind == ISM_TC_RANK1)
        return hs * hs;
    return r == 6 ? 1.0 : hs / diag;
}

/* max |G_r| / row_scale over the box k (Krawczyk's enclosure of the solution). */
static double residual(ism_jet4_ws *w, const sys *s, const ism_interval k[], double diag,
                       double hs, uint64_t *evals)
{
    ism_interval g[ISM_OD_MAXM], J[ISM_OD_MAXM][ISM_OD_MAXK];
    ism_jet4 j;
    eval_at(w, s, k, &j, g, J, evals);
    double worst = 0.0;
    for (int r = 0; r < s->m; r++)
        worst = fmax(worst, mag(g[r]) / row_scale(s, r, diag, hs));
    return worst;
}

int ism_typecert(ism_jet4_ws *w, int system, const double p[3], double reach, double rmax,
                 double diag, double hscale, ism_typecert_result *out, uint64_t *evals)
{
    sys s;
    double zc[ISM_OD_MAXK];
    double cond = INFINITY;
    setup(w, system, p, &s, zc, evals);
    if (!refine(w, &s, zc, reach, diag, &cond, evals))
        return ISM_TC_SINGULAR;
    ism_interval z0[ISM_OD_MAXK], g[ISM_OD_MAXM], J[ISM_OD_MAXM][ISM_OD_MAXK];
    ism_jet4 j;
    for (int i = 0; i < s.k; i++)
        z0[i] = pt(zc[i]);
    eval_at(w, &s, z0, &j, g, J, evals); /* G(z_c), enclosed */
    double h2 = 0.0, t3 = 0.0;
    for (int a = 0; a < 3; a++)
        for (int b = 0; b < 3; b++) {
            h2 = fmax(h2, mag(j.h[a][b]));
            for (int c = 0; c < 3; c++)
                t3 = fmax(t3, mag(j.t[a][b][c]));
        }
    for (double r = TC_FIRST * rmax; r <= rmax * (1.0 + 1e-12); r *= TC_GROWTH) {
        /* v moves ~ (third / second derivative) × the move of x (A3 only) */
        double rv = r * fmax(1.0, t3 / fmax(h2, 1e-300));
        ism_interval z[ISM_OD_MAXK], jz[ISM_OD_MAXM][ISM_OD_MAXK], gz[ISM_OD_MAXM], k[ISM_OD_MAXK];
        for (int i = 0; i < s.k; i++) {
            double rad = i < 3 ? r : rv;
            z[i] = iv(down1(zc[i] - rad), up1(zc[i] + rad));
        }
        ism_jet4 jx;
        eval_at(w, &s, z, &jx, gz, jz, evals);
        if (!ism_od_krawczyk(s.m, s.k, jz, g, zc, z, k))
            continue;
        out->residual = residual(w, &s, k, diag, hscale > 0.0 ? hscale : fmax(h2, 1e-300), evals);
        if (!(out->residual <= TC_RESIDUAL_MAX))
            return ISM_TC_SINGULAR;
        memcpy(out->p, zc, sizeof out->p);
        out->radius = r;
        out->f = jx.v;
        return ISM_TC_CERTIFIED;
    }
    return cond > TC_COND_MAX ? ISM_TC_SINGULAR : ISM_TC_FAILED;
}
