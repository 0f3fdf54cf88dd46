/* breaks.c — the break-point registry: every non-empty leaf's corners in one hash table
 * keyed by lattice point, each holding its successor on the three lattice lines through it
 * (found by radix-sorting the points line by line), so the break points of a segment are
 * found from its lower end one probe per point. */
#include "core/octree/breaks.h"
#include "core/util/grow.h"

#include <stdlib.h>
#include <string.h>

/* Radix digits of 11 bits: one pass's 2^11 counts stay in the first-level cache. */
#define RADIX_BITS 11
#define RADIX (1u << RADIX_BITS)
/* Table slots per registered point, at least: probes stay short at a load of 1/2. */
#define SLOTS_PER_POINT 2
/* Slots of the point this many places ahead are asked for while the current one is filled:
 * the table is larger than the caches, and independent misses overlap. */
#define LOOKAHEAD 16

/* LSD radix sort of n keys of `bits` bits, carrying vals along when not NULL (tk, tv: room
 * for n more of each); the counts of every pass come from one read, and a pass whose digit
 * is the same in every key is skipped. */
static bool radix_sort(uint64_t *a, uint32_t *vals, uint64_t *tk, uint32_t *tv, size_t n,
                       int bits)
{
    int passes = (bits + RADIX_BITS - 1) / RADIX_BITS;
    size_t *count = calloc((size_t)passes * RADIX, sizeof *count);
    if (!count)
        return false;
    for (size_t i = 0; i < n; i++)
        for (int p = 0; p < passes; p++)
            count[p * RADIX + ((a[i] >> (p * RADIX_BITS)) & (RADIX - 1))]++;
    uint64_t *src = a, *dst = tk;
    uint32_t *vsrc = vals, *vdst = tv;
    for (int p = 0; p < passes && n; p++) {
        size_t *c = count + (size_t)p * RADIX;
        int shift = p * RADIX_BITS;
        if (c[(src[0] >> shift) & (RADIX - 1)] == n)
            continue;
        size_t sum = 0;
        for (size_t d = 0; d < RADIX; d++) {
            size_t k = c[d];
            c[d] = sum;
            sum += k;
        }
        for (size_t i = 0; i < n; i++) {
            size_t at = c[(src[i] >> shift) & (RADIX - 1)]++;
            dst[at] = src[i];
            if (vals)
                vdst[at] = vsrc[i];
        }
        uint64_t *s = src;
        src = dst;
        dst = s;
        uint32_t *vs = vsrc;
        vsrc = vdst;
        vdst = vs;
    }
    if (src != a) {
        memcpy(a, src, n * sizeof *a);
        if (vals)
            memcpy(vals, vsrc, n * sizeof *vals);
    }
    free(count);
    return true;
}

/* Sort keys of lattice points, line by line along `axis`: the two other coordinates, then
 * the coordinate along the axis, each shifted right by `shift` (every corner is a multiple
 * of the finest leaf's size) into cb bits. */
typedef struct packing {
    int shift, cb;
} packing;

static uint64_t pack(const packing *k, int axis, const int32_t p[3])
{
    int u = (axis + 1) % 3, v = (axis + 2) % 3;
    return ((uint64_t)(p[u] >> k->shift) << 2 * k->cb) |
           ((uint64_t)(p[v] >> k->shift) << k->cb) | (uint64_t)(p[axis] >> k->shift);
}

static void unpack(const packing *k, int axis, uint64_t key, int32_t p[3])
{
    int u = (axis + 1) % 3, v = (axis + 2) % 3;
    uint64_t m = ((uint64_t)1 << k->cb) - 1;
    p[u] = (int32_t)(key >> 2 * k->cb) << k->shift;
    p[v] = (int32_t)((key >> k->cb) & m) << k->shift;
    p[axis] = (int32_t)(key & m) << k->shift;
}

static uint64_t line_of(const packing *k, uint64_t key) { return key >> k->cb; }

/* A new point's slot (the point is not in the table yet). */
static ism_break_point *insert(ism_breaks *b, const int32_t p[3])
{
    uint64_t key = ism_lattice_key(p);
    size_t s = ism_cache_mix(key) & b->mask;
    while (b->slots[s].key)
        s = (s + 1) & b->mask;
    b->slots[s].key = key;
    return &b->slots[s];
}

/* Scratch of the build: the distinct points keyed along z (sorted), their successors along
 * x and y by index, and room for a radix sort with payload. */
typedef struct scratch {
    uint64_t *k, *tk, *ak;
    uint32_t *idx, *tv;
    int32_t *next[2];
} scratch;

/* The successors along `axis` (0 or 1) of the n points of w->k: re-keyed line by line along
 * it with their index, sorted, and read off consecutive pairs on one line. */
static bool link_axis(const packing *pk, scratch *w, size_t n, int axis)
{
    for (size_t i = 0; i < n; i++) {
        int32_t p[3];
        unpack(pk, 2, w->k[i], p);
        w->ak[i] = pack(pk, axis, p);
        w->idx[i] = (uint32_t)i;
        w->next[axis][i] = ISM_BREAK_NONE;
    }
    if (!radix_sort(w->ak, w->idx, w->tk, w->tv, n, 3 * pk->cb))
        return false;
    for (size_t i = 0; i + 1 < n; i++)
        if (line_of(pk, w->ak[i]) == line_of(pk, w->ak[i + 1]))
            w->next[axis][w->idx[i]] = (int32_t)(w->ak[i + 1] & (((uint64_t)1 << pk->cb) - 1))
                                       << pk->shift;
    return true;
}

/* The table of the n distinct points of w->k (sorted along z, so each one's successor along
 * z is the next one on its line), with their successors along x and y from link_axis. */
static bool fill_table(ism_breaks *b, const packing *pk, const scratch *w, size_t n)
{
    size_t cap = 16;
    while (cap < SLOTS_PER_POINT * n)
        cap *= 2;
    if (!(b->slots = calloc(cap, sizeof *b->slots)))
        return false;
    b->mask = cap - 1;
    b->n = n;
    for (size_t i = 0; i < n; i++) {
        int32_t p[3];
        if (i + LOOKAHEAD < n) {
            unpack(pk, 2, w->k[i + LOOKAHEAD], p);
            ism_breaks_prefetch(b, p);
        }
        unpack(pk, 2, w->k[i], p);
        ism_break_point *e = insert(b, p);
        e->next[0] = w->next[0][i];
        e->next[1] = w->next[1][i];
        e->next[2] = ISM_BREAK_NONE;
        if (i + 1 < n && line_of(pk, w->k[i]) == line_of(pk, w->k[i + 1]))
            e->next[2] = (int32_t)(w->k[i + 1] & (((uint64_t)1 << pk->cb) - 1)) << pk->shift;
    }
    return true;
}

static void scratch_free(scratch *w)
{
    free(w->k);
    free(w->tk);
    free(w->ak);
    free(w->idx);
    free(w->tv);
    free(w->next[0]);
    free(w->next[1]);
}

bool ism_breaks_build(ism_breaks *b, const ism_octree *t)
{
    memset(b, 0, sizeof *b);
    const ism_grid *g = &t->grid;
    size_t leaves = 0;
    int finest = 0;
    for (size_t i = 0; i < t->n; i++)
        if (t->nodes[i].state == ISM_NODE_LEAF) {
            leaves++;
            if (t->nodes[i].level > finest)
                finest = t->nodes[i].level;
        }
    packing pk = {g->depth - finest, finest + 1}; /* coordinates 0 .. 2^finest after shift */
    size_t n = 8 * leaves, room = n ? n : 1;
    scratch w = {malloc(room * sizeof *w.k), malloc(room * sizeof *w.tk), NULL, NULL, NULL,
                 {NULL, NULL}};
    bool ok = w.k && w.tk;
    for (size_t i = 0, m = 0; ok && i < t->n; i++) {
        const ism_node *nd = &t->nodes[i];
        if (nd->state != ISM_NODE_LEAF)
            continue;
        int32_t s = ism_grid_cell_steps(g, nd->level);
        for (int c = 0; c < 8; c++) {
            int32_t p[3];
            for (int a = 0; a < 3; a++)
                p[a] = nd->org[a] + ((c >> a) & 1) * s;
            w.k[m++] = pack(&pk, 2, p);
        }
    }
    ok = ok && radix_sort(w.k, NULL, w.tk, NULL, n, 3 * pk.cb);
    size_t m = 0;
    for (size_t i = 0; ok && i < n; i++)
        if (m == 0 || w.k[m - 1] != w.k[i])
            w.k[m++] = w.k[i];
    room = m ? m : 1;
    ok = ok && m < UINT32_MAX && (w.ak = malloc(room * sizeof *w.ak)) &&
         (w.idx = malloc(room * sizeof *w.idx)) && (w.tv = malloc(room * sizeof *w.tv)) &&
         (w.next[0] = malloc(room * sizeof *w.next[0])) &&
         (w.next[1] = malloc(room * sizeof *w.next[1]));
    ok = ok && link_axis(&pk, &w, m, 0) && link_axis(&pk, &w, m, 1) && fill_table(b, &pk, &w, m);
    scratch_free(&w);
    return ok;
}

void ism_breaks_free(ism_breaks *b)
{
    free(b->slots);
    memset(b, 0, sizeof *b);
}

bool ism_coords_push(ism_coords *c, int32_t v)
{
    if (!ism_grow((void **)&c->v, &c->cap, c->n + 1, sizeof *c->v, 16))
        return false;
    c->v[c->n++] = v;
    return true;
}

void ism_coords_free(ism_coords *c)
{
    free(c->v);
    c->v = NULL;
    c->n = c->cap = 0;
}
