/* curve_jet.h — the local geometry of f on a singular curve (a 1-D part of f = ∇f = 0):
 * Newton's corrector onto the curve within a plane, and the frame of a curve point — its
 * tangent (the Hessian's null vector), its normal plane and the Hessian restricted to that
 * plane, whose determinant tells a double curve (< 0) from a whisker (> 0). */
#ifndef ISM_CURVE_JET_H
#define ISM_CURVE_JET_H

#include <math.h>
#include <stdbool.h>
#include <stdint.h>
#include "core/eval/eval.h"
#include "core/util/vec3.h"

/* A converged point counts as on the curve when |∇f| ≤ this × Hessian scale × box diagonal,
 * i.e. it is within ~1e-9 × diagonal of a zero of ∇f. (Newton fixes only the two normal
 * components of ∇f; the tangent one vanishes by itself on a true curve, not near an isolated
 * critical point.) */
#define ISM_CURVE_GRAD_REL 1e-9

typedef struct ism_cjet {
    const ism_tape *f;
    ism_eval_ws *ws;
    double tol;      /* Newton stops when its step is below this (absolute length) */
    uint64_t evals;  /* Hessian evaluations so far */
} ism_cjet;

/* A point of a singular curve and its frame. */
typedef struct ism_cpoint {
    double p[3];
    double t[3];      /* unit tangent: the Hessian's (near-)null vector, oriented */
    double n[2][3];   /* orthonormal basis of the plane normal to t */
    double f;         /* f(p) */
    double grad;      /* |∇f(p)| */
    double hnorm;     /* largest |eigenvalue| of the Hessian: its scale */
    double D;         /* determinant of the Hessian restricted to the normal plane */
    double sigma;     /* largest |eigenvalue| of that restriction */
    double eig[3];    /* Hessian eigenvalues, ascending */
    double hn[6];     /* the Hessian restricted to the normal plane, as a 3×3 matrix
                         (I − ttᵀ) H (I − ttᵀ): xx xy xz yy yz zz */
} ism_cpoint;

/* Newton on E₀·∇f = E₁·∇f = 0 for p in the plane start + span(P₀, P₁) (a "station"): the
 * Jacobian is Eᵀ H P. Writes the converged point to out and the iterations used to *iters
 * (may be NULL). Fails (false) when the Jacobian is singular, an iterate moves farther than
 * maxmove from start, or maxit iterations do not bring the step below j->tol. */
bool ism_cjet_correct(ism_cjet *j, const double start[3], const double P[2][3],
                      const double E[2][3], double maxmove, int maxit, double out[3],
                      int *iters);

/* The frame at p. The tangent continues prev_t when given (NULL: the eigenvector of the
 * smallest |eigenvalue|, sign arbitrary); near a pinch point, where two eigenvalues are
 * both small, it is prev_t projected onto their eigenvectors, so it never jumps. */
void ism_cjet_frame(ism_cjet *j, const double p[3], const double *prev_t, ism_cpoint *out);

/* Whether the frame s (at a point Newton put on ∇f = 0) can start a trace: f ~ 0 there,
 * ∇f ~ 0, and the Hessian across the curve of rank 2 — both eigenvalues above the rank
 * thresholds of search.h relative to hessian_scale, the smaller above rank_margin × the
 * seed's own relative threshold (1: the curve stage's test; diag: the box diagonal). */
bool ism_cjet_seed_ok(const ism_cpoint *s, double hessian_scale, double diag,
                      double rank_margin);

/* The Frobenius inner product of a's and b's normal-plane Hessians (independent of the
 * bases chosen). Negative when the Hessian across the curve flipped between them: the curve
 * passed through a point where it vanishes. */
double ism_cjet_normal_dot(const ism_cpoint *a, const ism_cpoint *b);

/* The frame with its tangent reversed (the other direction of travel). */
void ism_cjet_reverse(ism_cpoint *c);

/* Distance from p to the segment a–b, and in *u the parameter (0..1) of its nearest point. */
double ism_dist_segment(const double p[3], const double a[3], const double b[3], double *u);

#endif
