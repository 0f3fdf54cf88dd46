/* sheet_project.h — moves a point onto a double sheet: Newton on the 1-D minimisation of f
 * along the Hessian's dominant direction n (step −(∇f·n)/λ, which for f = g² is Newton on g
 * along ∇g), and says whether f really vanishes where it lands. */
#ifndef ISM_SHEET_PROJECT_H
#define ISM_SHEET_PROJECT_H

#include <stdbool.h>
#include "core/eval/eval.h"

/* From p0, with nref the direction to orient n by and cell the finest cell's diagonal:
 * true when Newton settles within SHEET_MAX_MOVE cells of p0 at a point p where
 * |f(p)| ≤ SHEET_F_REL·|λ|·cell² (f's minimum along n is 0 there, not a positive valley
 * bottom or a point where ∇f ⟂ n); writes p, and in n the Hessian's direction there,
 * oriented like nref. */
bool ism_sheet_project(const ism_tape *f, ism_eval_ws *ws, const double p0[3],
                       const double nref[3], double cell, double p[3], double n[3]);

#endif
