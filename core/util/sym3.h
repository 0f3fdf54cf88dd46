/* sym3.h — eigen-decomposition of a symmetric 3×3 matrix (a Hessian), by cyclic Jacobi
 * rotations: accurate to a few ulps of the largest eigenvalue, no iteration count to tune;
 * and the pseudo-inverse Newton step on ∇f = 0 built on it. */
#ifndef ISM_SYM3_H
#define ISM_SYM3_H

#include <stdbool.h>

/* h = xx xy xz yy yz zz (the Hessian evaluator's order). Writes the eigenvalues ascending
 * into eig and, when vec is not NULL, unit eigenvectors as rows: vec[i] belongs to eig[i].
 * Non-finite input gives NaN eigenvalues. */
void ism_sym3_eigen(const double h[6], double eig[3], double vec[3][3]);

/* Sweeps of three rotations: Jacobi converges quadratically, 3×3 needs at most ~6; the cap
 * only guards against NaN input. */
#define ISM_SYM3_MAX_SWEEPS 32
/* The sweeps stop when the off-diagonal part off = |a01| + |a02| + |a12| is negligible; the
 * lanes (core/singular/sym3_lanes.c) stop on the same test, so that each lane ends where the
 * scalar loop does, bit for bit. Not above ISM_SYM3_OFF_TINY (or NaN: the comparison fails):
 * nothing left to rotate, and a rotation's theta = (aqq - app) / (2 apq) would divide by a
 * subnormal. At or below ISM_SYM3_OFF_REL × |a00| + |a11| + |a22|: rotating it away moves the
 * eigenvalues by about off² / gap, far below an ulp (1.1e-16 relative) of the diagonal. */
#define ISM_SYM3_OFF_TINY 1e-300
#define ISM_SYM3_OFF_REL 1e-18

/* The end of ism_sym3_eigen, for one that ran the sweeps elsewhere (core/singular/
 * sym3_lanes.c: four matrices side by side): a and v, the swept matrix and the rotations'
 * product (its columns the eigenvectors), into eig and vec as ism_sym3_eigen leaves them. */
void ism_sym3_sorted(const double h[6], const double a[3][3], const double v[3][3],
                     double eig[3], double vec[3][3]);

/* step = -H⁺ g (h = xx xy xz yy yz zz) over the eigen-directions of H whose eigenvalues are
 * above rel of the largest in magnitude — and, while the step is longer than trust, over one
 * direction fewer (smallest |λ| dropped first): near a curve or sheet of zeros of ∇f, H's
 * eigenvalues along the set are small but not 0, and stepping along them would throw the
 * point far along the set; the truncated step goes to the set across it (trust = INFINITY:
 * never truncated). False when H is zero or not finite. Newton on ∇f = 0 takes it: the
 * singular stage (core/singular/newton.h) and the octree's critical radius (turned.h). */
bool ism_sym3_pinv_step(const double g[3], const double h[6], double rel, double trust,
                        double step[3]);

/* The same step from ism_sym3_eigen's eig and vec of H. */
bool ism_sym3_pinv_of(const double g[3], const double eig[3], const double vec[3][3],
                      double rel, double trust, double step[3]);

/* Numerical rank: eigenvalues with |λ| > rel × max |λ| (0 for the zero matrix). */
int ism_sym3_rank(const double eig[3], double rel);

#endif
