/* crossing_angle.h — the angle at which the two sheets of f = 0 cross along a double curve,
 * read from f's Hessian. Two sheets meeting at a small angle stay within a cell of each other
 * for many cells beside the curve: the octree's cell along the curve (curve_cell.h) and the
 * conformance tube's radius (conform_angle.c) are both sized by it. */
#ifndef ISM_CROSSING_ANGLE_H
#define ISM_CROSSING_ANGLE_H

#include <stddef.h>
#include "core/eval/eval.h"

/* tan φ of the angle φ (0 < φ ≤ 90°) at which two sheets cross at p, a point of a double
 * curve: INFINITY at right angles, NAN where the Hessian is not that of two sheets crossing
 * (a pinch or triple point, a whisker, rounding). */
double ism_crossing_tan_at(const ism_tape *f, ism_eval_ws *ws, const double p[3]);

/* The median of ism_crossing_tan_at over at most ISM_CROSSING_SAMPLES of the n points xyz
 * (evenly by index; the NAN ones left out): NAN when none is a transversal crossing. */
double ism_curve_crossing_tan(const ism_tape *f, ism_eval_ws *ws, const double *xyz, size_t n);

/* Points sampled per curve at most: the angle changes slowly along a curve, and each sample
 * costs a Hessian evaluation. */
#define ISM_CROSSING_SAMPLES 64

#endif
