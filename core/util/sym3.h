/* sym3.h — eigen-decomposition of a symmetric 3×3 matrix (a Hessian), by cyclic Jacobi
 * rotations: accurate to a few ulps of the largest eigenvalue, no iteration count to tune. */
#ifndef ISM_SYM3_H
#define ISM_SYM3_H

/* h = xx xy xz yy yz zz (the Hessian evaluator's order). Writes the eigenvalues ascending
 * into eig and, when vec is not NULL, unit eigenvectors as rows: vec[i] belongs to eig[i].
 * Non-finite input gives NaN eigenvalues. */
void ism_sym3_eigen(const double h[6], double eig[3], double vec[3][3]);

/* Numerical rank: eigenvalues with |λ| > rel × max |λ| (0 for the zero matrix). */
int ism_sym3_rank(const double eig[3], double rel);

#endif
