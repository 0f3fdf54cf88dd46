/* rm_compact.c — the renumbering at the end of the pass: dead triangles and gone vertices
 * leave the mesh, the vertices keep their order (inserted ones after the others), the
 * triangles are ordered by the triangle before the pass each lies in (their origin), and the
 * maps are handed to the caller for what it keeps beside the mesh. */
#include "core/remesh/rm_pass.h"

#include <stdlib.h>
#include <string.h>

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

/* The live triangles in order of origin (then of index): a counting sort over the nbefore
 * origins. order gets them; returns how many. */
static size_t order_by_origin(const rm_mesh *r, size_t nbefore, uint32_t *first, uint32_t *order)
{
    size_t nt = r->m->ntris;
    memset(first, 0, (nbefore + 1) * sizeof *first);
    for (size_t t = 0; t < nt; t++)
        first[r->origin[t] + 1] += !r->dead[t];
    for (size_t i = 0; i < nbefore; i++)
        first[i + 1] += first[i];
    for (size_t t = 0; t < nt; t++)
        if (!r->dead[t])
            order[first[r->origin[t]]++] = (uint32_t)t;
    return first[nbefore];
}

bool rm_compact(rm_mesh *r, size_t nverts_before, size_t ntris_before, ism_remesh_renumber *ren)
{
    ism_mesh *m = r->m;
    collapse_dead(r);
    uint32_t *vmap = malloc((m->nverts ? m->nverts : 1) * sizeof *vmap);
    uint32_t *order = malloc((m->ntris ? m->ntris : 1) * sizeof *order);
    uint32_t *first = malloc((ntris_before + 1) * sizeof *first);
    uint32_t *tri = malloc((m->ntris ? m->ntris : 1) * 3 * sizeof *tri);
    bool ok = vmap && order && first && tri;
    if (ok) {
        size_t nv = 0, nt = order_by_origin(r, ntris_before, first, order);
        for (size_t v = 0; v < m->nverts; v++) {
            vmap[v] = r->gone[v] ? ISM_REMESH_GONE : (uint32_t)nv++;
            if (vmap[v] != ISM_REMESH_GONE) {
                memmove(m->pos + 3 * vmap[v], m->pos + 3 * v, 3 * sizeof *m->pos);
                memmove(m->normal + 3 * vmap[v], m->normal + 3 * v, 3 * sizeof *m->normal);
            }
        }
        for (size_t i = 0; i < nt; i++) {
            for (int k = 0; k < 3; k++)
                tri[3 * i + k] = vmap[m->tri[3 * (size_t)order[i] + k]];
            order[i] = r->origin[order[i]];
        }
        memcpy(m->tri, tri, 3 * nt * sizeof *tri);
        for (size_t s = 0; s < 2 * m->nsegs; s++) /* a segment's vertices are locked: kept */
            m->seg[s] = vmap[m->seg[s]];
        m->nverts = nv;
        m->ntris = nt;
        if (ren) {
            ren->vert = vmap, ren->origin = order;
            ren->nverts = nverts_before, ren->ntris = ntris_before, ren->ntris_after = nt;
            vmap = order = NULL;
        }
    }
    free(vmap);
    free(order);
    free(first);
    free(tri);
    return ok;
}
