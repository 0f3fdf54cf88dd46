/* turned.h — a feature about a cell across that the corners see. On the depth path a crossed
 * leaf at depth.max whose corner gradients turn over lies within about a cell of a critical
 * point or line of f with f = 0 near it: a tube thinner than a cell with a lattice line inside
 * it, a small ball over a lattice corner. The same feature between the lattice lines is a
 * hidden piece (thin_search.h), found and resolved ISM_THIN_RESOLVE_LEVELS deeper; seen by
 * the corners it was meshed at the cell's size (the tube r = 0.004 of issue 13 in the box
 * moved by (√2 − 1) of a depth-7 cell: one side of an inscribed 4-gon per cell, area −12.57%).
 * The octree (octree_build.c) resolves such a leaf as deep as a hidden piece; these are the
 * two tests it asks of it that look at f alone (the thresholds are octree_build.h's). */
#ifndef ISM_TURNED_H
#define ISM_TURNED_H

#include <stdbool.h>
#include "core/eval/eval.h"
#include "core/octree/corners.h"

/* Do two of the corner gradients g point further apart than the angle whose cosine is
 * cos_max (< 0), or does one vanish (a critical point of f at a corner)? Squared lengths and
 * dot products only. False when a gradient is not finite. */
bool ism_corners_turned(const double g[8][3], double cos_max);

/* The radius, in units of `size` (the leaf's width), of the feature that f's nearby critical
 * point stands for: `steps` pseudo-inverse Newton steps on ∇f = 0 (ism_sym3_pinv_step,
 * directions whose |λ| is under pinv_rel of the largest left: along a tube's axis) from the
 * corner of k with the smallest gradient, then ρ = √(2|f| / max|λ|). A tube y² + z² − r² or
 * a ball gives its own r exactly; a crossing of two sheets (f = 0 at the critical point) ~ 0.
 * 0 when an iterate leaves the ball of reach × size round that corner, or the jet is not
 * finite. */
double ism_critical_radius(const ism_tape *t, ism_eval_ws *ws, const ism_corners *k, double size,
                           int steps, double pinv_rel, double reach);

#endif
