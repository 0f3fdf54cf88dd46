/* rm_merge.c — a vertex merged into a neighbour (rm_merge.h): the two triangles on their
 * edge, the link condition, and the incidence update. */
#include "core/remesh/rm_merge.h"

#include <string.h>

bool rm_merge_find(const rm_mesh *r, uint32_t v, uint32_t w, uint32_t max_degree, rm_merge *g)
{
    return !r->locked[v] && rm_merge_find_any(r, v, w, max_degree, g);
}

/* g for merging v (at most max_degree triangles) into w, whatever w's degree. */
static bool merge_fill(const rm_mesh *r, uint32_t v, uint32_t w, uint32_t max_degree,
                       rm_merge *g)
{
    uint32_t t[2];
    int n;
    if (r->gone[v] || r->gone[w] || r->count[v] < 3 ||
        r->count[v] > max_degree || !rm_edge_triangles(r, v, w, t, &n))
        return false;
    const uint32_t *tri = r->m->tri;
    g->v = v, g->w = w, g->t1 = t[0], g->t2 = t[1], g->along = false;
    g->c = tri[3 * t[0] + (rm_corner(r->m, t[0], v) + 2) % 3];
    g->d = tri[3 * t[1] + (rm_corner(r->m, t[1], w) + 2) % 3];
    return g->c != g->d;
}

bool rm_merge_find_any(const rm_mesh *r, uint32_t v, uint32_t w, uint32_t max_degree,
                       rm_merge *g)
{
    if (max_degree > ISM_RM_MERGE_MAX_DEGREE)
        max_degree = ISM_RM_MERGE_MAX_DEGREE;
    return merge_fill(r, v, w, max_degree, g) && r->count[w] + r->count[v] - 4 <= max_degree;
}

bool rm_merge_find_into(const rm_mesh *r, uint32_t v, uint32_t w, rm_merge *g)
{
    return !r->locked[v] && merge_fill(r, v, w, ISM_RM_MERGE_MAX_DEGREE, g);
}

/* A vertex's neighbours are kept in an open-addressed table of this many slots (a power of
 * two, at least twice the 2 × ISM_RM_MERGE_MAX_DEGREE neighbours a fan of at most
 * ISM_RM_MERGE_MAX_DEGREE triangles has): a lookup probes about one slot, where a scan of the
 * neighbours compared with each of them (the collapses' link checks on coordinate-planes in
 * the irrational box: 38.9M of the pass's 370M instructions; their neighbour lists 20.7M of
 * 275M in the 1e-3 box). */
#define LINK_SLOTS 128

static uint32_t link_slot(uint32_t x) { return (x * 2654435761u) >> 25; /* 7 bits */ }

/* Puts x into the table; false when it was there already. */
static bool link_put(uint32_t *table, uint32_t x)
{
    uint32_t i = link_slot(x);
    while (table[i] != UINT32_MAX && table[i] != x)
        i = (i + 1) & (LINK_SLOTS - 1);
    bool fresh = table[i] == UINT32_MAX;
    table[i] = x;
    return fresh;
}

static bool link_has(const uint32_t *table, uint32_t x)
{
    for (uint32_t i = link_slot(x); table[i] != UINT32_MAX; i = (i + 1) & (LINK_SLOTS - 1))
        if (table[i] == x)
            return true;
    return false;
}

/* v's distinct neighbours (of its first ISM_RM_MERGE_MAX_DEGREE triangles) into the cleared
 * table, and into nb unless NULL; returns how many. */
static int link_fill(const rm_mesh *r, uint32_t v, uint32_t *table, uint32_t *nb)
{
    int n = 0;
    memset(table, 0xff, LINK_SLOTS * sizeof *table);
    for (uint32_t i = 0; i < r->count[v] && i < ISM_RM_MERGE_MAX_DEGREE; i++) {
        const uint32_t *t = r->m->tri + 3 * rm_slot(r, v, i);
        for (int k = 0; k < 3; k++)
            if (t[k] != v && link_put(table, t[k])) {
                if (nb)
                    nb[n] = t[k];
                n++;
            }
    }
    return n;
}

int rm_merge_neighbours(const rm_mesh *r, uint32_t v, uint32_t *nb)
{
    uint32_t table[LINK_SLOTS];
    return link_fill(r, v, table, nb);
}

bool rm_merge_link_ok(const rm_mesh *r, const rm_merge *g)
{
    uint32_t table[LINK_SLOTS];
    if (r->count[g->v] > ISM_RM_MERGE_MAX_DEGREE)
        return false; /* no g of rm_merge_find's: the table would not hold v's neighbours */
    (void)link_fill(r, g->v, table, NULL);
    for (uint32_t i = 0; i < r->count[g->w]; i++) {
        const uint32_t *t = r->m->tri + 3 * rm_slot(r, g->w, i);
        int cd = 0;
        for (int k = 0; k < 3; k++) {
            uint32_t x = t[k];
            cd += x == g->c || x == g->d;
            if (x == g->w || x == g->v || x == g->c || x == g->d)
                continue;
            if (link_has(table, x))
                return false;
        }
        if (cd == 2 && r->count[g->v] == 3)
            return false;
    }
    return true;
}

void rm_merge_corners(const rm_mesh *r, uint32_t t, uint32_t v, const double *x,
                      const double *q[3])
{
    const uint32_t *c = r->m->tri + 3 * t;
    for (int k = 0; k < 3; k++)
        q[k] = c[k] == v ? x : r->m->pos + 3 * (size_t)c[k];
}

uint32_t rm_merge_across(const rm_mesh *r, uint32_t a, uint32_t b, uint32_t t)
{
    uint32_t two[2];
    int n;
    if (!rm_edge_triangles(r, a, b, two, &n))
        return UINT32_MAX;
    return two[0] == t ? two[1] : two[0];
}

bool rm_merge_apply(rm_mesh *r, const rm_merge *g, uint32_t *fan, uint32_t *nfan)
{
    uint32_t n = r->count[g->v];
    if (!rm_slot_reserve(r, g->w, n))
        return false;
    memcpy(fan, r->vt + r->start[g->v], n * sizeof *fan);
    *nfan = 0;
    for (uint32_t i = 0; i < n; i++) {
        uint32_t t = fan[i], *c = r->m->tri + 3 * t;
        if (t == g->t1 || t == g->t2) {
            r->dead[t] = 1;
            rm_slot_remove(r, g->w, t);
            rm_slot_remove(r, t == g->t1 ? g->c : g->d, t);
            continue;
        }
        c[rm_corner(r->m, t, g->v)] = g->w;
        rm_slot_add(r, g->w, t);
        fan[(*nfan)++] = t;
    }
    r->count[g->v] = 0;
    r->gone[g->v] = r->locked[g->v] = 1;
    return true;
}

void rm_merge_unapply(rm_mesh *r, const rm_merge *g, const uint32_t *fan, uint32_t nfan)
{
    for (uint32_t i = 0; i < nfan; i++) {
        r->m->tri[3 * (size_t)fan[i] + rm_corner(r->m, fan[i], g->w)] = g->v;
        rm_slot_remove(r, g->w, fan[i]);
    }
    const uint32_t two[2] = {g->t1, g->t2}, other[2] = {g->c, g->d};
    for (int i = 0; i < 2; i++) {
        r->dead[two[i]] = 0;
        rm_slot_add(r, g->w, two[i]);
        rm_slot_add(r, other[i], two[i]);
    }
    r->count[g->v] = nfan + 2;
    r->gone[g->v] = r->locked[g->v] = 0;
}
