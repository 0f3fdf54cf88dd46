/* sheet_orient.h — gives the Hessian directions n of the field's vertices one consistent
 * sign between lattice neighbours, so that ψ = (∇f·n)/λ changes sign across a double sheet
 * and nowhere else along a lattice edge. */
#ifndef ISM_SHEET_ORIENT_H
#define ISM_SHEET_ORIENT_H

#include <stdbool.h>
#include "core/singular/sheet_field.h"

/* Orients n at every vertex that has a direction (ISM_SF_JET without ISM_SF_NO_DIR) and sets
 * psi and ISM_SF_ORIENTED. The sign travels along lattice edges between such vertices, most
 * parallel pairs first (a maximum spanning forest on |n_a·n_b|), so an edge where n turns
 * sharply never decides a sign that a smoother path could. False when out of memory. */
bool ism_sheet_orient(ism_sheet_field *sf);

#endif
