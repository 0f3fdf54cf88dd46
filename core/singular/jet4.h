/* jet4.h — outward-rounded enclosures of f's derivatives up to the fourth over a box, for the
 * certificates of degenerate singular points (deflate.h, typecert.h). Third derivatives are
 * the interval Hessians of the tapes of ∂f/∂x_k, fourth those of the tapes of ∂²f/∂x_k∂x_l
 * (core/eval/tape_partial.h differentiates a tape into a tape). */
#ifndef ISM_SING_JET4_H
#define ISM_SING_JET4_H

#include <stdint.h>
#include "core/eval/eval.h"

/* f over a box: value, gradient d[i] = f_i, Hessian h[i][j] = f_ij, third t[i][j][k] = f_ijk
 * and (order 4) fourth q[i][j][k][l] = f_ijkl. Every entry encloses that derivative at every
 * point of the box (entries equal by symmetry come from different tapes and may differ in
 * width; each is a valid enclosure). */
typedef struct ism_jet4 {
    ism_interval v, d[3], h[3][3], t[3][3][3], q[3][3][3][3];
} ism_jet4;

typedef struct ism_jet4_ws ism_jet4_ws;

/* Derivatives up to order 3 or 4 (the fourth costs six more tapes). NULL when out of memory
 * or order is out of range. */
ism_jet4_ws *ism_jet4_ws_new(const ism_tape *f, int order);
void ism_jet4_ws_free(ism_jet4_ws *w);

/* Fills out over the box x (a point box [c, c] encloses the exact derivatives at c); q is
 * left untouched at order 3. *evals (may be NULL) counts interval jet evaluations. */
void ism_jet4_eval(ism_jet4_ws *w, const ism_interval x[3], ism_jet4 *out, uint64_t *evals);

#endif
