/* points.h — the singular points stage: from the search's candidate boxes to certified (or
 * honestly uncertified) singular points, typed by the Hessian.
 *
 * Candidates are (a) boxes where Krawczyk proved one zero of ∇f (ISM_LBOX_UNIQUE), (b)
 * clusters of finest boxes whose projections onto ∇f = 0 all meet in one point ("isolated"
 * clusters), (c) rank-3 projections inside extended clusters. From each, Newton on ∇f (the
 * Hessian as Jacobian, pseudo-inverse) gives p; then Krawczyk on a box of half-width at most
 * ISM_SING_CERT_REL × the box diagonal around p (grown from ulps until it succeeds) proves one
 * zero of ∇f there, and the interval of f over that box must hold 0 — a critical point proved
 * off the surface (a sphere's centre) is dropped, as is one whose cell-sized neighbourhood
 * F excludes 0. Types: node (H indefinite, non-degenerate), isolated (H definite, or rank 2
 * with f of one sign around), cusp (rank 2, f changes sign along the null direction:
 * x² + z² − y³), degenerate (rank ≤ 1, or rank 2 otherwise). cones = -1.
 *
 * Uncertified candidates of isolated clusters are kept (certified = false, their residuals,
 * a type, radius = the cluster's half-width); duplicates (the same point from two clusters
 * or boxes) are merged by distance after certification. Boxes explained by a point are
 * flagged ISM_LBOX_USED; boxes explained by a critical point proved off the surface are
 * removed; rank-1 and rank-2 boxes of extended clusters (sheets, curves) are left as they
 * were. */
#ifndef ISM_SING_POINTS_H
#define ISM_SING_POINTS_H

#include <stdbool.h>
#include "core/singular/locus.h"
#include "core/singular/point_cert.h" /* ISM_SING_CERT_REL */
#include "core/expr/expr.h"

/* Adds the points found from out->boxes (the search's output for the same f and o) to
 * out->points, sorted by position (z, y, x), and updates the boxes as described above.
 * Adds its time and Hessian evaluations to out. Past o->deadline_ms or with *o->cancel set it
 * stops between candidates, keeps what it found and sets out->incomplete. False only when
 * out of memory. */
bool ism_sing_points(const ism_tape *f, const ism_locus_options *o, ism_locus *out,
                     ism_error *err);

#endif
