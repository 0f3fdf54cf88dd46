/* search.h — the interval subdivision stage of the singular locus: which cells of the box
 * may hold a point where f = 0 and ∇f = 0.
 *
 * The box is cut like an octree down to o->max_depth; a cell is dropped when intervals prove
 * 0 ∉ F(X) or 0 ∉ ∂F/∂xi(X) for some i (each smooth piece of a min/max/abs separately), or
 * when the Krawczyk operator proves ∇f has no zero in it. A cell where Krawczyk proves
 * exactly one zero of ∇f is not cut further (flag ISM_LBOX_UNIQUE). Cells that survive to the
 * finest size (box side / 2^max_depth) are the candidates: each with its centre projected
 * onto ∇f = 0 by pseudo-inverse Newton (flag ISM_LBOX_PROJECTED when that converged within
 * the cell grown by half its width) and the Hessian's numerical rank there; a candidate on
 * which an earlier one's projection lies (in key order, within a run of candidates) takes
 * that projection and its rank instead of a Newton run of its own. */
#ifndef ISM_SING_SEARCH_H
#define ISM_SING_SEARCH_H

#include <stdbool.h>
#include "core/singular/locus.h"
#include "core/expr/expr.h"

/* Relative eigenvalue threshold of the rank recorded for a candidate box (ism_sym3_rank):
 * at a point of ∇f = 0 found to ~1e-12 of a cell, the Hessian's vanishing eigenvalues are
 * ~1e-10 of its largest or less, real curvatures are far above 1e-6. */
#define ISM_SING_RANK_REL 1e-6

/* ... and eigenvalues at most this × the locus' Hessian scale (locus.h) are 0 whatever the
 * largest: where f vanishes to third order (f = g³·k on g = 0, the heart's ring z = 0) the
 * computed Hessian is rounding, ~1e-13 of its terms, whose eigenvalues have no meaningful
 * ratios; the curvature of any singular point a person writes lies far above 1e-9 of the
 * Hessian the same f shows across its box. */
#define ISM_SING_HZERO_REL 1e-9

/* The Hessian's rank from its eigenvalues: those above ISM_SING_RANK_REL × the largest and
 * above ISM_SING_HZERO_REL × hscale (the locus' Hessian scale; 0 = relative test only). */
int ism_sing_rank(const double eig[3], double hscale);

/* Appends to out->boxes the candidate boxes (ISM_LBOX_UNIQUE ones may be coarser than the
 * finest size), sorted by position (z, then y, then x of their lower corner), and adds the
 * work counters and time to out. Identical output for any thread count (when complete).
 * Sets out->incomplete (and why) on budget, deadline or cancel. False only on bad options
 * or out of memory (err says which). */
bool ism_sing_search(const ism_tape *f, const ism_locus_options *o, ism_locus *out,
                     ism_error *err);

/* ism_sing_search with the children's interval gradients taken in batches (search.c
 * pre_gradients; ism_sing_search's way) or, batch false, one by one: the same boxes and the
 * same counters bit for bit either way, the batch only faster (test_search_batch.c holds
 * the two to that); out->grads_batched counts the cells it took. */
bool ism_sing_search_batched(const ism_tape *f, const ism_locus_options *o, bool batch,
                             ism_locus *out, ism_error *err);

#endif
