/* rm_hcell.h — certified bounds on f's Hessian over the cells of a grid laid over the mesh
 * (rm_hcell.c), so that the quality pass under an error bound can leave out the second
 * Newton evaluation of a distance measure (rm_bound.c) where the first step's residual
 * cannot carry the point past the limit it is measured against.
 *
 * The Newton step from x (s1 = f/|∇f| at x, landing at y, |y − x| = |s1|) cancels f's first
 * order exactly, so f(y) = ½ δᵀH(ξ)δ for some ξ on the segment: |f(y)| ≤ ½ M s1², with M a
 * bound on ‖H‖ over the segment, and |∇f(y)| ≥ |∇f(x)| − M |s1|. The second term of the
 * measure, s2 = |f(y)| / |∇f(y)|, is then at most ½ M s1² / (|∇f(x)| − M |s1|). M comes from
 * f's interval jet (interval_jet.h) over the cell holding x grown by max_error each way
 * (|s1| ≤ max_error keeps y inside): the Frobenius norm of the Hessian's enclosures, which
 * bounds the spectral one. None (INFINITY) where the jet has a kink (a min/max/abs switching
 * branch) or an unbounded entry.
 *
 * Measured (callgrind, --quality good, default bound, 1 thread): on the smooth presets' dual
 * meshes about half the fan's points have a first step above half the bound, each a second
 * evaluation of f and ∇f. */
#ifndef ISM_RM_HCELL_H
#define ISM_RM_HCELL_H

#include "core/remesh/rm_pass.h"

/* The grid's cell side, in mean edges of the mesh as the pass found it: a cell's jet costs
 * several evaluations (torus ~3,000 instructions against ~390 for f and ∇f at a point), so a
 * cell must serve many points; a larger cell's enclosures are looser. */
#define RM_HCELL_EDGES 4.0
/* Once this many cells have had their jet worked out, if fewer than RM_HCELL_MIN_SHARE of
 * the points asked of the cells have been spared their second evaluation (kinks, or
 * enclosures too loose for the bound), no new cell is worked out for the rest of the pass
 * (the cells known still answer): where the grid does not pay it costs at most the trial's
 * jets. A spared point saves an evaluation, a cell's jet costs about eight (torus) to twenty
 * (gyroid-ball); a cell serves tens of points. */
#define RM_HCELL_TRIAL 64
#define RM_HCELL_MIN_SHARE 0.5

/* The grid over m's vertices (cells of RM_HCELL_EDGES mean edges), none worked out yet; NULL
 * when out of memory or m has no edge (the measures then take both steps). */
struct rm_hcell *rm_hcell_new(const rm_pass *p);
void rm_hcell_free(struct rm_hcell *h);

/* A bound on the second term of the measure at x (rm_bound.c's s2) for a first step of s1
 * (|s1| ≤ max_error) with gradient norm gn at x: ½ M s1² / (gn − M |s1|) with M the Hessian
 * bound of x's cell; INFINITY where the cell has none or the denominator (a lower bound on
 * |∇f| where the step lands) is not above the pass's gthresh, where the second step would
 * find ∇f vanished. */
double rm_hcell_residual(rm_pass *p, const double x[3], double s1, double gn);

/* A second evaluation the bound spared (counted for the trial above). */
void rm_hcell_spared(rm_pass *p);

/* The points asked of the cells' bounds so far and those spared a second evaluation (0, 0
 * without cells). */
void rm_hcell_counts(const rm_pass *p, size_t *asked, size_t *spared);

#endif
