/* cut_compact.c — unused vertices dropped after the cut (cut_compact.h): one pass marks what
 * the triangles, segments and cut edges use, the kept vertices slide down in order, and every
 * index is rewritten through the map. */
#include "core/curves/cut_compact.h"
#include <stdlib.h>
#include <string.h>

#define GONE UINT32_MAX

bool ism_cut_compact(ism_mesh *m, ism_cut *c)
{
    uint32_t *map = calloc(m->nverts ? m->nverts : 1, sizeof *map);
    if (!map)
        return false;
    for (size_t i = 0; i < 3 * m->ntris; i++)
        map[m->tri[i]] = 1;
    for (size_t i = 0; i < 2 * m->nsegs; i++)
        map[m->seg[i]] = 1;
    for (size_t i = 0; i < c->nedges; i++)
        map[c->edges[i].a] = map[c->edges[i].b] = 1;
    size_t n = 0;
    for (size_t v = 0; v < m->nverts; v++) {
        if (!map[v]) {
            map[v] = GONE;
            continue;
        }
        if (n != v) {
            memcpy(m->pos + 3 * n, m->pos + 3 * v, 3 * sizeof *m->pos);
            memcpy(m->normal + 3 * n, m->normal + 3 * v, 3 * sizeof *m->normal);
        }
        map[v] = (uint32_t)n++;
    }
    if (n != m->nverts) {
        for (size_t i = 0; i < 3 * m->ntris; i++)
            m->tri[i] = map[m->tri[i]];
        for (size_t i = 0; i < 2 * m->nsegs; i++)
            m->seg[i] = map[m->seg[i]];
        for (size_t i = 0; i < c->nedges; i++) {
            c->edges[i].a = map[c->edges[i].a];
            c->edges[i].b = map[c->edges[i].b];
        }
        m->nverts = n;
    }
    free(map);
    return true;
}
