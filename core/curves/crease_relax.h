/* crease_relax.h — thin triangles on a crease's edges mended by moving their corner off the
 * crease: a triangle whose third corner hovers over the crease edge (or nearly on one of its
 * ends) has a flat normal that is noise, and splitting it only makes more of them. */
#ifndef ISM_CREASE_RELAX_H
#define ISM_CREASE_RELAX_H

#include <stddef.h>
#include <stdint.h>
#include "core/curves/cut_internal.h"

/* A triangle on a crease edge with an angle under this is thin (degrees): its flat normal is
 * off the surface's by more than the curvature explains, and halving it keeps its shape. */
#define CREASE_RELAX_THIN_DEG 10.0

/* Per vertex: a signature of the star whose move last failed (0: none). A move is tried
 * again only once the star has changed (relax_vertex's outcome depends on nothing else): the
 * refinement calls the relaxation before each of its passes, and most candidates of one pass
 * are the last pass's, untouched. */
typedef struct cut_relax_memo {
    uint64_t *failed;
    size_t cap;
} cut_relax_memo;

void cut_relax_memo_free(cut_relax_memo *memo);

/* Each vertex off crease k that is the third corner of a triangle on one of its cut edges
 * whose smallest angle is under CREASE_RELAX_THIN_DEG goes to the centroid of its neighbours,
 * put back on its branch's zero set, when its star is a closed fan, it stays on its branch,
 * none of its triangles turns over and their smallest angle grows. *moved counts them. False when out of memory. */
bool cut_crease_relax(cut_state *s, size_t k, cut_relax_memo *memo, size_t *moved);

#endif
