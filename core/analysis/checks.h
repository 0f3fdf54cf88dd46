/* checks.h — the input checks ism_analyse and ism_analysis_project share (checks.c), and the
 * error helper they report with. */
#ifndef ISM_AN_CHECKS_H
#define ISM_AN_CHECKS_H

#include <stdbool.h>
#include "core/mesh/mesh.h"
#include "core/expr/expr.h"
#include "core/analysis/analysis_types.h"

/* Fills err (may be NULL) with a positionless message; returns false (the expression
 * engine's ism_error_set). */
#define ism_an_fail ism_error_set

/* True when m can be analysed: fewer than 2^32-1 vertices and at most (2^32-4)/3 triangles,
 * every coordinate finite and below 1e100 in size, every index in range. False with a
 * message naming the first offending vertex or triangle. */
bool ism_an_check_mesh(const ism_mesh *m, ism_error *err);
/* True when every option is in its documented range; false with a message naming it. */
bool ism_an_check_options(const ism_analysis_options *o, ism_error *err);

#endif
