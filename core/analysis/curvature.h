/* curvature.h — curvature of a level set of f at a point from f's derivatives (curvature.c);
 * public (analysis.h includes it) and used by the implicit pass. */
#ifndef ISM_AN_CURVATURE_H
#define ISM_AN_CURVATURE_H

#include <stdbool.h>

/* Curvature of the level set of f through a point, from g = ∇f and h = Hessian (xx, xy, xz,
 * yy, yz, zz), with the sign convention of mean_curvature in analysis_types.h. Returns false
 * (and zeros) when |g| is 0 or anything is not finite. Outputs may be NULL. */
bool ism_curvature_from_derivatives(const double g[3], const double h[6], double *mean,
                                    double *gauss, double *k1, double *k2);

#endif
