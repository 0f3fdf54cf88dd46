/* tape_partial.h — a tape's partial derivative as a tape of its own: ∂f/∂x, ∂f/∂y or ∂f/∂z,
 * built by forward differentiation of the instructions (one tangent register per value).
 * Every evaluator then applies to it; its interval Hessian encloses third derivatives of f,
 * which the certificate of a degenerate singular point needs (core/singular/deflate.h). */
#ifndef ISM_TAPE_PARTIAL_H
#define ISM_TAPE_PARTIAL_H

#include "core/expr/expr.h"

/* A new tape computing ∂f/∂x_axis (axis 0, 1, 2) wherever f is differentiable; at a kink of
 * min/max/abs (operands equal, abs of 0) and at a clipped sqrt/log/real power's edge it gives
 * a non-finite value (an interval holding one is the whole line), never a wrong finite one.
 * NULL when out of memory or axis is out of range. Free with ism_tape_free. */
ism_tape *ism_tape_partial(const ism_tape *t, int axis);

#endif
