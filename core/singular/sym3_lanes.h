/* sym3_lanes.h — ism_sym3_pinv_step (core/util/sym3.h) for many Hessians at once: the Jacobi
 * sweeps of four matrices side by side, each lane the scalar sweeps' IEEE operations in their
 * order, so every step is bit for bit the scalar one. For the singular search's Newton runs
 * in lanes (newton.h, ism_sing_newton_lanes), where the sweeps were most of a step's cost. */
#ifndef ISM_SYM3_LANES_H
#define ISM_SYM3_LANES_H

#include <stdbool.h>
#include <stddef.h>

/* ok[i] = ism_sym3_pinv_step(g[i], h[i], rel[i], trust[i], step[i]) for i < n. */
void ism_sym3_pinv_lanes(const double (*g)[3], const double (*h)[6], const double *rel,
                         const double *trust, double (*step)[3], bool *ok, size_t n);

#endif
