/* sheet_orient.c — consistent signs for the Hessian directions (see sheet_orient.h): Prim's
 * algorithm on a max-heap of lattice edges weighted by |n_a·n_b|; each vertex takes the sign
 * that agrees with the neighbour it is reached from. Each connected set of vertices starts
 * from its lowest index, so the result is deterministic. */
#include "core/singular/sheet_orient.h"
#include "core/singular/lattice_key.h"
#include "core/util/vec3.h"

#include <math.h>
#include <stdlib.h>

typedef struct heap_edge {
    double w;
    uint32_t to, from;
} heap_edge;

typedef struct heap {
    heap_edge *e;
    size_t n, cap;
} heap;

static bool heap_push(heap *h, heap_edge x)
{
    if (h->n == h->cap) {
        size_t c = h->cap ? 2 * h->cap : 1024;
        heap_edge *e = realloc(h->e, c * sizeof *e);
        if (!e)
            return false;
        h->e = e;
        h->cap = c;
    }
    size_t i = h->n++;
    while (i > 0 && h->e[(i - 1) / 2].w < x.w) {
        h->e[i] = h->e[(i - 1) / 2];
        i = (i - 1) / 2;
    }
    h->e[i] = x;
    return true;
}

static heap_edge heap_pop(heap *h)
{
    heap_edge top = h->e[0], x = h->e[--h->n];
    size_t i = 0;
    for (;;) {
        size_t c = 2 * i + 1;
        if (c >= h->n)
            break;
        if (c + 1 < h->n && h->e[c + 1].w > h->e[c].w)
            c++;
        if (h->e[c].w <= x.w)
            break;
        h->e[i] = h->e[c];
        i = c;
    }
    if (h->n)
        h->e[i] = x;
    return top;
}

static bool has_direction(const ism_sheet_vertex *v)
{
    return (v->have & ISM_SF_JET) && !(v->have & ISM_SF_NO_DIR);
}

static void settle(ism_sheet_vertex *v, const double ref[3])
{
    if (ref && ism_dot3(v->n, ref) < 0)
        for (int k = 0; k < 3; k++)
            v->n[k] = -v->n[k];
    v->psi = ism_dot3(v->g, v->n) / v->lam;
    v->have |= ISM_SF_ORIENTED;
}

/* Pushes the edges from settled vertex a to its unsettled lattice neighbours. */
static bool push_neighbours(ism_sheet_field *sf, heap *h, uint32_t a)
{
    int32_t ip[3];
    int32_t top = (int32_t)1 << sf->grid->depth;
    ism_lkey_unpack(sf->map.keys[a], ip);
    for (int axis = 0; axis < 3; axis++)
        for (int s = -1; s <= 1; s += 2) {
            int32_t q[3] = {ip[0], ip[1], ip[2]};
            q[axis] += s;
            if (q[axis] < 0 || q[axis] > top)
                continue;
            uint32_t b = ism_key_map_find(&sf->map, ism_lkey(q[0], q[1], q[2]));
            if (b == ISM_KEY_NONE || !has_direction(&sf->v[b])
                || (sf->v[b].have & ISM_SF_ORIENTED))
                continue;
            heap_edge e = {fabs(ism_dot3(sf->v[a].n, sf->v[b].n)), b, a};
            if (!heap_push(h, e))
                return false;
        }
    return true;
}

bool ism_sheet_orient(ism_sheet_field *sf)
{
    heap h = {NULL, 0, 0};
    bool ok = true;
    for (uint32_t s = 0; ok && s < sf->map.n; s++) {
        ism_sheet_vertex *v = &sf->v[s];
        if (!has_direction(v) || (v->have & ISM_SF_ORIENTED))
            continue;
        settle(v, NULL);
        ok = push_neighbours(sf, &h, s);
        while (ok && h.n) {
            heap_edge e = heap_pop(&h);
            ism_sheet_vertex *b = &sf->v[e.to];
            if (b->have & ISM_SF_ORIENTED)
                continue;
            settle(b, sf->v[e.from].n);
            ok = push_neighbours(sf, &h, e.to);
        }
    }
    free(h.e);
    return ok;
}
