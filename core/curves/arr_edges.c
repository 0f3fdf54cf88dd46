/* arr_edges.c — the mesh's edges for the arrangement: each triangle's three edges numbered,
 * how many triangles use each, which lie on a cut curve. An edge is filed under its lower
 * vertex (a CSR of each vertex's edges to higher vertices, a few each), so numbering walks
 * the triangles twice and finding an edge scans its lower end's short list: no hash table
 * (hashing the mesh's 3 T triangle sides, with its rehashes, was about a seventh of the
 * cut and arrangement's time on the benchmark). */
#include "core/curves/arr_internal.h"
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

void arr_mesh_edges_free(arr_mesh_edges *e)
{
    free(e->lo_start);
    free(e->hi);
    free(e->tri_edge);
    free(e->ntri);
    free(e->on_curve);
    free(e->v_on_curve);
    free(e->v_used);
    memset(e, 0, sizeof *e);
}

uint32_t arr_edge_find(const arr_mesh_edges *e, uint32_t a, uint32_t b)
{
    uint32_t lo = a < b ? a : b, hi = a < b ? b : a;
    for (uint32_t k = e->lo_start[lo]; k < e->lo_start[lo + 1]; k++)
        if (e->hi[k] == hi)
            return k;
    return ARR_NO_EDGE;
}

/* Sorts list[0..n) (a vertex's higher neighbours: a handful) and drops repeats; returns the
 * count left. */
static uint32_t sort_unique(uint32_t *list, uint32_t n)
{
    for (uint32_t i = 1; i < n; i++)
        for (uint32_t j = i; j > 0 && list[j - 1] > list[j]; j--) {
            uint32_t t = list[j];
            list[j] = list[j - 1];
            list[j - 1] = t;
        }
    uint32_t k = 0;
    for (uint32_t i = 0; i < n; i++)
        if (!k || list[k - 1] != list[i])
            list[k++] = list[i];
    return k;
}

/* The corner after corner i of a triangle: side i runs from corner i to it (side s of the
 * mesh, 3 t + i, from m->tri[s] to m->tri[3 t + NEXT(i)]). Sides are walked a triangle at
 * a time: the index arithmetic of side s alone (s % 3) was half the cost of filing. */
#define NEXT(i) ((i) == 2 ? 0 : (i) + 1)

/* lo_start and hi: every triangle side filed under its lower vertex, repeats dropped. */
static bool file_edges(const ism_mesh *m, arr_mesh_edges *e)
{
    size_t nv = m->nverts, sides = 3 * m->ntris;
    uint32_t *start = calloc(nv + 2, sizeof *start);
    e->lo_start = malloc((nv + 1) * sizeof *e->lo_start);
    e->hi = malloc((sides + 1) * sizeof *e->hi);
    if (!start || !e->lo_start || !e->hi) {
        free(start);
        return false;
    }
    for (size_t t = 0; t < m->ntris; t++)
        for (int i = 0; i < 3; i++) {
            uint32_t a = m->tri[3 * t + i], b = m->tri[3 * t + NEXT(i)];
            start[(a < b ? a : b) + 2]++;
        }
    for (size_t v = 0; v < nv; v++)
        start[v + 2] += start[v + 1];
    for (size_t t = 0; t < m->ntris; t++) /* then v's sides are start[v] .. start[v + 1] */
        for (int i = 0; i < 3; i++) {
            uint32_t a = m->tri[3 * t + i], b = m->tri[3 * t + NEXT(i)];
            e->hi[start[(a < b ? a : b) + 1]++] = a < b ? b : a;
        }
    uint32_t n = 0;
    for (size_t v = 0; v < nv; v++) {
        uint32_t first = start[v], k = sort_unique(e->hi + first, start[v + 1] - first);
        e->lo_start[v] = n;
        memmove(e->hi + n, e->hi + first, k * sizeof *e->hi);
        n += k;
    }
    e->lo_start[nv] = n;
    e->n = n;
    free(start);
    return true;
}

size_t arr_mesh_edge_count(const ism_mesh *m)
{
    arr_mesh_edges e;
    memset(&e, 0, sizeof e);
    size_t n = file_edges(m, &e) ? e.n : SIZE_MAX;
    arr_mesh_edges_free(&e);
    return n;
}

bool arr_mesh_edges_build(const ism_mesh *m, const ism_cut *c, arr_mesh_edges *e)
{
    memset(e, 0, sizeof *e);
    if (!file_edges(m, e))
        goto fail;
    e->tri_edge = malloc((3 * m->ntris + 1) * sizeof *e->tri_edge);
    e->ntri = calloc(e->n + 1, sizeof *e->ntri);
    e->on_curve = calloc(e->n + 1, 1);
    e->v_on_curve = calloc(m->nverts + 1, 1);
    e->v_used = calloc(m->nverts + 1, 1);
    if (!e->tri_edge || !e->ntri || !e->on_curve || !e->v_on_curve || !e->v_used)
        goto fail;
    for (size_t t = 0; t < m->ntris; t++)
        for (int i = 0; i < 3; i++) {
            uint32_t k = arr_edge_find(e, m->tri[3 * t + i], m->tri[3 * t + NEXT(i)]);
            e->tri_edge[3 * t + i] = k;
            e->ntri[k]++;
            e->v_used[m->tri[3 * t + i]] = 1;
        }
    for (size_t i = 0; i < c->nedges; i++) {
        uint32_t k = arr_edge_find(e, c->edges[i].a, c->edges[i].b);
        if (k != ARR_NO_EDGE)
            e->on_curve[k] = 1;
        e->v_on_curve[c->edges[i].a] = e->v_on_curve[c->edges[i].b] = 1;
    }
    return true;
fail:
    arr_mesh_edges_free(e);
    return false;
}
