/* components.c — connected components of a mesh: triangles joined by shared edges (of any
 * kind: a non-manifold edge joins its sheets), numbered in order of their smallest triangle;
 * and the coarser components of vertices joined by triangles (two cones meeting at a Kummer
 * node are two edge components but one vertex component). Union-find, near-linear. */
#include "core/analysis/components.h"
#include "core/analysis/unionfind.h"

#include <stdlib.h>

bool ism_an_edge_components(const ism_mesh *m, const ism_an_edge_table *et, uint32_t *comp,
                            size_t *ncomp)
{
    for (size_t t = 0; t < m->ntris; t++)
        comp[t] = (uint32_t)t;
    for (uint32_t e = 0; e < et->nedges; e++) {
        const uint32_t *he = et->edge_he + et->edge_start[e];
        for (uint32_t i = 1; i < ism_an_edge_count(et, e); i++)
            ism_an_uf_union(comp, he[0] / 3, he[i] / 3);
    }
    /* Every parent is at most its child, so in ascending order a triangle's parent has
     * already been given its component number. */
    size_t n = 0;
    for (size_t t = 0; t < m->ntris; t++) {
        if (ism_an_tri_collapsed(m->tri, t))
            comp[t] = ISM_AN_NONE;
        else if (comp[t] == t)
            comp[t] = (uint32_t)n++;
        else
            comp[t] = comp[comp[t]];
    }
    *ncomp = n;
    return true;
}

bool ism_an_vertex_components(const ism_mesh *m, const ism_an_vertex_facts *vf, size_t *n)
{
    uint32_t *parent = malloc((m->nverts ? m->nverts : 1) * sizeof *parent);
    if (!parent)
        return false;
    for (size_t v = 0; v < m->nverts; v++)
        parent[v] = (uint32_t)v;
    for (size_t t = 0; t < m->ntris; t++) {
        if (ism_an_tri_collapsed(m->tri, t))
            continue;
        const uint32_t *c = m->tri + 3 * t;
        ism_an_uf_union(parent, c[0], c[1]);
        ism_an_uf_union(parent, c[1], c[2]);
    }
    *n = 0;
    for (size_t v = 0; v < m->nverts; v++)
        *n += vf->corners[v] > 0 && parent[v] == v;
    free(parent);
    return true;
}
