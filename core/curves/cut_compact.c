/* cut_compact.c — unused vertices dropped after the cut (cut_compact.h): the cut edges' ends
 * are kept beside what the triangles and segments use (ism_mesh_compact), and the cut edges
 * are renumbered through the same map. */
#include "core/curves/cut_compact.h"
#include <stdlib.h>

bool ism_cut_compact(ism_mesh *m, ism_cut *c)
{
    uint32_t *used = calloc(m->nverts ? m->nverts : 1, sizeof *used);
    if (!used)
        return false;
    for (size_t i = 0; i < c->nedges; i++)
        used[c->edges[i].a] = used[c->edges[i].b] = 1;
    ism_mesh_compact(m, used);
    for (size_t i = 0; i < c->nedges; i++) {
        c->edges[i].a = used[c->edges[i].a];
        c->edges[i].b = used[c->edges[i].b];
    }
    free(used);
    return true;
}
