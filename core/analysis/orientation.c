/* orientation.c — can each component be oriented consistently? Two triangles on a manifold
 * edge agree when they run along it in opposite directions. A union-find that keeps, for
 * every triangle, the parity of its flip relative to its root ("flip me to agree with the
 * root") finds the first contradiction in each component: a Möbius strip has one.
 * Non-manifold edges are not crossed (which sheets continue each other there is geometry,
 * not connectivity). */
#include "core/analysis/orientation.h"

#include <stdlib.h>

typedef struct parity_sets {
    uint32_t *parent;
    uint8_t *parity; /* relative to parent */
} parity_sets;

/* Root of i; *par is i's parity relative to it. Compresses the path fully. */
static uint32_t find(parity_sets *s, uint32_t i, uint8_t *par)
{
    uint32_t r = i;
    uint8_t p = 0;
    while (s->parent[r] != r) {
        p ^= s->parity[r];
        r = s->parent[r];
    }
    *par = p;
    for (uint32_t x = i; s->parent[x] != x;) {
        uint32_t next = s->parent[x];
        uint8_t px = s->parity[x];
        s->parent[x] = r;
        s->parity[x] = p;
        p ^= px;
        x = next;
    }
    return r;
}

/* Records that triangles i and j need parities differing by rel; false on contradiction. */
static bool relate(parity_sets *s, uint32_t i, uint32_t j, uint8_t rel)
{
    uint8_t pi, pj;
    uint32_t ri = find(s, i, &pi), rj = find(s, j, &pj);
    if (ri == rj)
        return (uint8_t)(pi ^ pj) == rel;
    uint32_t lo = ri < rj ? ri : rj, hi = ri < rj ? rj : ri;
    s->parent[hi] = lo;
    s->parity[hi] = pi ^ pj ^ rel;
    return true;
}

bool ism_an_orientation(const ism_mesh *m, const ism_an_edge_table *et, const uint32_t *comp,
                        uint8_t *bad, size_t *inconsistent)
{
    size_t nt = m->ntris ? m->ntris : 1;
    parity_sets s = {malloc(nt * sizeof *s.parent), calloc(nt, 1)};
    if (!s.parent || !s.parity) {
        free(s.parent);
        free(s.parity);
        return false;
    }
    for (size_t t = 0; t < m->ntris; t++)
        s.parent[t] = (uint32_t)t;
    for (uint32_t e = 0; e < et->nedges; e++) {
        if (ism_an_edge_count(et, e) != 2)
            continue;
        const uint32_t *he = et->edge_he + et->edge_start[e];
        uint8_t same_direction = m->tri[he[0]] == m->tri[he[1]];
        *inconsistent += same_direction;
        if (!relate(&s, he[0] / 3, he[1] / 3, same_direction))
            bad[comp[he[0] / 3]] = 1;
    }
    free(s.parent);
    free(s.parity);
    return true;
}
