/* resolvable.h — can the octree resolve f at all? A coarse pass before polygonising that
 * tells hopeless work from expensive work in milliseconds, so that a request which would
 * refine every cell to depth.max (and hold a worker to its deadline) is refused instead:
 *
 *  - f is 0 on a volume (a constant 0, x - x, min(x, 0)): every cell holds "surface";
 *  - f varies faster than any cell can resolve (sin(1e300 x)): its interval enclosure over a
 *    cell does not shrink with the cell, even far below the deepest depth a request may ask.
 *
 * Expensive but resolvable surfaces (fine detail, long tapes, deep requests) pass. */
#ifndef ISM_RESOLVABLE_H
#define ISM_RESOLVABLE_H

#include <stddef.h>

#include "core/expr/expr.h"

typedef enum ism_resolvable {
    ISM_RESOLVABLE_OK = 0,
    ISM_RESOLVABLE_ZERO_VOLUME,  /* f is exactly 0 at most sample points */
    ISM_RESOLVABLE_TOO_FINE,     /* f's enclosure does not shrink with the cell */
    ISM_RESOLVABLE_NO_MEMORY,
} ism_resolvable;

/* Samples f near its zero set inside box (x0 y0 z0 x1 y1 z1) and says whether the octree can
 * resolve it; why gets a sentence for the user when it cannot. Costs at most a few thousand
 * interval evaluations of t (fewer for long tapes). Deterministic. */
ism_resolvable ism_resolvable_check(const ism_tape *t, const double box[6], char *why,
                                    size_t n);

#endif
