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

/* step = -H⁺ g (h = xx xy xz yy yz zz) over the eigen-directions of H whose eigenvalues are
 * above rel of the largest in magnitude — and, while the step is longer than trust, over one
 * direction fewer (smallest |λ| dropped first): near a curve or sheet of zeros of ∇f, H's
 * eigenvalues along the set are small but not 0, and stepping along them would throw the
 * point far along the set; the truncated step goes to the set across it (trust = INFINITY:
 * never truncated). False when H is zero or not finite. Newton on ∇f = 0 takes it: the
 * singular stage (core/singular/newton.h) and the octree's critical radius (turned.h). */
bool ism_sym3_pinv_step(const double g[3], const double h[6], double rel, double trust,
                        double step[3]);

/* Numerical rank: eigenvalues with |λ| > rel × max |λ| (0 for the zero matrix). */
int ism_sym3_rank(const double eig[3], double rel);

#endif
