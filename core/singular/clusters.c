/* clusters.c — 26-connected clusters of finest candidate boxes (clusters.h): the boxes'
 * lattice coordinates go into an open-addressing hash table, and each unlabelled box floods
 * its cluster through the table breadth first. */
#include "core/singular/clusters.h"

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

/* Lattice coordinate c of a key moved by d, or -1 off the key's range (0 is kept for "no
 * key", so a coordinate 0 is off it too). */
static int64_t moved(int64_t c, int d)
{
    c += d;
    return c <= 0 || c >= (1 << 21) ? -1 : c;
}

static void flood(const table *t, const uint64_t *keys, uint32_t *label, uint32_t *queue,
                  uint32_t start, uint32_t id)
{
    size_t head = 0, tail = 0;
    label[start] = id;
    queue[tail++] = start;
    while (head < tail) {
        uint32_t b = queue[head++];
        int64_t c[3];
        for (int k = 0; k < 3; k++)
            c[k] = (int64_t)((keys[b] >> (21 * k)) & 0x1fffff);
        /* the 27 neighbours (b itself among them), x fastest: the order the queue grows in */
        for (int m = 0; m < 27; m++) {
            int64_t x = moved(c[0], m % 3 - 1), y = moved(c[1], m / 3 % 3 - 1),
                    z = moved(c[2], m / 9 - 1);
            uint64_t k = x < 0 || y < 0 || z < 0
                             ? 0
                             : (uint64_t)x | (uint64_t)y << 21 | (uint64_t)z << 42;
            uint32_t nb = k ? lookup(t, k) : NO_BOX;
            if (nb != NO_BOX && label[nb] == NO_BOX) {
                label[nb] = id;
                queue[tail++] = nb;
            }
        }
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
    uint32_t *queue = malloc((n ? n : 1) * sizeof *queue);
    if (!t.key || !t.val || !keys || !queue || n >= NO_BOX) {
        free(t.key);
        free(t.val);
        free(keys);
        free(queue);
        return (size_t)-1;
    }
    for (size_t s = 0; s < cap; s++)
        t.val[s] = NO_BOX;
    for (size_t i = 0; i < n; i++) {
        keys[i] = box_key(o, &boxes[i]);
        label[i] = NO_BOX;
        if (keys[i]) {
            size_t s = slot_of(&t, keys[i]);
            t.key[s] = keys[i];
            t.val[s] = (uint32_t)i;
        }
    }
    uint32_t count = 0;
    for (size_t i = 0; i < n; i++) {
        if (label[i] != NO_BOX)
            continue;
        if (keys[i])
            flood(&t, keys, label, queue, (uint32_t)i, count);
        else
            label[i] = count;
        count++;
    }
    free(t.key);
    free(t.val);
    free(keys);
    free(queue);
    return count;
}
