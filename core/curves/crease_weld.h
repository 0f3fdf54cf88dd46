/* crease_weld.h — tie vertices (f ties there: on a crease) that are one point computed twice:
 * under an error bound the polygoniser makes a crease point in each leaf that meets it
 * (octree/crease_split.h), and where the crease lies on a lattice plane those copies sit a
 * rounding apart, joined by triangles of no area that carry no branch. */
#ifndef ISM_CREASE_WELD_H
#define ISM_CREASE_WELD_H

#include <stddef.h>
#include <stdint.h>
#include "core/mesh/mesh.h"

/* Renames in tri (nt triangles of m, 3 corners each) every tie vertex (label[v] equal to
 * none) within tol of an earlier tie vertex to that one, so each such point is one vertex.
 * Triangles left with a repeated corner are no triangles: the caller skips them. Returns how
 * many vertices were renamed, or SIZE_MAX when out of memory (tri then unchanged). */
size_t ism_crease_weld_ties(const ism_mesh *m, const uint32_t *label, uint32_t none, double tol,
                            uint32_t *tri, size_t nt);

#endif
