/* root_table.c — the build's edge roots logged per thread and gathered into one table
 * (root_table.h). */
#include "core/octree/root_table.h"
#include "core/util/grow.h"

#include <stdlib.h>
#include <string.h>

/* Table slots per logged root, at least: probe runs stay short at a load of 1/2 or less
 * (an edge searched by two threads is logged twice and kept once). */
#define SLOTS_PER_ROOT 2

void ism_root_log_push(ism_root_log *l, uint64_t a, uint64_t b, double t)
{
    if (!ism_grow((void **)&l->v, &l->cap, l->n + 1, sizeof *l->v, 1024))
        return;
    l->v[l->n++] = (ism_root_entry){a, b, t};
}

void ism_root_log_free(ism_root_log *l)
{
    free(l->v);
    memset(l, 0, sizeof *l);
}

static void put(ism_root_table *t, const ism_root_entry *r)
{
    for (size_t s = ism_edge_slot(r->a, r->b, 63) & t->mask;; s = (s + 1) & t->mask) {
        ism_root_entry *e = &t->slots[s];
        if (!e->a) {
            *e = *r;
            return;
        }
        if (e->a == r->a && e->b == r->b)
            return; /* the same search's answer (a pure function of the edge) */
    }
}

void ism_root_table_build(ism_root_table *t, const ism_root_log *logs, int n)
{
    memset(t, 0, sizeof *t);
    size_t roots = 0;
    for (int k = 0; k < n; k++)
        roots += logs[k].n;
    if (!roots)
        return;
    size_t cap = 16;
    while (cap < SLOTS_PER_ROOT * roots)
        cap *= 2;
    if (!(t->slots = calloc(cap, sizeof *t->slots)))
        return;
    t->mask = cap - 1;
    for (int k = 0; k < n; k++)
        for (size_t i = 0; i < logs[k].n; i++)
            put(t, &logs[k].v[i]);
}

void ism_root_table_free(ism_root_table *t)
{
    free(t->slots);
    memset(t, 0, sizeof *t);
}
