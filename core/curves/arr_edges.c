/* arr_edges.c — the mesh's edges for the arrangement: each triangle's three edges numbered
 * through a key map, how many triangles use each, which lie on a cut curve; and the
 * union-find the faces and components are made with. */
#include "core/curves/arr_internal.h"
#include <stdlib.h>
#include <string.h>

uint64_t arr_edge_key(uint32_t a, uint32_t b)
{
    return a < b ? ((uint64_t)a << 32) | b : ((uint64_t)b << 32) | a;
}

void arr_mesh_edges_free(arr_mesh_edges *e)
{
    ism_key_map_free(&e->map);
    free(e->tri_edge);
    free(e->ntri);
    free(e->on_curve);
    free(e->v_on_curve);
    free(e->v_used);
    memset(e, 0, sizeof *e);
}

bool arr_mesh_edges_build(const ism_mesh *m, const ism_cut *c, arr_mesh_edges *e)
{
    memset(e, 0, sizeof *e);
    ism_key_map_init(&e->map);
    size_t cap = 3 * m->ntris + 1;
    e->tri_edge = malloc(cap * sizeof *e->tri_edge);
    e->ntri = calloc(cap, sizeof *e->ntri);
    e->on_curve = calloc(cap, 1);
    e->v_on_curve = calloc(m->nverts + 1, 1);
    e->v_used = calloc(m->nverts + 1, 1);
    if (!e->tri_edge || !e->ntri || !e->on_curve || !e->v_on_curve || !e->v_used)
        goto fail;
    for (size_t t = 0; t < m->ntris; t++)
        for (int i = 0; i < 3; i++) {
            uint32_t a = m->tri[3 * t + i], b = m->tri[3 * t + (i + 1) % 3];
            bool added;
            uint32_t k = ism_key_map_add(&e->map, arr_edge_key(a, b), &added);
            if (k == ISM_KEY_NONE)
                goto fail;
            e->tri_edge[3 * t + i] = k;
            e->ntri[k]++;
            e->v_used[a] = 1;
        }
    e->n = e->map.n;
    for (size_t i = 0; i < c->nedges; i++) {
        uint32_t k = ism_key_map_find(&e->map, arr_edge_key(c->edges[i].a, c->edges[i].b));
        if (k != ISM_KEY_NONE)
            e->on_curve[k] = 1;
        e->v_on_curve[c->edges[i].a] = e->v_on_curve[c->edges[i].b] = 1;
    }
    return true;
fail:
    arr_mesh_edges_free(e);
    return false;
}
