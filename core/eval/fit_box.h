/* fit_box.h — where the zero set of f lies inside a generous cube: a coarse interval pass
 * (breadth-first subdivision, a box kept while its interval of f contains 0) gives a box
 * that is guaranteed to contain every zero of f in the cube (interval bounds are outward
 * rounded), loose by at most one cell of the level reached plus the interval evaluator's
 * overestimate. Used to choose the box of an expression the user typed without one. */
#ifndef ISM_FIT_BOX_H
#define ISM_FIT_BOX_H

#include <stdbool.h>
#include <stddef.h>
#include "core/expr/expr.h"

/* Deepest level of the pass: 128 cells a side, so the box is found to within 1/128 of the
 * cube (plus one cell of margin). */
#define ISM_FIT_MAX_LEVEL 7
/* Work bound: interval evaluations times tape length (~0.1 s on one core); a level that
 * would exceed it is not entered and the result comes from the last level done. */
#define ISM_FIT_MAX_WORK 40000000.0

typedef struct ism_fit_box_result {
    double box[6];             /* xmin ymin zmin xmax ymax zmax; the cube when empty */
    bool empty;                /* no box kept: f has no zero in the cube */
    int level;                 /* the finest level done (cells of cube / 2^level) */
    bool complete;             /* level reached ISM_FIT_MAX_LEVEL within the work bound */
    size_t evaluations;        /* interval evaluations spent */
} ism_fit_box_result;

/* Fits the box around f = 0 within cube (min < max on each axis), padded by one cell of the
 * finest level done and clipped to the cube. False when out of memory. */
bool ism_fit_box(const ism_tape *t, const double cube[6], ism_fit_box_result *out);

#endif
