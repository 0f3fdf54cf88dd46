/* cut_fn.c — evaluating a curve's second function g and Newton on (f, g) that puts points on
 * the curve: the minimum-norm step dx = −Jᵀ (J Jᵀ)⁻¹ r with J the rows ∇f, ∇g (and ∇g₂ at a
 * crossing of two curves, where the system is square). */
#include "core/curves/cut_fn.h"
#include "core/util/min_norm.h"
#include "core/util/vec3.h"
#include <math.h>
#include <stdlib.h>
#include <string.h>

/* Newton steps before giving up (quadratic convergence needs a handful from a mesh point). */
#define CUT_NEWTON_ITERS 30
/* Step halvings tried when a full Newton step does not reduce the residual. */
#define CUT_DAMPING_HALVINGS 12
/* J Jᵀ with a determinant below this × the product of its diagonal is singular (the two
 * surfaces are tangent there): no reliable step. */
#define CUT_SINGULAR_REL 1e-14

bool ism_cut_eval_init(ism_cut_eval *ev, const ism_tape *f, const ism_cut_fn *fns, size_t n)
{
    memset(ev, 0, sizeof *ev);
    ev->pair[0] = ev->pair[1] = ISM_CUT_NO_BRANCH;
    ev->f = f;
    ev->fns = fns;
    ev->nfns = n;
    ev->fws = ism_eval_ws_new(f);
    ev->gws = calloc(n ? n : 1, sizeof *ev->gws);
    if (!ev->fws || !ev->gws) {
        ism_cut_eval_free(ev);
        return false;
    }
    for (size_t k = 0; k < n; k++)
        if (fns[k].tape && !(ev->gws[k] = ism_eval_ws_new(fns[k].tape))) {
            ism_cut_eval_free(ev);
            return false;
        }
    return true;
}

void ism_cut_eval_free(ism_cut_eval *ev)
{
    ism_eval_ws_free(ev->fws);
    if (ev->gws)
        for (size_t k = 0; k < ev->nfns; k++)
            ism_eval_ws_free(ev->gws[k]);
    free(ev->gws);
    memset(ev, 0, sizeof *ev);
}

/* The silhouette function ∇f·d, with gradient H d. */
static double silhouette_g(ism_cut_eval *ev, const double d[3], const double p[3],
                           double grad[3])
{
    double g[3], h[6];
    ism_eval_hessian(ev->f, ev->fws, p[0], p[1], p[2], g, h);
    if (grad) {
        grad[0] = h[0] * d[0] + h[1] * d[1] + h[2] * d[2];
        grad[1] = h[1] * d[0] + h[3] * d[1] + h[4] * d[2];
        grad[2] = h[2] * d[0] + h[4] * d[1] + h[5] * d[2];
    }
    return g[0] * d[0] + g[1] * d[1] + g[2] * d[2];
}

/* The crease function f_A − f_B of the current pair of branches (or a − b of a min/max at
 * the top of f's tape when no pair is set). */
static double crease_g(ism_cut_eval *ev, const double p[3], double grad[3])
{
    double v[2], g[2][3];
    if (ev->branch_tape && ev->pair[0] != ISM_CUT_NO_BRANCH) {
        for (int s = 0; s < 2; s++)
            v[s] = ism_eval_gradient(ev->branch_tape[ev->pair[s]], ev->branch_ws[ev->pair[s]],
                                     p[0], p[1], p[2], g[s]);
    } else if (!ism_eval_top_branches(ev->f, ev->fws, p[0], p[1], p[2], v, g)) {
        return NAN;
    }
    for (int i = 0; grad && i < 3; i++)
        grad[i] = g[0][i] - g[1][i];
    return v[0] - v[1];
}

bool ism_cut_crease_fn(const ism_tape *f, ism_cut_fn *out)
{
    if (!ism_tape_has_min_max(f))
        return false;
    memset(out, 0, sizeof *out);
    out->kind = ISM_CUT_CREASE;
    out->source = -1;
    return true;
}

double ism_cut_g(ism_cut_eval *ev, size_t k, const double p[3], double grad[3])
{
    const ism_cut_fn *fn = &ev->fns[k];
    if (fn->kind == ISM_CUT_SILHOUETTE)
        return silhouette_g(ev, fn->n, p, grad);
    if (fn->kind == ISM_CUT_CREASE)
        return crease_g(ev, p, grad);
    double v = fn->n[0] * p[0] + fn->n[1] * p[1] + fn->n[2] * p[2] - fn->c, g[3] = {0, 0, 0};
    if (fn->tape)
        v += grad ? ism_eval_gradient(fn->tape, ev->gws[k], p[0], p[1], p[2], g)
                  : ism_eval_point(fn->tape, ev->gws[k], p[0], p[1], p[2]);
    if (grad)
        for (int i = 0; i < 3; i++)
            grad[i] = g[i] + fn->n[i];
    return v;
}

double ism_cut_g_hessian(ism_cut_eval *ev, size_t k, const double p[3], double h, double grad[3],
                         double hess[6])
{
    const ism_cut_fn *fn = &ev->fns[k];
    double v = ism_cut_g(ev, k, p, grad);
    memset(hess, 0, 6 * sizeof *hess);
    if (fn->kind == ISM_CUT_SILHOUETTE || fn->kind == ISM_CUT_CREASE) {
        double d[3][3]; /* d[c]: (∇g(p + h e_c) − ∇g(p − h e_c)) / 2h, column c */
        for (int c = 0; c < 3; c++) {
            double q[3] = {p[0], p[1], p[2]}, gp[3], gm[3];
            q[c] = p[c] + h;
            ism_cut_g(ev, k, q, gp);
            q[c] = p[c] - h;
            ism_cut_g(ev, k, q, gm);
            for (int r = 0; r < 3; r++)
                d[c][r] = (gp[r] - gm[r]) / (2 * h);
        }
        static const int at[6][2] = {{0, 0}, {0, 1}, {0, 2}, {1, 1}, {1, 2}, {2, 2}};
        for (int i = 0; i < 6; i++) /* symmetrised */
            hess[i] = 0.5 * (d[at[i][0]][at[i][1]] + d[at[i][1]][at[i][0]]);
        return v;
    }
    if (fn->tape) {
        double g[3];
        ism_eval_hessian(fn->tape, ev->gws[k], p[0], p[1], p[2], g, hess);
    }
    return v;
}

bool ism_cut_g_batch(ism_cut_eval *ev, size_t k, const double *pos, size_t n, double *out)
{
    const ism_cut_fn *fn = &ev->fns[k];
    if (fn->kind == ISM_CUT_SILHOUETTE || fn->kind == ISM_CUT_CREASE) {
        for (size_t i = 0; i < n; i++)
            out[i] = ism_cut_g(ev, k, pos + 3 * i, NULL);
        return true;
    }
    double xyz[3][ISM_EVAL_BATCH];
    for (size_t i0 = 0; i0 < n; i0 += ISM_EVAL_BATCH) {
        size_t m = n - i0 < ISM_EVAL_BATCH ? n - i0 : ISM_EVAL_BATCH;
        for (size_t i = 0; i < m; i++)
            for (int c = 0; c < 3; c++)
                xyz[c][i] = pos[3 * (i0 + i) + c];
        if (fn->tape)
            ism_eval_batch(fn->tape, ev->gws[k], xyz[0], xyz[1], xyz[2], out + i0, m);
        for (size_t i = 0; i < m; i++)
            out[i0 + i] = (fn->tape ? out[i0 + i] : 0) + fn->n[0] * xyz[0][i] +
                          fn->n[1] * xyz[1][i] + fn->n[2] * xyz[2][i] - fn->c;
    }
    return true;
}

/* |value| / |gradient| of row i (infinite for a nonzero value of zero gradient). */
static double row_distance(const double r[3], const double J[3][3], int i)
{
    double n = sqrt(ism_dot3(J[i], J[i]));
    return n > 0 ? fabs(r[i]) / n : (r[i] == 0 ? 0 : INFINITY);
}

/* Values and gradient rows of f, the functions ks and the plane (n, c; NULL for none) at p;
 * the worst |value| / |gradient|. */
static double system_at(ism_cut_eval *ev, const size_t *ks, int nk, const double plane[4],
                        const double p[3], double r[3], double J[3][3])
{
    r[0] = ism_eval_gradient(ev->f, ev->fws, p[0], p[1], p[2], J[0]);
    for (int i = 0; i < nk; i++)
        r[i + 1] = ism_cut_g(ev, ks[i], p, J[i + 1]);
    if (plane) {
        memcpy(J[nk + 1], plane, 3 * sizeof *plane);
        r[nk + 1] = ism_dot3(plane, p) - plane[3];
    }
    double worst = 0;
    for (int i = 0; i <= nk + (plane != NULL); i++) {
        double d = row_distance(r, J, i);
        worst = d > worst ? d : worst;
    }
    return worst;
}

/* Newton ended at x with rows r, J of f and the functions ks: kept for the normal of a new
 * vertex there (ism_cut_f_gradient) and its residuals (ism_cut_known_residuals). */
static void note_end(ism_cut_eval *ev, const size_t *ks, int nk, const double x[3],
                     const double r[3], const double J[3][3])
{
    memcpy(ev->last_p, x, sizeof ev->last_p);
    memcpy(ev->last_grad, J[0], sizeof J[0]);
    ev->last_ok = true;
    ism_cut_resid *kept = &ev->last_res;
    memcpy(kept->p, x, sizeof kept->p);
    kept->res[0] = row_distance(r, J, 0);
    kept->nk = 0;
    for (int i = 0; i < nk; i++)
        if (ev->fns[ks[i]].kind != ISM_CUT_CREASE) {
            kept->ks[kept->nk] = (uint32_t)ks[i];
            kept->res[++kept->nk] = row_distance(r, J, i + 1);
        }
}

/* The unit normal of the plane holding dir and n (dir × n normalised); false when parallel. */
static bool across_normal(const double dir[3], const double n[3], double out[3])
{
    double c[3];
    ism_cross3(dir, n, c);
    double l = ism_norm3(c);
    if (!(l > 0) || !isfinite(l))
        return false;
    for (int k = 0; k < 3; k++)
        out[k] = c[k] / l;
    return true;
}

bool ism_cut_plane_along(const double a[3], const double b[3], const double n[3],
                         const double p[3], double plane[4])
{
    double d[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]};
    if (!across_normal(d, n, plane))
        return false;
    plane[3] = ism_dot3(plane, p);
    return true;
}

/* Newton on f, the nk functions ks and the plane (NULL for none): at most 3 equations. With
 * dir (plane NULL), the plane through p holding dir and ∇f(p) is made from the first
 * evaluation. */
static bool refine(ism_cut_eval *ev, const size_t *ks, int nk, const double plane[4],
                   const double dir[3], double tol, double max_move, double p[3])
{
    double x[3] = {p[0], p[1], p[2]}, r[3], J[3][3], across[4];
    double worst = system_at(ev, ks, nk, plane, x, r, J);
    if (dir) { /* its row as system_at would have made it */
        if (!across_normal(dir, J[0], across))
            return false;
        across[3] = ism_dot3(across, x);
        memcpy(J[nk + 1], across, 3 * sizeof *across);
        r[nk + 1] = ism_dot3(across, x) - across[3];
        double d = fabs(r[nk + 1]) / sqrt(ism_dot3(across, across));
        worst = d > worst ? d : worst;
        plane = across;
    }
    int m = nk + 1 + (plane != NULL);
    for (int it = 0; it <= CUT_NEWTON_ITERS; it++) {
        if (!isfinite(worst))
            return false;
        if (worst <= tol) {
            double d[3] = {x[0] - p[0], x[1] - p[1], x[2] - p[2]};
            if (ism_dot3(d, d) > max_move * max_move)
                return false;
            memcpy(p, x, sizeof x);
            note_end(ev, ks, nk, x, r, J);
            return true;
        }
        double step[3];
        if (!ism_min_norm_step(m, (const double (*)[3])J, r, CUT_SINGULAR_REL, step))
            return false;
        /* damped: halve the step until the residual drops (a kink of f, a far start) */
        double lambda = 1, next = INFINITY, xn[3];
        for (int h = 0; h < CUT_DAMPING_HALVINGS; h++, lambda *= 0.5) {
            for (int c = 0; c < 3; c++)
                xn[c] = x[c] + lambda * step[c];
            next = system_at(ev, ks, nk, plane, xn, r, J);
            if (next < worst)
                break;
        }
        if (!(next < worst))
            return false;
        memcpy(x, xn, sizeof x);
        worst = next;
    }
    return false;
}

bool ism_cut_refine(ism_cut_eval *ev, const size_t *ks, int nk, double tol, double max_move,
                    double p[3])
{
    return refine(ev, ks, nk, NULL, NULL, tol, max_move, p);
}

bool ism_cut_refine_on_plane(ism_cut_eval *ev, size_t k, const double plane[4], double tol,
                             double max_move, double p[3])
{
    return refine(ev, &k, 1, plane, NULL, tol, max_move, p);
}

bool ism_cut_refine_across(ism_cut_eval *ev, size_t k, const double dir[3], double tol,
                           double max_move, double p[3])
{
    return refine(ev, &k, 1, NULL, dir, tol, max_move, p);
}

void ism_cut_f_gradient(ism_cut_eval *ev, const double p[3], double grad[3])
{
    if (ev->last_ok && !memcmp(ev->last_p, p, sizeof ev->last_p))
        memcpy(grad, ev->last_grad, sizeof ev->last_grad);
    else
        ism_eval_gradient(ev->f, ev->fws, p[0], p[1], p[2], grad);
}

void ism_cut_residuals(ism_cut_eval *ev, size_t k, const double p[3], double *df, double *dg)
{
    double g[3];
    double f = ism_eval_gradient(ev->f, ev->fws, p[0], p[1], p[2], g);
    double nf = sqrt(ism_dot3(g, g));
    *df = nf > 0 ? fabs(f) / nf : fabs(f);
    double v = ism_cut_g(ev, k, p, g), ng = sqrt(ism_dot3(g, g));
    *dg = ng > 0 ? fabs(v) / ng : fabs(v);
}

bool ism_cut_known_residuals(const ism_cut_resid *r, size_t k, const double p[3], double *df,
                             double *dg)
{
    if (memcmp(r->p, p, sizeof r->p))
        return false;
    for (int i = 0; i < r->nk; i++)
        if (r->ks[i] == k) {
            *df = r->res[0];
            *dg = r->res[i + 1];
            return true;
        }
    return false;
}
