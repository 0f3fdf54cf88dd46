/* boundary.c — boundary edges chained into loops. From a boundary edge arriving at vertex w,
 * the next boundary edge is found by walking w's cone of faces across manifold edges until
 * the cone ends: at another boundary edge (the chain goes on) or at a non-manifold edge (the
 * chain ends there: the boundary arcs of crossing planes end on the crossing line). Walking
 * cones, not "the other boundary edge at w", keeps two discs that touch at a boundary vertex
 * two loops. Each cone is walked at most twice: linear. */
#include "core/analysis/boundary.h"

#include <stdlib.h>

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

/* Follows the chain from e0 out of its end w; true when it comes back to e0. */
static bool follow(chain_walk *cw, uint32_t e0, uint32_t w)
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
        e = n;
    }
}

bool ism_an_boundary_chains(const ism_mesh *m, const ism_an_edge_table *et,
                            const ism_an_vertex_facts *vf, const uint32_t *comp, ism_analysis *a)
{
    chain_walk cw = {m, et, vf, calloc(et->nedges ? et->nedges : 1, 1)};
    if (!cw.visited)
        return false;
    for (uint32_t e = 0; e < et->nedges; e++) {
        if (ism_an_edge_count(et, e) != 1 || cw.visited[e])
            continue;
        cw.visited[e] = 1;
        uint32_t lo, hi;
        ism_an_edge_ends(m, et, e, &lo, &hi);
        ism_component *c = &a->component[comp[et->edge_he[et->edge_start[e]] / 3]];
        if (follow(&cw, e, hi)) {
            a->boundary_loops++;
            c->boundary_loops++;
        } else {
            follow(&cw, e, lo);
            a->boundary_chains++;
            c->boundary_chains++;
        }
    }
    free(cw.visited);
    return true;
}
