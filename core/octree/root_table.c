/* root_table.c — the build's edge roots logged per thread and gathered into one table
 * (root_table.h). */
#include "core/octree/root_table.h"
#include "core/util/grow.h"

#include <stdint.h>
#include <stdlib.h>
#include <string.h>

/* Table slots per logged root, at least: probe runs stay short at a load of 1/2 or less
 * (an edge searched by two threads is logged twice and kept once). */
#define SLOTS_PER_ROOT 2

/* A log's first allocation, in roots: one node logs up to 12 and a build that logs any
 * logs thousands (Barth's sextic at E 1e-2: 31,390 over its threads), so the doublings
 * start at 24 KiB rather than at one entry. */
#define LOG_FIRST_ROOTS 1024

void ism_root_log_push(ism_root_log *l, uint64_t a, uint64_t b, double t)
{
    if (l->n >= l->limit ||
        !ism_grow((void **)&l->v, &l->cap, l->n + 1, sizeof *l->v, LOG_FIRST_ROOTS))
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

void ism_root_table_init(ism_root_table *t, size_t roots)
{
    memset(t, 0, sizeof *t);
    if (!roots || roots > SIZE_MAX / SLOTS_PER_ROOT / 2)
        return;
    size_t cap = 16; /* the smallest table: a few roots need no finer size */
    while (cap < SLOTS_PER_ROOT * roots)
        cap *= 2;
    if ((t->slots = calloc(cap, sizeof *t->slots)))
        t->mask = cap - 1;
}

void ism_root_table_take(ism_root_table *t, ism_root_log *l)
{
    for (size_t i = 0; t->slots && i < l->n; i++)
        put(t, &l->v[i]);
    ism_root_log_free(l);
}

void ism_root_table_free(ism_root_table *t)
{
    free(t->slots);
    memset(t, 0, sizeof *t);
}
