/* cut_compact.h — the cut mesh without vertices nothing uses: the crease cut welds tie copies
 * and a fallback cut leaves the first attempt's vertices behind, which would otherwise ship
 * as loose points in PLY/OBJ. */
#ifndef ISM_CUT_COMPACT_H
#define ISM_CUT_COMPACT_H

#include <stdbool.h>
#include "core/curves/cut_types.h"
#include "core/mesh/mesh.h"

/* Drops the vertices of m used by no triangle, segment or cut edge of c, keeping the others'
 * order, and renumbers the triangles, segments and cut edges. False (nothing changed) when
 * out of memory. */
bool ism_cut_compact(ism_mesh *m, ism_cut *c);

#endif
