/* curves.c — non-manifold edges chained into curves, and the non-manifold points. A chain
 * runs on through every vertex where exactly two non-manifold edges meet and stops at every
 * other vertex: a free end (one edge) or a junction (three or more, such as the triple point
 * of Steiner's surface), which become points beside the class-3 vertices where several cones
 * of faces meet. Linear in the number of non-manifold edges (plus one pass over vertices). */
#include "core/analysis/curves.h"

#include <stdlib.h>
#include <string.h>

typedef struct curve_builder {
    const ism_mesh *m;
    const ism_an_edge_table *et;
    const uint32_t *degree; /* non-manifold edges per vertex */
    uint32_t *adj_start;    /* per vertex: its non-manifold edges adj[adj_start[v] ..] */
    uint32_t *adj;
    uint8_t *visited;       /* per edge */
    ism_analysis *a;
    size_t nverts_out;
} curve_builder;

static uint32_t other_end(const curve_builder *cb, uint32_t e, uint32_t v)
{
    uint32_t lo, hi;
    ism_an_edge_ends(cb->m, cb->et, e, &lo, &hi);
    return lo == v ? hi : lo;
}

/* The non-manifold edge at a degree-2 vertex v that is not e. */
static uint32_t continuation(const curve_builder *cb, uint32_t v, uint32_t e)
{
    const uint32_t *adj = cb->adj + cb->adj_start[v];
    return adj[0] == e ? adj[1] : adj[0];
}

/* Follows the chain that leaves v along e until a vertex that is not of degree 2, or back to
 * where it started, and records it as one curve. */
static void walk_curve(curve_builder *cb, uint32_t v, uint32_t e)
{
    ism_analysis *a = cb->a;
    a->curve_verts[cb->nverts_out++] = v;
    for (;;) {
        cb->visited[e] = 1;
        uint32_t w = other_end(cb, e, v);
        a->curve_verts[cb->nverts_out++] = w;
        if (cb->degree[w] != 2)
            break;
        uint32_t next = continuation(cb, w, e);
        if (cb->visited[next])
            break; /* closed the loop */
        v = w;
        e = next;
    }
    a->curve_start[++a->ncurves] = (uint32_t)cb->nverts_out;
}

static bool build_adjacency(curve_builder *cb)
{
    size_t nv = cb->m->nverts, nm = cb->a->nonmanifold_edges;
    cb->adj_start = malloc((nv + 1) * sizeof *cb->adj_start);
    cb->adj = malloc(2 * nm * sizeof *cb->adj);
    cb->visited = calloc(cb->et->nedges, 1);
    if (!cb->adj_start || !cb->adj || !cb->visited)
        return false;
    cb->adj_start[0] = 0;
    for (size_t v = 0; v < nv; v++)
        cb->adj_start[v + 1] = cb->adj_start[v] + cb->degree[v];
    uint32_t *fill = malloc((nv ? nv : 1) * sizeof *fill);
    if (!fill)
        return false;
    memcpy(fill, cb->adj_start, nv * sizeof *fill);
    for (uint32_t e = 0; e < cb->et->nedges; e++)
        if (ism_an_edge_count(cb->et, e) >= 3) {
            uint32_t lo, hi;
            ism_an_edge_ends(cb->m, cb->et, e, &lo, &hi);
            cb->adj[fill[lo]++] = e;
            cb->adj[fill[hi]++] = e;
        }
    free(fill);
    return true;
}

static void chain_all(curve_builder *cb)
{
    /* open chains: from every end point and junction, along each edge not yet walked */
    for (uint32_t v = 0; v < cb->m->nverts; v++)
        if (cb->degree[v] != 0 && cb->degree[v] != 2)
            for (uint32_t i = cb->adj_start[v]; i < cb->adj_start[v + 1]; i++)
                if (!cb->visited[cb->adj[i]])
                    walk_curve(cb, v, cb->adj[i]);
    /* what is left are closed loops through degree-2 vertices only; the first edge left in
     * edge order starts at its loop's smallest vertex */
    for (uint32_t e = 0; e < cb->et->nedges; e++)
        if (ism_an_edge_count(cb->et, e) >= 3 && !cb->visited[e]) {
            uint32_t lo, hi;
            ism_an_edge_ends(cb->m, cb->et, e, &lo, &hi);
            walk_curve(cb, lo, e);
        }
}

bool ism_an_find_curves(const ism_mesh *m, const ism_an_edge_table *et,
                        const ism_an_vertex_facts *vf, ism_analysis *a)
{
    size_t nm = a->nonmanifold_edges;
    a->ncurves = 0;
    a->curve_start = malloc((nm + 1) * sizeof *a->curve_start);
    a->curve_verts = malloc((2 * nm + 1) * sizeof *a->curve_verts);
    if (!a->curve_start || !a->curve_verts)
        return false;
    a->curve_start[0] = 0;
    if (nm == 0)
        return true;
    curve_builder cb = {.m = m, .et = et, .degree = vf->nm_degree, .a = a};
    bool ok = build_adjacency(&cb);
    if (ok)
        chain_all(&cb);
    free(cb.adj_start);
    free(cb.adj);
    free(cb.visited);
    return ok;
}

static int point_kind(const ism_analysis *a, const ism_an_vertex_facts *vf, size_t v)
{
    if (a->vertex_class[v] == ISM_VERTEX_NONMANIFOLD_POINT)
        return ISM_POINT_CONES;
    if (vf->nm_degree[v] == 1)
        return ISM_POINT_CURVE_END;
    if (vf->nm_degree[v] >= 3)
        return ISM_POINT_JUNCTION;
    return -1;
}

bool ism_an_find_points(const ism_mesh *m, const ism_an_vertex_facts *vf, ism_analysis *a)
{
    size_t n = 0;
    for (size_t v = 0; v < m->nverts; v++)
        n += point_kind(a, vf, v) >= 0;
    a->points = malloc((n ? n : 1) * sizeof *a->points);
    a->point_kind = malloc(n ? n : 1);
    a->point_pos = malloc((n ? 3 * n : 1) * sizeof *a->point_pos);
    if (!a->points || !a->point_kind || !a->point_pos)
        return false;
    a->npoints = 0;
    for (size_t v = 0; v < m->nverts; v++) {
        int kind = point_kind(a, vf, v);
        if (kind < 0)
            continue;
        size_t i = a->npoints++;
        a->points[i] = (uint32_t)v;
        a->point_kind[i] = (uint8_t)kind;
        memcpy(a->point_pos + 3 * i, m->pos + 3 * v, 3 * sizeof(double));
    }
    return true;
}
