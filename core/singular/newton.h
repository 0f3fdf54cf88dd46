/* newton.h — Newton's method on ∇f = 0 with the Hessian as Jacobian, through its
 * pseudo-inverse: quadratic convergence at a non-degenerate critical point, and at a
 * degenerate one (a cusp, a double sheet, two spheres touching) a step that moves only along
 * the Hessian's well-determined directions — Gauss–Newton onto the set ∇f = 0. */
#ifndef ISM_SING_NEWTON_H
#define ISM_SING_NEWTON_H

#include <stdbool.h>
#include <stdint.h>
#include "core/eval/eval.h"

/* Eigenvalues below this fraction of the largest in magnitude are treated as 0 by the
 * pseudo-inverse when projecting onto curves and sheets of zeros of ∇f: far above double
 * rounding of a Hessian (~1e-16 relative), so that the tiny eigenvalues along the set do not
 * throw the point along it; far below any curvature ratio of a surface a person writes. */
#define ISM_SING_PINV_REL 1e-9
/* The same for converging onto an isolated but degenerate zero (cusp, touching spheres),
 * where an eigenvalue fades as the zero is approached: a few ulps of the largest. */
#define ISM_SING_PINV_REL_POINT 1e-15

/* The step itself, -H⁺∇f truncated to a trust length, is ism_sym3_pinv_step (sym3.h), which
 * the octree's critical-radius test (core/octree/turned.h) shares. */

/* Converged means a step below tol and |∇f| <= this × tol × |H| (Frobenius): the gradient
 * a few thousand step tolerances of curvature would give — far below where a truncated
 * step stalls off the set (|∇f| ~ |H| × distance), far above rounding. */
#define ISM_SING_NEWTON_RESID 1e4

typedef struct ism_newton_result {
    bool converged;   /* the last step was below tol */
    int iterations;
    double grad_norm; /* |∇f| at the final point */
    double grad[3], hess[6]; /* ism_eval_hessian's ∇f and H at the final point */
    double start_hess[6];    /* ... and H at the start point (the run's first jet) */
} ism_newton_result;

typedef struct ism_newton_opts {
    double rel;          /* pseudo-inverse threshold (ISM_SING_PINV_REL or _POINT) */
    double trust;        /* longest step before directions are dropped */
    double tol;          /* a step shorter than this ends the iteration */
    int max_iter;
    const double *lo, *hi; /* the iterates must stay in [lo, hi] (NULL: unbounded) */
    bool extrapolate;    /* where the steps shrink by a steady ratio (linear convergence at
                            a multiple zero of ∇f), jump by the rest of their geometric
                            series (see newton.c) */
} ism_newton_opts;

/* Iterates p <- p - H⁺∇f from p (steps truncated as above), at most o->max_iter times,
 * until a step is shorter than o->tol. Stops (converged = false) when an iterate leaves
 * [lo, hi] or the jet is not finite; p is then the last point inside. *evals (may be NULL)
 * counts the Hessian evaluations. */
ism_newton_result ism_sing_newton(const ism_tape *t, ism_eval_ws *ws, double p[3],
                                  const ism_newton_opts *o, uint64_t *evals);

/* Runs per pass of ism_sing_newton_lanes: the singular search's projection runs
 * (SEARCH_PROJECT_RUN) at once. */
#define ISM_SING_NEWTON_LANES 64

/* ism_sing_newton from each of p[0..n) with o[i], r[i] its result, run side by side: each
 * pass takes the jets of all unfinished runs in one ism_eval_hessian_batch (bit for bit the
 * scalar jets), so each p[i] and r[i] are exactly what ism_sing_newton(t, ws, p[i], &o[i])
 * gives. *evals (may be NULL) counts the Hessians, as there. */
void ism_sing_newton_lanes(const ism_tape *t, ism_eval_ws *ws, double (*p)[3],
                           const ism_newton_opts *o, ism_newton_result *r, size_t n,
                           uint64_t *evals);

#endif
