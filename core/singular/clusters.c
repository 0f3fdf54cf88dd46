/* clusters.c — 26-connected clusters of finest candidate boxes (clusters.h): the boxes'
 * lattice coordinates go into an open-addressing hash table, each box is joined with its 13
 * neighbours after it in (z, y, x) order found there (core/analysis/unionfind.h: a set's root
 * its first box), and the sets are numbered in the order of their first boxes. */
#include "core/singular/clusters.h"
#include "core/analysis/unionfind.h"

#include <math.h>
#include <stdlib.h>

#define NO_BOX UINT32_MAX

typedef struct table {
    uint64_t *key;
    uint32_t *val;
    size_t mask;
} table;

static uint64_t hash64(uint64_t k)
{
    k ^= k >> 33;
    k *= 0xff51afd7ed558ccdULL;
    k ^= k >> 33;
    return k;
}

static size_t slot_of(const table *t, uint64_t k)
{
    size_t s = hash64(k) & t->mask;
    while (t->val[s] != NO_BOX && t->key[s] != k)
        s = (s + 1) & t->mask;
    return s;
}

static uint32_t lookup(const table *t, uint64_t k)
{
    return t->val[slot_of(t, k)];
}

/* Lattice key of a finest box (coordinates + 1, so that neighbours at -1 stay positive), or
 * 0 for a box larger than a finest cell. */
static uint64_t box_key(const ism_locus_options *o, const ism_lbox *b)
{
    uint64_t key = 0;
    double cells = ldexp(1.0, o->max_depth);
    for (int k = 0; k < 3; k++) {
        double cell = (o->box[k + 3] - o->box[k]) / cells;
        if (b->hi[k] - b->lo[k] > 1.5 * cell)
            return 0;
        long long i = llround((b->lo[k] - o->box[k]) / cell);
        if (i < 0 || i >= (1LL << 20))
            return 0;
        key |= (uint64_t)(i + 1) << (21 * k);
    }
    return key;
}

/* Offsets of the 13 neighbours after a box in (z, y, x) order, added to its key: a key's
 * fields hold coordinates + 1 in 1 .. 2^20, so moving one by ±1 stays within its 21 bits (0
 * or 2^20 + 1, which no box has: such a key is in no table). The other 13 neighbours see the
 * box as one of theirs, so every adjacent pair is joined once. */
static void forward_offsets(uint64_t off[13])
{
    int n = 0;
    for (int m = 14; m < 27; m++) {
        int64_t d = (int64_t)(m % 3 - 1) + (int64_t)(m / 3 % 3 - 1) * ((int64_t)1 << 21)
                    + (int64_t)(m / 9 - 1) * ((int64_t)1 << 42);
        off[n++] = (uint64_t)d;
    }
}

size_t ism_sing_clusters(const ism_locus_options *o, const ism_lbox *boxes, size_t n,
                         uint32_t *label)
{
    size_t cap = 16;
    while (cap < 2 * n)
        cap *= 2;
    table t = { calloc(cap, sizeof(uint64_t)), malloc(cap * sizeof(uint32_t)), cap - 1 };
    uint64_t *keys = malloc((n ? n : 1) * sizeof *keys);
    uint32_t *up = label; /* the union-find forest, then the labels */
    if (!t.key || !t.val || !keys || n >= NO_BOX) {
        free(t.key);
        free(t.val);
        free(keys);
        return (size_t)-1;
    }
    for (size_t s = 0; s < cap; s++)
        t.val[s] = NO_BOX;
    for (size_t i = 0; i < n; i++) {
        keys[i] = box_key(o, &boxes[i]);
        up[i] = (uint32_t)i;
        if (keys[i]) {
            size_t s = slot_of(&t, keys[i]);
            if (t.val[s] != NO_BOX) /* the same cell twice (the search's are distinct) */
                ism_an_uf_union(up, t.val[s], (uint32_t)i);
            t.key[s] = keys[i];
            t.val[s] = (uint32_t)i;
        }
    }
    uint64_t off[13];
    forward_offsets(off);
    for (size_t i = 0; i < n; i++)
        for (int m = 0; keys[i] && m < 13; m++) {
            uint32_t nb = lookup(&t, keys[i] + off[m]);
            if (nb != NO_BOX)
                ism_an_uf_union(up, (uint32_t)i, nb);
        }
    /* numbered in the order of each cluster's first box, its root: every box points at its
     * root first (a root r <= i), then label[i] replaces up[i] in order, so label[r] is
     * written before any box of r's set after it reads it */
    for (size_t i = 0; i < n; i++)
        up[i] = ism_an_uf_find(up, (uint32_t)i);
    uint32_t count = 0;
    for (size_t i = 0; i < n; i++) {
        uint32_t r = up[i];
        label[i] = r == i ? count++ : label[r];
    }
    free(t.key);
    free(t.val);
    free(keys);
    return count;
}
