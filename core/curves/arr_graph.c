/* arr_graph.c — the arrangement's vertices, edges and curves from the cut edges: a mesh
 * vertex is an arrangement vertex where a curve meets the singular locus (a singular point,
 * a double curve), where curves of two functions meet, where one curve has other than two
 * cut edges (a branch or an end), and once on each closed curve that meets nothing; edges
 * are the chains of cut edges between them; a curve is the arcs of one function joined
 * through its own vertices, except at the singular locus, where its arcs end. */
#include "core/curves/arr_internal.h"
#include "core/util/grow.h"
#include "core/util/vec3.h"
#include <math.h>
#include <stdlib.h>
#include <string.h>

/* First capacity of the growable arrays: arrangements have tens of vertices and edges. */
#define GRAPH_FIRST 64

#define NONE UINT32_MAX

typedef struct graph {
    const ism_mesh *m;
    const ism_cut *c;
    const uint32_t *sing;   /* per vertex: arr_singular_marks */
    ism_arrangement *a;
    uint32_t *start, *adj;  /* per vertex: its cut edges adj[start[v] .. start[v+1]) */
    uint32_t *fn1;          /* per vertex: the function of its first cut edge */
    uint8_t *multi;         /* per vertex: cut edges of two functions meet */
    uint32_t *avid;         /* per vertex: arrangement vertex or NONE */
    uint8_t *seen;          /* per cut edge */
    size_t cap_v, cap_e, cap_chain;
} graph;

static bool build_adjacency(graph *g)
{
    size_t nv = g->m->nverts, ne = g->c->nedges;
    g->start = calloc(nv + 2, sizeof *g->start);
    g->adj = malloc((2 * ne + 1) * sizeof *g->adj);
    g->fn1 = malloc((nv + 1) * sizeof *g->fn1);
    g->multi = calloc(nv + 1, 1);
    g->avid = malloc((nv + 1) * sizeof *g->avid);
    g->seen = calloc(ne + 1, 1);
    if (!g->start || !g->adj || !g->fn1 || !g->multi || !g->avid || !g->seen)
        return false;
    memset(g->fn1, 0xff, (nv + 1) * sizeof *g->fn1);
    memset(g->avid, 0xff, (nv + 1) * sizeof *g->avid);
    for (size_t i = 0; i < ne; i++) {
        const ism_cut_edge *e = &g->c->edges[i];
        g->start[e->a + 2]++;
        g->start[e->b + 2]++;
        for (int k = 0; k < 2; k++) {
            uint32_t v = k ? e->b : e->a;
            if (g->fn1[v] == NONE)
                g->fn1[v] = e->fn;
            else if (g->fn1[v] != e->fn)
                g->multi[v] = 1;
        }
    }
    for (size_t v = 0; v < nv; v++)
        g->start[v + 2] += g->start[v + 1];
    for (size_t i = 0; i < ne; i++) {
        g->adj[g->start[g->c->edges[i].a + 1]++] = (uint32_t)i;
        g->adj[g->start[g->c->edges[i].b + 1]++] = (uint32_t)i;
    }
    return true;
}

static bool add_vertex(graph *g, uint32_t v, int type, int point)
{
    ism_arrangement *a = g->a;
    if (!ism_grow((void **)&a->vertices, &g->cap_v, a->nvertices + 1, sizeof *a->vertices, GRAPH_FIRST))
        return false;
    g->avid[v] = (uint32_t)a->nvertices;
    a->vertices[a->nvertices++] =
        (ism_arr_vertex){.v = v, .degree = (int)(g->start[v + 1] - g->start[v]), .type = type,
                         .point = point};
    return true;
}

static bool push_chain(graph *g, uint32_t v)
{
    ism_arrangement *a = g->a;
    if (!ism_grow((void **)&a->chain, &g->cap_chain, a->nchain + 1, sizeof *a->chain, GRAPH_FIRST))
        return false;
    a->chain[a->nchain++] = v;
    return true;
}

static double seg_length(const ism_mesh *m, uint32_t a, uint32_t b)
{
    return ism_dist3(m->pos + 3 * (size_t)a, m->pos + 3 * (size_t)b);
}

/* The arc leaving arrangement vertex at mesh vertex v through cut edge ce. */
static bool walk(graph *g, uint32_t v, uint32_t ce)
{
    ism_arr_edge e = {.from = g->avid[v], .fn = g->c->edges[ce].fn, .first = g->a->nchain};
    if (!push_chain(g, v))
        return false;
    for (;;) {
        g->seen[ce] = 1;
        const ism_cut_edge *c = &g->c->edges[ce];
        uint32_t w = c->a == v ? c->b : c->a;
        e.length += seg_length(g->m, v, w);
        if (!push_chain(g, w))
            return false;
        v = w;
        if (g->avid[v] != NONE)
            break;
        uint32_t next = NONE;
        for (uint32_t i = g->start[v]; i < g->start[v + 1]; i++)
            if (!g->seen[g->adj[i]])
                next = g->adj[i];
        if (next == NONE) /* cannot happen on a degree-2 vertex unless revisited */
            break;
        ce = next;
    }
    e.to = g->avid[v] != NONE ? g->avid[v] : e.from;
    e.count = g->a->nchain - e.first;
    ism_arrangement *a = g->a;
    if (!ism_grow((void **)&a->edges, &g->cap_e, a->nedges + 1, sizeof *a->edges, GRAPH_FIRST))
        return false;
    a->edges[a->nedges++] = e;
    return true;
}

static bool walk_from(graph *g, uint32_t v)
{
    for (uint32_t i = g->start[v]; i < g->start[v + 1]; i++)
        if (!g->seen[g->adj[i]] && !walk(g, v, g->adj[i]))
            return false;
    return true;
}

/* The type of curve vertex v of deg cut edges, or -1 when it is inside an arc. */
static int vertex_type(const graph *g, size_t v, uint32_t deg)
{
    if (deg == 0)
        return -1;
    if (g->sing[v] == ARR_SING_DOUBLE)
        return ISM_ARR_DOUBLE_CURVE;
    if (g->sing[v] != ARR_SING_NONE)
        return ISM_ARR_SINGULAR_POINT;
    if (deg == 2 && !g->multi[v])
        return -1;
    return g->multi[v] ? ISM_ARR_CROSSING : deg == 1 ? ISM_ARR_END : ISM_ARR_BRANCH;
}

static bool vertices_and_edges(graph *g)
{
    for (size_t v = 0; v < g->m->nverts; v++) {
        int type = vertex_type(g, v, g->start[v + 1] - g->start[v]);
        int point = type == ISM_ARR_SINGULAR_POINT ? (int)g->sing[v] : -1;
        if (type >= 0 && !add_vertex(g, (uint32_t)v, type, point))
            return false;
    }
    for (size_t i = 0; i < g->a->nvertices; i++)
        if (!walk_from(g, g->a->vertices[i].v))
            return false;
    for (size_t i = 0; i < g->c->nedges; i++) /* closed curves meeting nothing */
        if (!g->seen[i]) {
            uint32_t v = g->c->edges[i].a;
            if (!add_vertex(g, v, ISM_ARR_LOOP, -1) || !walk_from(g, v))
                return false;
        }
    return true;
}

typedef struct end_ref {
    uint32_t vertex, fn, edge;
} end_ref;

/* The 2 ne edge ends into r ordered by (vertex, fn, edge): counted into their vertices in
 * edge order, then each vertex's few ends put in fn order by insertion (stable). (qsort
 * of the ends was 2% of the benchmark's cut and arrangement.) False when out of memory. */
static bool sort_ends(const ism_arrangement *a, end_ref *r)
{
    size_t ne = a->nedges, nv = a->nvertices;
    uint32_t *start = calloc(nv + 2, sizeof *start);
    if (!start)
        return false;
    for (size_t i = 0; i < ne; i++) {
        start[a->edges[i].from + 2]++;
        start[a->edges[i].to + 2]++;
    }
    for (size_t v = 0; v < nv; v++)
        start[v + 2] += start[v + 1];
    for (size_t i = 0; i < ne; i++) { /* then v's ends are start[v] .. start[v + 1] */
        const ism_arr_edge *e = &a->edges[i];
        r[start[e->from + 1]++] = (end_ref){e->from, e->fn, (uint32_t)i};
        r[start[e->to + 1]++] = (end_ref){e->to, e->fn, (uint32_t)i};
    }
    for (size_t v = 0; v < nv; v++)
        for (uint32_t i = start[v] + 1; i < start[v + 1]; i++)
            for (uint32_t j = i; j > start[v] && r[j - 1].fn > r[j].fn; j--) {
                end_ref t = r[j];
                r[j] = r[j - 1];
                r[j - 1] = t;
            }
    free(start);
    return true;
}

/* Whether a curve ends at vertex type t (its arcs are not joined there). */
static bool ends_at(int t)
{
    return t == ISM_ARR_END || t == ISM_ARR_DOUBLE_CURVE || t == ISM_ARR_SINGULAR_POINT;
}

/* Curves: arcs of one function sharing an arrangement vertex are one curve, except where
 * they meet the singular locus: there each arc ends. */
static bool curves(ism_arrangement *a)
{
    size_t ne = a->nedges;
    end_ref *r = malloc((2 * ne + 1) * sizeof *r);
    uint32_t *par = malloc((ne + 1) * sizeof *par), *id = malloc((ne + 1) * sizeof *id);
    bool ok = r && par && id && sort_ends(a, r);
    if (ok) {
        for (size_t i = 0; i < ne; i++)
            par[i] = (uint32_t)i;
        for (size_t i = 1; i < 2 * ne; i++)
            if (r[i].vertex == r[i - 1].vertex && r[i].fn == r[i - 1].fn &&
                !ends_at(a->vertices[r[i].vertex].type))
                (void)ism_an_uf_union(par, r[i].edge, r[i - 1].edge);
        a->ncurves = 0;
        for (size_t i = 0; i < ne; i++)
            id[i] = ism_an_uf_find(par, (uint32_t)i) == i ? (uint32_t)a->ncurves++ : NONE;
        a->curves = calloc(a->ncurves + 1, sizeof *a->curves);
        ok = a->curves != NULL;
    }
    for (size_t i = 0; ok && i < ne; i++) {
        ism_arr_edge *e = &a->edges[i];
        e->curve = id[ism_an_uf_find(par, (uint32_t)i)];
        ism_arr_curve *c = &a->curves[e->curve];
        if (!c->nedges)
            c->closed = true;
        c->fn = e->fn;
        c->length += e->length;
        c->nedges++;
        if (ends_at(a->vertices[e->from].type) || ends_at(a->vertices[e->to].type))
            c->closed = false;
    }
    free(r);
    free(par);
    free(id);
    return ok;
}

bool arr_build_graph(const ism_mesh *m, const ism_cut *c, const uint32_t *sing,
                     ism_arrangement *a)
{
    graph g = {.m = m, .c = c, .sing = sing, .a = a};
    bool ok = build_adjacency(&g) && vertices_and_edges(&g) && curves(a);
    free(g.start);
    free(g.adj);
    free(g.fn1);
    free(g.multi);
    free(g.avid);
    free(g.seen);
    return ok;
}
