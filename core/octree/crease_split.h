/* crease_split.h — under an error bound, a leaf's triangles cut along the crease of a CSG
 * surface, f = min(a, b) or max(a, b) at the top of its tape: each triangle whose corners
 * lie on both branches is split at points of a = b = 0 on its two mixed edges, so every
 * piece lies on one smooth branch and its distance to f = 0 shrinks with the square of its
 * size, not linearly as a triangle folded across the crease does. */
#ifndef ISM_CREASE_SPLIT_H
#define ISM_CREASE_SPLIT_H

#include <stdbool.h>
#include <stddef.h>
#include "core/octree/cell_types.h"
#include "core/octree/sampler.h"

/* Splits out's triangles from first_tri on (one leaf's) along the crease of s's tape; does
 * nothing when the tape does not end in min/max, or when the leaf's shortened tape
 * (s->local) has that min/max decided over its box and the triangles lie in the box (one
 * branch there: no crease). Inside the box the shortened tape gives the branches when it
 * keeps the min/max (bit for bit f's). A mixed edge's crease point depends on its two end
 * points only (taken in coordinate order), so the leaves sharing an edge find the same
 * point bit for bit and the weld joins them. False when out of memory. */
bool ism_crease_split(ism_sampler *s, ism_cell_out *out, size_t first_tri);

/* The branch of f's top min/max active at p (0 or 1), or -1 when the tape does not end in
 * min/max. g: that branch's gradient there (may be NULL). */
int ism_crease_branch(ism_sampler *s, const double p[3], double g[3]);

/* x moved onto a = b = 0 for the branches a, b of f's top min/max by minimum-norm Newton
 * steps (up to 8; fewer once x repeats): false when a step fails (the branches' gradients
 * parallel, or a value not finite) or the tape does not end in min/max. Where x lands is
 * the caller's to check (it may be a distant part of the crease). */
bool ism_crease_newton(ism_sampler *s, double x[3]);

#endif
