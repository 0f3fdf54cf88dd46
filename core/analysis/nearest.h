/* nearest.h — the distance from a point to f = 0 found by searching for the surface (nearest.c),
 * where the first-order estimate |f| / |∇f| overstates it: beside singular points and curves,
 * where ∇f vanishes on the surface and grows only linearly off it. */
#ifndef ISM_AN_NEAREST_H
#define ISM_AN_NEAREST_H

#include <stdint.h>
#include "core/expr/expr.h"
#include "core/eval/eval.h"

/* min(d0, the distance from q to the points of f = 0 found by Newton's projection from q and,
 * where |∇f(q)| < rays_below (beside the locus: ∇f vanishes there), by a search along rays
 * from q for a sign change of f within that), d0 the first-order estimate at q. Every point
 * found lies on f = 0 (Newton converged, or a sign change narrowed to 1.5e-5 of the radius),
 * so where one is found the result is an upper bound of the true distance; where none is
 * (f keeps its sign round q: a touching or an isolated zero) d0 stands. counts: NULL, or
 * [0] += the points f was evaluated at and [1] += the gradients (the polygoniser's stats). */
double ism_an_nearest_zero(const ism_tape *f, ism_eval_ws *ws, const double q[3], double d0,
                           double rays_below, uint64_t counts[2]);

#endif
