/* curve_cert.h — the certificate of a traced singular curve (a double curve or a whisker),
 * point by point, from f.
 *
 * On a singular curve ∇f = 0 is three equations in three unknowns whose solutions form a
 * curve: the system is overdetermined along it and no interval method can prove it has a
 * solution at all (a perturbation of f as small as you like breaks the curve into isolated
 * points or nothing). What can be proved is the part that is regular: at a curve point p,
 * with t the Hessian's near-null direction (the tangent) and u, v an orthonormal basis of
 * the plane across it, the 2-D system
 *
 *     G(a, b) = ( u·∇f(p + a u + b v),  v·∇f(p + a u + b v) ) = 0
 *
 * has the Jacobian [u v]ᵀ H [u v], the Hessian across the curve: indefinite on a double
 * curve, definite on a whisker, non-singular either way (away from pinch and triple points).
 *
 * PROVED when a point passes: Krawczyk (krawczyk.h, ism_krawczyk2) on the square |a|, |b| ≤
 * r (r ≤ ISM_SING_CERT_REL × diagonal: a box of width ≤ 1e-9 × diagonal) shows that exactly
 * one point x* of that square of the normal plane through p has ∇f(x*) ⟂ u, v — and that the
 * Hessian across is non-singular on the square (the curve's kind cannot change there).
 * ONLY CONSISTENT: that x* is on the locus, i.e. f(x*) = 0 and t·∇f(x*) = 0. We check that
 * the intervals of f and of ∂f/∂t over the box contain 0 — necessary for a locus point in the
 * box, not sufficient. For a non-generic overdetermined system this is the best an interval
 * method can do; a point whose f or ∂f/∂t interval excludes 0 is refuted (no locus point of
 * that normal square lies in the box).
 *
 * A curve's end at a pinch, triple or other singular point of the list (where the Hessian
 * across degenerates and the 2-D system is singular) passes when that point is certified
 * (point_cert.h) and lies within 2 × ISM_SING_CERT_REL × diagonal of the end. */
#ifndef ISM_SING_CURVE_CERT_H
#define ISM_SING_CURVE_CERT_H

#include <stdbool.h>
#include <stdint.h>
#include "core/eval/interval_jet.h"
#include "core/expr/expr.h"
#include "core/singular/locus.h"

typedef struct ism_ccert {
    double radius;        /* the square's half-width used (the last tried when it failed) */
    double residual_f;    /* |f(p)| */
    double residual_grad; /* |∇f(p)| */
} ism_ccert;

/* Certifies the curve point p with half-widths growing up to rmax (jw: a workspace of t's
 * interval jets; *evals counts them). Returns whether p passed. */
bool ism_curve_cert_point(const ism_tape *t, ism_ivjet_ws *jw, const double p[3], double rmax,
                          ism_ccert *out, uint64_t *evals);

/* Certifies every curve of out (after ism_sing_certify_curve_points: an end at a point takes
 * that point's certificate), setting each curve's certified, uncertified_points,
 * first_uncertified, first_residual_f / _grad and cert_radius. Stops at o's deadline or
 * cancel (the curves not reached keep uncertified_points = n, first_uncertified = -1;
 * out->incomplete is set). False only when out of memory. */
bool ism_sing_certify_curves(const ism_tape *f, const ism_locus_options *o, ism_locus *out,
                             ism_error *err);

#endif
