/* crease_split.h — under an error bound, a leaf's triangles cut along the crease of a CSG
 * surface, f = min(a, b) or max(a, b) at the top of its tape: each triangle whose corners
 * lie on both branches is split at points of a = b = 0 on its two mixed edges, so every
 * piece lies on one smooth branch and its distance to f = 0 shrinks with the square of its
 * size, not linearly as a triangle folded across the crease does.
 *
 * Where f has kinks below its top min/max, or passes it on through later steps (the cube
 * max(|x|, |y|, |z|) − 1 inside cube-minus-ball's top max, the cube and Steinmetz alone), the
 * branches are f's smooth pieces instead (eval.h ism_eval_piece: the branch every min, max
 * and abs on f's active path takes), the crease between two pieces where f on each (their
 * kinks forced) is 0, and where three pieces meet (the cube's corners) a triangle or polygon
 * round that point is cut there too: the cube's edges, folded, left triangles half a depth-10
 * cell off at any bound (cube-minus-ball at E = 1e-4: 14.3 E, 9,440 cells missed). */
#ifndef ISM_CREASE_SPLIT_H
#define ISM_CREASE_SPLIT_H

#include <stdbool.h>
#include <stddef.h>
#include "core/octree/cell_types.h"
#include "core/octree/grid.h"
#include "core/octree/sampler.h"

/* Splits out's triangles from first_tri on (one leaf's) along the crease of s's tape; does
 * nothing when the tape does not end in min/max, or when the leaf's shortened tape
 * (s->local) has that min/max decided over its box and the triangles lie in the box (one
 * branch there: no crease). Inside the box the shortened tape gives the branches when it
 * keeps the min/max (bit for bit f's). A mixed edge's crease point depends on its two end
 * points only (taken in coordinate order), so the leaves sharing an edge find the same
 * point bit for bit and the weld joins them. False when out of memory. */
bool ism_crease_split(ism_sampler *s, ism_cell_out *out, size_t first_tri);

/* Under an error bound, a polygon of a leaf (ism_triangulate_loop's arguments) whose corners
 * lie on both branches, two runs of them, is cut along the chord between the crease points
 * of its two mixed edges (on f's pieces also three runs on three pieces, or four alternating
 * on two, cut from each mixed edge's crease point to the point where those creases meet) (the points ism_crease_split puts there, flagged ISM_FP_CREASE), and
 * each branch's polygon is triangulated on its own, wound as the whole polygon is: fanned
 * whole and split after, a fan from a point on one branch to two on the other crosses the
 * wedge between them and its pieces turn over (cube-minus-ball's face z = −1 beside its
 * crease circle: triangles facing +z). Under a bound (s->dist_above), on a top min/max of two
 * branches, a chord that strays from the crease is replaced by crease points along it, shared
 * by both polygons where the path leaves both ends into the polygon (crease_split.c
 * follow_crease; else the chord stays). *done false (nothing emitted) when the polygon is
 * not cut: one branch, more than two mixed edges, or no crease point found. False when out
 * of memory. */
bool ism_crease_cut_loop(ism_sampler *s, const ism_fpoint *pts, size_t n, double reach,
                         const double node[6], double max_error, ism_cell_out *out, bool *done);

/* Is the crease unresolved by out's triangles from first_tri on (one leaf's, after
 * ism_crease_split)? A triangle faces against ∇f at its centroid (the directions more than
 * 120° apart); or the crease passes between corners unseen — an edge whose ends lie on one
 * branch with its midpoint on the other, or a triangle's three corners on one branch and its
 * centroid on the other (the gyroid ball's ball beside (−0.63, −0.80, −0.96) in a leaf 0.085
 * wide under E = 3e-3, a gyroid bump inside: an edge midpoint no zero could be shown within E
 * of, and a triangle facing the ball's way at a centroid where the gyroid's gradient holds);
 * or an edge between two crease points whose middle lies farther than max_error / 2 from the
 * crease. Only where the leaf keeps f's top min/max; false elsewhere. centroid_g: NULL, or
 * ∇f at each triangle's centroid as ism_emitted_error_kept measured it (the same bits as
 * sampling it here). */
bool ism_crease_unresolved(ism_sampler *s, const ism_cell_out *out, size_t first_tri,
                           double max_error, const double (*centroid_g)[3]);

/* The sampler's wedge_edges_below (sampler.h): under an error bound (max_error > 0) the
 * diagonal of a cell of grid g one level above max_depth (crease_split.c CREASE_WEDGE_LEVELS),
 * the longest edge of the leaves that can no longer, or hardly, be split to follow the crease;
 * 0 without a bound (max_error <= 0: one edge's length only). */
double ism_crease_wedge_edges(const ism_grid *g, int max_depth, double max_error);

/* The sampler's fold_below under an error bound (max_error > 0; 0 without one): in pieces
 * mode a mixed edge is left whole, folded, where |f|/|∇f| at the point its two pieces' values
 * cross along it is within CREASE_FOLD_SHARE × max_error and their wedge is no sharper than
 * CREASE_FOLD_COS allows (crease_split.c whole_edge). */
double ism_crease_fold_below(double max_error);

/* Is f's crease read off its smooth pieces (the sampler's crease_pieces): f has a kink that is
 * not its top min/max of two registers (a kink below it, or a min/max passed on through later
 * steps), and at most ISM_PIECE_KINKS kinks? */
bool ism_crease_pieces(const ism_tape *f);

/* The branch of f's top min/max active at p (0 or 1), or -1 when the tape does not end in
 * min/max. g: that branch's gradient there (may be NULL). */
int ism_crease_branch(ism_sampler *s, const double p[3], double g[3]);

/* x moved onto a = b = 0 for the branches a, b of f's top min/max by minimum-norm Newton
 * steps (up to 8; fewer once x repeats): false when a step fails (the branches' gradients
 * parallel, or a value not finite) or the tape does not end in min/max. Where x lands is
 * the caller's to check (it may be a distant part of the crease). */
bool ism_crease_newton(ism_sampler *s, double x[3]);

#endif
