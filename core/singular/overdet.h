/* overdet.h — Krawczyk's test for m ≥ k equations G(z) = 0 in k unknowns whose Jacobian has
 * full column rank at the solution (an overdetermined but regular system: the defining
 * equations of a singular point's type, typecert.h; m = k for the deflated cusp system,
 * deflate.h). With P a real k × m left inverse of mid J(Z):
 *
 *     K(Z) = z_c − P G(z_c) + (I − P J(Z)) (Z − z_c)
 *
 * is Krawczyk's operator of the square system P G = 0 with preconditioner I. K ⊂ int Z proves
 * that P G has exactly one zero in Z (it lies in K) — so G has at most that one zero in Z: any
 * zero of G is one of P G. All arithmetic is outward rounded; P is any real matrix (only the
 * contraction depends on its quality). */
#ifndef ISM_SING_OVERDET_H
#define ISM_SING_OVERDET_H

#include <stdbool.h>
#include "core/eval/eval.h"

#define ISM_OD_MAXK 7  /* unknowns: x, a null vector v, a perturbation ε */
#define ISM_OD_MAXM 10 /* equations: ∇f (3) and six Hessian conditions (rank 0) */

/* P = a left inverse of a (m × k, m ≥ k): a⁻¹ when square, else the least-squares inverse of
 * D a, its rows scaled to unit length (but by at most a fixed factor, overdet.c), times D.
 * *cond (may be NULL): ‖P D⁻¹‖ ‖D a‖ in max-row norms, the condition of the scaled matrix.
 * False when a is (numerically) rank deficient or not finite. */
bool ism_od_left_inverse(int m, int k, const double a[][ISM_OD_MAXK], double p[][ISM_OD_MAXM],
                         double *cond);

/* The test above on Z = z[0..k) with centre zc; g encloses G(z_c), jz encloses J over Z.
 * Writes K (may be NULL). True when K ⊂ int Z. */
bool ism_od_krawczyk(int m, int k, const ism_interval jz[][ISM_OD_MAXK], const ism_interval g[],
                     const double zc[], const ism_interval z[], ism_interval kout[]);

#endif
