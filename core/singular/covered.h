/* covered.h — which candidate boxes of the singular search the polygoniser's mesh already
 * covers. A double sheet lying exactly on a lattice plane (x² in a box symmetric about
 * x = 0) is met by the polygoniser itself, which emits a tile where f vanishes on all of it;
 * the double-sheet stage must not mesh it a second time. */
#ifndef ISM_COVERED_H
#define ISM_COVERED_H

#include <stdbool.h>
#include "core/mesh/mesh.h"
#include "core/singular/locus.h"

/* Flags ISM_LBOX_USED on every finest box of l->boxes (side box / 2^max_depth) that holds a
 * corner of a triangle of m (on its boundary included; segments and lone vertices cover
 * nothing). O(T + V + boxes) time, O(V + boxes) memory. False when out of memory. */
bool ism_locus_mark_covered(ism_locus *l, const ism_locus_options *o, const ism_mesh *m);

#endif
