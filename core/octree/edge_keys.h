/* edge_keys.h — a mesh edge as one 64-bit key (its two vertex indices, smaller first) and a
 * sorted list of such keys with one vertex each: how the clips of a dual mesh (by the balls
 * round singular points, dual_balls.c, and by the box, dual_box.c) give two triangles sharing
 * an edge the same cut vertex. */
#ifndef ISM_EDGE_KEYS_H
#define ISM_EDGE_KEYS_H

#include <stddef.h>
#include <stdint.h>
#include <stdlib.h>
#include "core/util/sort_u64.h"

static inline uint64_t ism_edge_key(uint32_t a, uint32_t b)
{
    return a < b ? (uint64_t)a << 32 | b : (uint64_t)b << 32 | a;
}

static inline int ism_edge_key_order(const void *a, const void *b)
{
    uint64_t x = *(const uint64_t *)a, y = *(const uint64_t *)b;
    return (x > y) - (x < y);
}

/* One triangle's edge by its key: the dual mesh's edges matched with their twins by sorting
 * (dual_balls.c's boundary and closed checks, dual_measure.c's missed sides). */
typedef struct ism_edge_ref {
    uint64_t key; /* ism_edge_key of its ends */
    uint32_t tri; /* 3 t + k: the edge from corner k to corner k + 1 of triangle t */
} ism_edge_ref;

/* By key, then by triangle: the same order on any libc's qsort. */
static inline int ism_edge_ref_order(const void *a, const void *b)
{
    const ism_edge_ref *x = a, *y = b;
    return x->key != y->key ? (x->key < y->key ? -1 : 1) : (x->tri > y->tri) - (x->tri < y->tri);
}

/* In refs e[0..n) sorted by key: the end of the run from i of e[i]'s key (the edge's
 * triangles: j - i of them). */
static inline size_t ism_edge_run_end(const ism_edge_ref *e, size_t n, size_t i)
{
    size_t j = i + 1;
    while (j < n && e[j].key == e[i].key)
        j++;
    return j;
}

/* keys[0..n) sorted, each once; returns how many are left. */
static inline size_t ism_edge_keys_unique(uint64_t *keys, size_t n)
{
    if (!n) /* keys may be NULL then */
        return 0;
    ism_sort_u64(keys, n);
    size_t u = 0;
    for (size_t i = 0; i < n; i++)
        if (!u || keys[i] != keys[u - 1])
            keys[u++] = keys[i];
    return u;
}

/* The vertex of edge a-b in the sorted keys[0..n) (vert[i]: key i's), or UINT32_MAX. */
static inline uint32_t ism_edge_key_vertex(const uint64_t *keys, const uint32_t *vert, size_t n,
                                           uint32_t a, uint32_t b)
{
    uint64_t key = ism_edge_key(a, b);
    const uint64_t *at = n ? bsearch(&key, keys, n, sizeof key, ism_edge_key_order) : NULL;
    return at ? vert[at - keys] : UINT32_MAX;
}

#endif
