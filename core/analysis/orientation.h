/* orientation.h — consistent orientation of each component (orientation.c), part of the
 * topology pass. */
#ifndef ISM_AN_ORIENTATION_H
#define ISM_AN_ORIENTATION_H

#include <stddef.h>
#include <stdint.h>
#include <stdbool.h>
#include "core/mesh/mesh.h"
#include "core/analysis/edges.h"

/* Sets bad[c] for every component c that cannot be oriented consistently across its
 * manifold edges; counts the manifold edges whose triangles run the same way. */
bool ism_an_orientation(const ism_mesh *m, const ism_an_edge_table *et, const uint32_t *comp,
                        uint8_t *bad, size_t *inconsistent);

#endif
