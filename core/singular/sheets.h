/* sheets.h — double sheets: the 2-D parts of f = 0 across which f does not change sign
 * (f = g²·k, k ≠ 0: a sphere counted twice, a plane x² = 0), found from f on the lattice of
 * the finest search cells and meshed as the zero set of ψ = (∇f·n)/λ ((n, λ) the Hessian's
 * dominant eigenpair: ψ is the signed Newton distance to the sheet) where f itself
 * vanishes. The polygoniser sees no sign change there and meshes
 * nothing; sign-changing surfaces are left to it. */
#ifndef ISM_SHEETS_H
#define ISM_SHEETS_H

#include <stdbool.h>
#include "core/expr/expr.h"
#include "core/mesh/mesh.h"
#include "core/singular/locus.h"

/* Finds the double sheets of f in o->box at resolution box side / 2^o->max_depth and
 * appends their triangles to mesh: vertices on the sheet (Newton, |f| ≈ 0), shared between
 * the sheets' own triangles (not with triangles already in mesh), each connected sheet
 * consistently oriented with unit normals, its triangles one range recorded in io->sheets
 * with its area. A sheet's boundary lies on the box, or about a cell from where it meets
 * a sign-changing surface or its Hessian loses rank 1. Cut short by o->cancel,
 * o->deadline_ms or o->max_boxes (candidate cells), it sets io->incomplete and its reason
 * and returns true, having appended nothing. False (err says why) on bad options or when
 * out of memory. Adds its time and evaluation counts to io. */
bool ism_sing_double_sheets(const ism_tape *f, const ism_locus_options *o, ism_locus *io,
                            ism_mesh *mesh, ism_error *err);

/* The same, without an octree of its own: the candidate cells are the finest-size boxes
 * that ism_sing_search, run with the same box and depth, left in io->boxes (those not
 * flagged ISM_LBOX_USED). That search keeps every cell where f = ∇f = 0 may hold, hence
 * every cell of a double sheet, so nothing is lost, and a surface without any costs
 * next to nothing. Both functions flag ISM_LBOX_USED on the finest boxes of io->boxes
 * whose cells gave sheet triangles. */
bool ism_sing_double_sheets_from_search(const ism_tape *f, const ism_locus_options *o,
                                        ism_locus *io, ism_mesh *mesh, ism_error *err);

#endif
