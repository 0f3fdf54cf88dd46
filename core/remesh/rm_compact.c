/* rm_compact.c — the renumbering after collapses: dead triangles and gone vertices leave the
 * mesh, everything else keeps its order, and the maps from old to new indices are handed to
 * the caller for what it keeps beside the mesh. */
#include "core/remesh/rm_pass.h"

#include <stdlib.h>
#include <string.h>

void ism_remesh_renumber_free(ism_remesh_renumber *ren)
{
    free(ren->vert);
    free(ren->tri);
    memset(ren, 0, sizeof *ren);
}

/* Dead triangles with one repeated corner (a collapsed triangle, which every reader skips):
 * the mesh stays valid even if the renumbering cannot be made. */
static void collapse_dead(rm_mesh *r)
{
    for (size_t t = 0; t < r->m->ntris; t++)
        if (r->dead[t]) {
            uint32_t *c = r->m->tri + 3 * t;
            uint32_t keep = r->gone[c[0]] ? (r->gone[c[1]] ? c[2] : c[1]) : c[0];
            c[0] = c[1] = c[2] = keep;
        }
}

/* map[i] = the new index of kept element i (in order), ISM_REMESH_GONE for dropped; returns
 * how many are kept. */
static size_t number(const uint8_t *drop, size_t n, uint32_t *map)
{
    size_t k = 0;
    for (size_t i = 0; i < n; i++)
        map[i] = drop[i] ? ISM_REMESH_GONE : (uint32_t)k++;
    return k;
}

bool rm_compact(rm_mesh *r, ism_remesh_renumber *ren)
{
    ism_mesh *m = r->m;
    collapse_dead(r);
    uint32_t *vmap = malloc((m->nverts ? m->nverts : 1) * sizeof *vmap);
    uint32_t *tmap = malloc((m->ntris ? m->ntris : 1) * sizeof *tmap);
    if (!vmap || !tmap) {
        free(vmap);
        free(tmap);
        return false;
    }
    size_t nv = number(r->gone, m->nverts, vmap), nt = number(r->dead, m->ntris, tmap);
    for (size_t v = 0; v < m->nverts; v++)
        if (vmap[v] != ISM_REMESH_GONE) {
            memmove(m->pos + 3 * vmap[v], m->pos + 3 * v, 3 * sizeof *m->pos);
            memmove(m->normal + 3 * vmap[v], m->normal + 3 * v, 3 * sizeof *m->normal);
        }
    for (size_t t = 0; t < m->ntris; t++)
        for (int k = 0; tmap[t] != ISM_REMESH_GONE && k < 3; k++)
            m->tri[3 * tmap[t] + k] = vmap[m->tri[3 * t + k]];
    for (size_t s = 0; s < 2 * m->nsegs; s++) /* a segment's vertices are locked: never gone */
        m->seg[s] = vmap[m->seg[s]];
    if (ren) {
        ren->vert = vmap, ren->tri = tmap;
        ren->nverts = m->nverts, ren->ntris = m->ntris;
    } else {
        free(vmap);
        free(tmap);
    }
    m->nverts = nv;
    m->ntris = nt;
    return true;
}
