/* curve_events.h — what happens at the ends and marks of a traced path: clipping a step at
 * the box's face, locating a pinch point between two curve points, finding the singular
 * point a path runs into, and adding the points tracing discovers to the locus. */
#ifndef ISM_CURVE_EVENTS_H
#define ISM_CURVE_EVENTS_H

#include <stdbool.h>
#include "core/singular/curve_tracer.h"

/* nxt (a corrected point outside the box, one step from cur inside it) becomes the curve's
 * point on the box's face the segment cur→nxt leaves through: exactly on the face plane,
 * ∇f = 0 solved in it. False when the curve runs (nearly) along the face there. */
bool ism_cevent_clip(ism_ctracer *tr, const ism_cpoint *cur, ism_cpoint *nxt);

/* The point between curve points a and b (determinants of opposite sign, or b's exactly 0)
 * where the normal-plane Hessian's determinant vanishes: regula falsi (Illinois) on the
 * station along a→b, each station corrected onto the curve. *radius: the final bracket. */
void ism_cevent_locate_pinch(ism_ctracer *tr, const ism_cpoint *a, const ism_cpoint *b,
                             ism_cpoint *out, double *radius);

/* The point of the locus (other than ignore) that the segment a→b passes closest to its
 * start within its snap distance, or -1. */
int ism_cevent_hit_point(const ism_ctracer *tr, const double a[3], const double b[3],
                         int ignore);

/* The index of the locus point within snap distance of c->p (an uncertified one becomes a
 * pinch point when type is ISM_SING_PINCH), else of a new uncertified point of this type at
 * c (eigenvalues and residuals from c). -1 when out of memory. */
int ism_cevent_point(ism_ctracer *tr, const ism_cpoint *c, int type, double radius);

#endif
