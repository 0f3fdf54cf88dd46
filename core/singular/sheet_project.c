/* sheet_project.c — Newton onto a double sheet along the Hessian's dominant direction (see
 * sheet_project.h). Near f = g²·k (k ≠ 0), H ≈ 2k∇g∇gᵀ, so n is ∇g's direction and
 * −(∇f·n)/λ = −g/|∇g| to first order: quadratic convergence onto g = 0. */
#include "core/singular/sheet_project.h"
#include "core/util/vec3.h"

#include <math.h>
#include <string.h>

/* Newton steps before giving up (quadratic convergence needs ~6 from a cell away). */
#define SHEET_MAX_ITER 40
/* Converged: a step below this fraction of the cell (~1e-15 absolute at depth 6 in a box of
 * side 2, a few ulps of the coordinates). */
#define SHEET_STEP_TOL 1e-13
/* When rounding in f keeps the steps from falling below SHEET_STEP_TOL (f expanded into
 * monomials loses digits near its double zero), steps under this fraction of the cell
 * after SHEET_MAX_ITER still count as settled; the f test below then decides. */
#define SHEET_STALL_TOL 1e-7
/* Farthest the point may travel from p0, in cell diagonals: a crossing of ψ on a cell edge
 * whose sheet point is farther away belongs to another cell, or to no sheet. */
#define SHEET_MAX_MOVE 2.0
/* f at the landing point, relative to |λ|·cell² (f one cell off a double sheet is about
 * λ·cell²/2): below 1e-6 of that, f's minimum along n is a zero (the point is within 1e-3
 * cells of f = 0 along n). A valley whose bottom stays above it (f = g² + ε), or a point
 * where ∇f ⟂ n without f = 0, is no double sheet. */
#define SHEET_F_REL 1e-6
/* Power-iteration steps per Newton step that refresh n from the Hessian (see power_step). */
#define SHEET_POWER_STEPS 2

/* n ← H·n / |H·n|, kept on nref's side; λ ← nᵀHn. Near a double sheet H is ~rank 1, so
 * each step shrinks the error in n by λ2/λ1 ≈ 0 (no eigen-decomposition needed; and
 * Newton along any direction across the sheet lands on it, so n need not be exact). */
static bool power_step(const double h[6], double n[3], double *lam)
{
    double w[3] = {h[0] * n[0] + h[1] * n[1] + h[2] * n[2], h[1] * n[0] + h[3] * n[1] + h[4] * n[2],
                   h[2] * n[0] + h[4] * n[1] + h[5] * n[2]};
    double len = sqrt(w[0] * w[0] + w[1] * w[1] + w[2] * w[2]);
    if (!(len > 0) || !isfinite(len))
        return false;
    double s = w[0] * n[0] + w[1] * n[1] + w[2] * n[2] < 0 ? -1.0 / len : 1.0 / len;
    for (int k = 0; k < 3; k++)
        n[k] = s * w[k];
    *lam = n[0] * (h[0] * n[0] + h[1] * n[1] + h[2] * n[2])
         + n[1] * (h[1] * n[0] + h[3] * n[1] + h[4] * n[2])
         + n[2] * (h[2] * n[0] + h[4] * n[1] + h[5] * n[2]);
    return *lam != 0;
}

bool ism_sheet_project(const ism_tape *f, ism_eval_ws *ws, const double p0[3],
                       const double nref[3], double cell, double p[3], double n[3])
{
    double g[3], h[6], lam = 0, fv = 0, step = INFINITY;
    memcpy(p, p0, 3 * sizeof *p);
    memcpy(n, nref, 3 * sizeof *n);
    for (int it = 0; it < SHEET_MAX_ITER && !(fabs(step) <= SHEET_STEP_TOL * cell); it++) {
        fv = ism_eval_hessian(f, ws, p[0], p[1], p[2], g, h);
        for (int k = 0; k < SHEET_POWER_STEPS; k++)
            if (!power_step(h, n, &lam))
                return false;
        step = -(g[0] * n[0] + g[1] * n[1] + g[2] * n[2]) / lam;
        if (!isfinite(step))
            return false;
        for (int k = 0; k < 3; k++)
            p[k] += step * n[k];
        if (!(ism_dist3(p, p0) <= SHEET_MAX_MOVE * cell))
            return false;
    }
    if (!(fabs(step) <= SHEET_STALL_TOL * cell))
        return false;
    /* fv was taken one step back: f only falls along a Newton step toward the minimum, so
       this is the stricter test */
    return fabs(fv) <= SHEET_F_REL * fabs(lam) * cell * cell;
}
