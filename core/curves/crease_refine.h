/* crease_refine.h — after the crease is cut, the triangles beside it refined until their own
 * (flat) normals are their branch's normal along the crease, so the mesh's dihedral angle
 * there is the angle between the two branches' gradients. */
#ifndef ISM_CREASE_REFINE_H
#define ISM_CREASE_REFINE_H

#include <stddef.h>
#include "core/curves/cut_internal.h"

/* Pass after pass, each triangle on a cut edge of crease k whose flat normal is more than
 * CREASE_REFINE_DEG off its branch's gradient at the edge's midpoint is split in four at its
 * edges' midpoints (the crease edge's on both branches, the others on the triangle's branch),
 * its neighbours split in two or three to match: the mesh keeps its topology, the crease its
 * cut edges (halved where split). *added counts the new vertices. False when out of memory. */
bool cut_crease_refine(cut_state *s, size_t k, size_t *added);

#endif
