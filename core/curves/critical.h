/* critical.h — tangency points of curves on f = 0, found from the equations: where g = 0
 * touches the surface (a singular point of the curve f = g = 0, ∇f ∥ ∇g: Viviani's
 * self-crossing) or touches an earlier curve f = g_j = 0 (∇f, ∇g_j, ∇g dependent). Both are
 * critical points of g on a constraint set (f = 0, or f = g_j = 0) at which g = 0; Newton on
 * the square Lagrange system ∇g = Σ λ_i ∇c_i, c_i = 0 finds them. */
#ifndef ISM_CRITICAL_H
#define ISM_CRITICAL_H

#include <stdbool.h>
#include <stddef.h>
#include "core/curves/cut_fn.h"

/* No second constraint: the critical point of g_k on f = 0 alone. */
#define ISM_CUT_NO_CURVE ((size_t)-1)

/* Moves p to the critical point of g_k on f = 0 (j is ISM_CUT_NO_CURVE) or on the curve
 * f = g_j = 0 near it. True when Newton converged (its last step and the constraints'
 * distances |c|/|∇c| at most tol) within max_move of the start; *dist then holds g_k's
 * distance |g_k|/|∇g_k| at the point (0 at a tangency). h is the difference step for the
 * Hessians of silhouettes and creases. p is unchanged when false. */
bool ism_cut_critical(ism_cut_eval *ev, size_t k, size_t j, double tol, double max_move,
                      double h, double p[3], double *dist);

#endif
