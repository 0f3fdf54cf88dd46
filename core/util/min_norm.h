/* min_norm.h — the minimum-norm Newton step for m = 2 or 3 equations in three unknowns (a
 * point put on two or three surfaces at once: a curve of f = g = 0, a crease a = b = 0, the
 * crossing of two curves). */
#ifndef ISM_MIN_NORM_H
#define ISM_MIN_NORM_H

#include <stdbool.h>

/* The step dx = −Jᵀ (J Jᵀ)⁻¹ r for the m rows of J (the equations' gradients) and their
 * values r: the shortest move that zeroes the linearised equations. False (step unset) when
 * J Jᵀ is singular to within rel: its determinant not above rel × the product of its
 * diagonal (rows dependent: the surfaces tangent there), or not finite. */
bool ism_min_norm_step(int m, const double J[][3], const double r[], double rel,
                       double step[3]);

#endif
