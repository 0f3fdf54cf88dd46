/* typecert.h — certificates for degenerate singular points that Krawczyk on ∇f (a node, an
 * isolated point) and the deflated cusp system (deflate.h) cannot give: each point type is
 * the solution of a *defining system* G = 0 of m equations in k ≤ m unknowns, built from f's
 * derivatives, whose Jacobian has full column rank at a point of that type in general
 * position (typecert.c derives each). Krawczyk on the square system P G (overdet.h) then
 * proves, in a box X of half-width ≤ 0.5e-9 × the box diagonal:
 *
 *   (uniqueness, exact)   at most one point of X satisfies G = 0 — the one zero x* of P G;
 *   (existence, backward) at x*, |G| ≤ the residual bound: x* is exactly a point of that
 *                         type of a function f̃ whose jet at x* differs from f's by that much.
 *
 * Existence for f itself cannot be proved by any interval method for these types: each is
 * unstable — an arbitrarily small change of f removes it (a pinch point's curve, a triple
 * point's three sheets) or splits it (A3: t⁴ − δt² has three critical points) — the same
 * reason the cusp certificate carries its ε. */
#ifndef ISM_SING_TYPECERT_H
#define ISM_SING_TYPECERT_H

#include <stdint.h>
#include "core/eval/eval.h"
#include "core/singular/jet4.h"

enum ism_tc_system {
    ISM_TC_RANK0 = 0, /* ∇f = 0, H = 0: a triple point (xyz = 0, Steiner's origin), the
                         cross-cap's whisker end — 9 equations in x */
    ISM_TC_RANK1 = 1, /* ∇f = 0, rank H = 1: a pinch point (Whitney x² − zy²) — 6 in x */
    ISM_TC_A3 = 2,    /* ∇f = 0, Hv = 0, nᵀv = 1, D³f[v, v, v] = 0: an A3 point (the horn
                         cyclide's) — 8 in (x, v) */
    ISM_TC_SYSTEMS
};

enum ism_tc_answer {
    ISM_TC_CERTIFIED = 0,
    ISM_TC_SINGULAR = 1, /* Gauss–Newton on G did not converge to a regular solution near the
                            start: the point is of a higher codimension than the system
                            (touching spheres for RANK1, an A4 point or a curve for A3) */
    ISM_TC_FAILED = 2,   /* converged, but Krawczyk did not contract on any box up to rmax */
};

typedef struct ism_typecert_result {
    double p[3];      /* the certified point: the centre of X */
    double radius;    /* half-width of X */
    ism_interval f;   /* f over X */
    double residual;  /* the bound on |G| at x*, each equation relative to f's derivative of
                         its order at the box's Hessian scale hs: |∇f| / (hs·diag), |H| / hs,
                         |D³f| / (hs / diag) — the relative change of f's jet that makes x*
                         exactly of the type */
} ism_typecert_result;

/* Refines p (within reach of it) by Gauss–Newton on the system's G, then tries boxes of
 * half-width rmax × 1e-6, 1e-5, ... up to rmax around the refined point. diag: the search
 * box's diagonal (the scale of positions); hscale: its Hessian scale (locus.h; 0 = the
 * Hessian at p). w: f's jets to order 3, or 4 for ISM_TC_A3 (its Jacobian holds D⁴f).
 * *evals (may be NULL) counts jet evaluations. */
int ism_typecert(ism_jet4_ws *w, int system, const double p[3], double reach, double rmax,
                 double diag, double hscale, ism_typecert_result *out, uint64_t *evals);

#endif
