/* crease_label.h — f's branch (branches.h) at every vertex of a mesh, a box of vertices at a
 * time where the box decides it. */
#ifndef ISM_CREASE_LABEL_H
#define ISM_CREASE_LABEL_H

#include <stdbool.h>
#include <stdint.h>
#include "core/curves/branches.h"
#include "core/mesh/mesh.h"

/* label[v] = ism_branches_at(b, vertex v) for every vertex, the same values and the branches
 * numbered in the same order (vertex order). False when out of memory. */
bool cut_crease_label(ism_branches *b, const ism_mesh *m, uint32_t *label);

#endif
