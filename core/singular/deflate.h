/* deflate.h — a certificate for an isolated singular point whose Hessian has rank 2 (a cusp,
 * x² + z² − y³), where Krawczyk on ∇f = 0 cannot work: the Hessian, its Jacobian, is
 * singular there. The system is deflated (Leykin–Verschelde–Zhao; the ε-perturbation of
 * Rump–Graillat, "Verified error bounds for multiple roots of systems of nonlinear
 * equations", 2010) to 7 equations in 7 unknowns (x, v, ε):
 *
 *     ∇f(x) − ε n = 0,   H(x) v = 0,   nᵀ v − 1 = 0       (n: the approximate null vector)
 *
 * whose Jacobian [[H, 0, −n], [D³f[v], H, 0], [0, nᵀ, 0]] is non-singular exactly when the
 * cubic term of f along the null direction, D³f(n, n, n), is not 0 — the A2 cusp. Krawczyk
 * on a box Z = X × V × E then proves: X holds exactly one point x (with v, ε unique in V, E)
 * where the Hessian is singular and ∇f(x) = ε n, |ε| ≤ the bound returned. Intervals cannot
 * prove ε = 0 (a degenerate zero of ∇f disappears under an arbitrarily small perturbation),
 * so the certificate is of a degenerate critical point of ∇f − ε n, |ε| tiny. D³f comes from
 * the interval Hessians of the partial derivatives of f (core/eval/tape_partial.h). */
#ifndef ISM_SING_DEFLATE_H
#define ISM_SING_DEFLATE_H

#include <stdbool.h>
#include <stdint.h>
#include "core/eval/eval.h"
#include "core/singular/jet4.h"


enum ism_deflate_answer {
    ISM_DEFLATE_CERTIFIED = 0,
    ISM_DEFLATE_SINGULAR = 1, /* D³f(n, n, n) ≈ 0 (A3 or worse: the horn cyclide's point):
                                 the deflated Jacobian is singular too */
    ISM_DEFLATE_FAILED = 2,   /* Krawczyk did not contract on any box up to rmax */
};

typedef struct ism_deflate_result {
    double radius;     /* half-width of the x box (certified) */
    ism_interval f;    /* f over that box */
    double eps;        /* |ε| ≤ eps: the perturbation of ∇f along n */
} ism_deflate_result;

/* Tries the x boxes p ± r for r = r_first, r_first × growth, ... up to r_max, around the
 * approximate cusp p with unit null vector n of its Hessian. *evals (may be NULL) counts
 * interval jet evaluations. */
int ism_deflate_certify(ism_jet4_ws *w, const double p[3], const double n[3],
                        double r_first, double r_max, double growth, ism_deflate_result *out,
                        uint64_t *evals);

#endif
