/* boundary.c — boundary edges chained into loops. From a boundary edge arriving at vertex w,
 * the next boundary edge is found by walking w's cone of faces across manifold edges until
 * the cone ends: at another boundary edge (the chain goes on) or at a non-manifold edge (the
 * chain ends there: the boundary arcs of crossing planes end on the crossing line). Walking
 * cones, not "the other boundary edge at w", keeps two discs that touch at a boundary vertex
 * two loops. Each cone is walked at most twice: linear. */
#include "core/analysis/boundary.h"

#include <stdlib.h>
#include <string.h>

typedef struct chain_walk {
    const ism_mesh *m;
    const ism_an_edge_table *et;
    const ism_an_vertex_facts *vf;
    uint8_t *visited; /* per edge */
} chain_walk;

static uint32_t corner_at(const uint32_t *tri, uint32_t first, uint32_t w)
{
    return tri[first] == w ? first : tri[first + 1] == w ? first + 1 : first + 2;
}

/* The boundary edge after e at its end vertex w, or ISM_AN_NONE when w's cone of faces ends on
 * a non-manifold edge first. */
static uint32_t next_boundary_edge(const chain_walk *cw, uint32_t e, uint32_t w)
{
    const ism_an_edge_table *et = cw->et;
    uint32_t h = et->edge_he[et->edge_start[e]];
    uint32_t first = h - h % 3;
    for (uint32_t steps = 0; steps <= cw->vf->corners[w]; steps++) {
        uint32_t c = corner_at(cw->m->tri, first, w);
        uint32_t ea = et->he_edge[c], eb = et->he_edge[ism_an_he_prev(c)];
        uint32_t out = ea == e ? eb : ea;
        uint32_t n = ism_an_edge_count(et, out);
        if (n == 1)
            return out;
        if (n > 2)
            return ISM_AN_NONE;
        const uint32_t *he = et->edge_he + et->edge_start[out];
        uint32_t across = he[0] - he[0] % 3 == first ? he[1] : he[0];
        first = across - across % 3;
        e = out;
    }
    return ISM_AN_NONE; /* unreachable for a consistent edge table */
}

static uint32_t far_end(const chain_walk *cw, uint32_t e, uint32_t w)
{
    uint32_t lo, hi;
    ism_an_edge_ends(cw->m, cw->et, e, &lo, &hi);
    return lo == w ? hi : lo;
}

/* Where the walk writes the vertices it passes (NULL: count only). */
typedef struct trail {
    uint32_t *v;
    size_t n;
} trail;

static void put(trail *t, uint32_t v)
{
    if (t)
        t->v[t->n++] = v;
}

/* Follows the chain from e0 out of its end w, putting every vertex reached after w on t;
 * true when it comes back to e0 (then the last vertex put is e0's other end). */
static bool follow(chain_walk *cw, uint32_t e0, uint32_t w, trail *t)
{
    uint32_t e = e0;
    for (;;) {
        uint32_t n = next_boundary_edge(cw, e, w);
        if (n == e0)
            return true;
        if (n == ISM_AN_NONE || cw->visited[n])
            return false;
        cw->visited[n] = 1;
        w = far_end(cw, n, w);
        put(t, w);
        e = n;
    }
}

/* The boundary chains as polylines (see analysis_types.h): each runs the way its first
 * edge's triangle runs it, so a loop follows the winding of its patch. */
typedef struct chains_out {
    uint32_t *start, *verts; /* as in ism_analysis */
    size_t n, nverts;
    trail back;              /* scratch: the walk out of an open chain's tail */
} chains_out;

static bool record(chain_walk *cw, chains_out *o, uint32_t e, uint32_t from, uint32_t to)
{
    size_t s = o->nverts;
    trail fwd = {o->verts + s + 1, 0};
    o->verts[s] = from;
    o->verts[s + 1] = to;
    fwd.n = 1;
    bool closed = follow(cw, e, to, &fwd);
    if (!closed) { /* open: prepend the walk out of the tail, reversed */
        o->back.n = 0;
        follow(cw, e, from, &o->back);
        memmove(o->verts + s + o->back.n, o->verts + s, (fwd.n + 1) * sizeof *o->verts);
        for (size_t i = 0; i < o->back.n; i++)
            o->verts[s + i] = o->back.v[o->back.n - 1 - i];
        fwd.n += o->back.n;
    }
    o->nverts = s + fwd.n + 1;
    o->start[++o->n] = (uint32_t)o->nverts;
    return closed;
}

/* The directed boundary edge e as its triangle runs it. */
static void direction(const ism_mesh *m, const ism_an_edge_table *et, uint32_t e,
                      uint32_t *from, uint32_t *to)
{
    uint32_t h = et->edge_he[et->edge_start[e]];
    *from = m->tri[h];
    *to = m->tri[ism_an_he_next(h)];
}

bool ism_an_boundary_chains(const ism_mesh *m, const ism_an_edge_table *et,
                            const ism_an_vertex_facts *vf, const uint32_t *comp, ism_analysis *a)
{
    size_t nb = 0;
    for (uint32_t e = 0; e < et->nedges; e++)
        nb += ism_an_edge_count(et, e) == 1;
    chain_walk cw = {m, et, vf, calloc(et->nedges ? et->nedges : 1, 1)};
    /* each chain holds its edges + 1 vertices: at most 2 per boundary edge in all */
    chains_out o = {malloc((nb + 1) * sizeof *o.start), malloc((2 * nb + 1) * sizeof *o.verts),
                    0, 0, {malloc((nb + 1) * sizeof *o.back.v), 0}};
    bool ok = cw.visited && o.start && o.verts && o.back.v;
    if (ok)
        o.start[0] = 0;
    for (uint32_t e = 0; ok && e < et->nedges; e++) {
        if (ism_an_edge_count(et, e) != 1 || cw.visited[e])
            continue;
        cw.visited[e] = 1;
        uint32_t from, to;
        direction(m, et, e, &from, &to);
        ism_component *c = &a->component[comp[et->edge_he[et->edge_start[e]] / 3]];
        if (record(&cw, &o, e, from, to)) {
            a->boundary_loops++;
            c->boundary_loops++;
        } else {
            a->boundary_chains++;
            c->boundary_chains++;
        }
    }
    free(cw.visited);
    free(o.back.v);
    if (!ok) {
        free(o.start);
        free(o.verts);
        return false;
    }
    a->nboundaries = o.n;
    a->boundary_start = o.start;
    a->boundary_verts = o.verts;
    return true;
}
