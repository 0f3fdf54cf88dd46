/* breaks.c — the break-point registry: every non-empty leaf's corners in one hash table
 * keyed by lattice point, each holding its successor on the three lattice lines through it
 * (found by radix-sorting the points line by line), so the break points of a segment are
 * found from its lower end one probe per point.
 *
 * Built on several threads: every step is a loop over equal blocks of an array (ism_parallel_
 * for), with prefix sums over the blocks between loops — the corners gathered per block of
 * nodes (less those a small filter saw among the block's recent leaves), an LSD radix sort
 * whose passes count and scatter per block (stable, so the order is the one a single thread
 * makes), duplicates dropped per block, and the table filled with compare-and-swap on empty
 * slots. The table's contents do not depend on the thread count; where a point lands in
 * its probe run may, which no query can see. The keys' layout: lattice_pack.h.
 *
 * A later max_error round polygonises only the leaves near its splits (leaf_memo.h) and
 * registers only the leaves near those (breaks_near.h). */
#include "core/octree/breaks.h"
#include "core/octree/lattice_pack.h"
#include "core/util/zeroed.h"

#include <stdlib.h>
#include <string.h>

/* Radix digits of 11 bits: one pass's 2^11 counts per block stay in the first-level cache. */
#define RADIX_BITS 11
#define RADIX (1u << RADIX_BITS)
/* Table slots per registered point, at least: probes stay short at a load of 1/2. */
#define SLOTS_PER_POINT 2
/* Slots of the point this many places ahead are asked for while the current one is filled:
 * the table is larger than the caches, and independent misses overlap. */
#define LOOKAHEAD 16
/* Slots of the filter that drops a leaf's corner when one of the last leaves gathered in
 * its block had it (a direct-mapped table of recent corners): leaves come depth-first, so
 * siblings and cousins sharing corners are close in the order, and the sort gets a fraction
 * of the 8 corners a leaf; 4096 keys (32 KB) stay in the first-level cache. The duplicates
 * that slip through are dropped after the sort, as before. */
#define CORNER_FILTER_BITS 12

/* The coordinate along the key's axis of the point after key i of a sorted array a of n,
 * when it lies on the same line; else ISM_BREAK_NONE. */
static int32_t successor(const ism_packing *k, const uint64_t *a, size_t n, size_t i)
{
    if (i + 1 >= n || ism_pack_line(k, a[i]) != ism_pack_line(k, a[i + 1]))
        return ISM_BREAK_NONE;
    return ism_pack_along(k, a[i + 1]);
}

/* The build: its arrays, and the split of the current one into blocks. */
typedef struct builder {
    const ism_octree *t;
    const uint8_t *take;      /* per node: register its corners; NULL: every leaf's */
    ism_breaks *b;
    ism_packing pk;
    ism_pool *pool;
    int threads;
    ism_par_cost *cost;
    size_t nblocks;
    size_t *per_block;        /* a count per block (prefix sums turn them into offsets) */
    size_t *gathered;         /* per block: corners kept by the filter (then offsets) */
    int *finest;              /* per block of nodes: the deepest leaf level */
    size_t *count;            /* radix sort: RADIX counts per block */
    /* the distinct points keyed along z (sorted); room for a sort with payload */
    uint64_t *k, *tk, *ak;
    uint32_t *idx, *tv;
    int32_t *next[2];         /* successors along x and y, by index in k */
    size_t n;                 /* length of the array being worked on */
    /* the current radix pass */
    uint64_t *src, *dst;
    uint32_t *vsrc, *vdst;
    int shift, axis;
} builder;

/* The range [lo, hi) of block blk of the array being worked on (read once per loop: the
 * loops write through pointers the compiler cannot tell apart from the builder's fields). */
typedef struct range {
    size_t lo, hi;
} range;

static range block(const builder *w, size_t blk)
{
    return (range){w->n * blk / w->nblocks, w->n * (blk + 1) / w->nblocks};
}

static void run_blocks(builder *w, size_t n, void (*fn)(void *, size_t, int))
{
    w->n = n;
    ism_pool_for(w->pool, w->nblocks, fn, w, w->cost);
}

/* ---- the corners of the leaves ------------------------------------------------------ */

/* Are node i's corners registered? */
static bool taken(const builder *w, size_t i)
{
    return w->t->nodes[i].state == ISM_NODE_LEAF && (!w->take || w->take[i]);
}

static void count_leaves(void *ctx, size_t blk, int thread)
{
    (void)thread;
    builder *w = ctx;
    size_t leaves = 0;
    int finest = 0;
    range r = block(w, blk);
    for (size_t i = r.lo; i < r.hi; i++)
        if (taken(w, i)) {
            leaves++;
            if (w->t->nodes[i].level > finest)
                finest = w->t->nodes[i].level;
        }
    w->per_block[blk] = leaves;
    w->finest[blk] = finest;
}

/* The block's leaves' corners into w->tk at 8 per leaf before it, less the ones the filter
 * has seen; how many into w->gathered[blk]. */
static void gather_corners(void *ctx, size_t blk, int thread)
{
    (void)thread;
    builder *w = ctx;
    const ism_grid *g = &w->t->grid;
    const ism_node *nodes = w->t->nodes;
    const ism_packing pk = w->pk;
    uint64_t *first = w->tk + 8 * w->per_block[blk], *k = first;
    uint64_t seen[1u << CORNER_FILTER_BITS]; /* key + 1, 0: empty */
    memset(seen, 0, sizeof seen);
    range r = block(w, blk);
    for (size_t i = r.lo; i < r.hi; i++) {
        const ism_node *nd = &nodes[i];
        if (!taken(w, i))
            continue;
        /* corner c's key is the origin's plus the leaf's size in each field c moves along:
         * the origin and the size are multiples of 1 << pk.shift (the finest leaf's size),
         * and a field's sum stays within its cb bits (coordinates 0 .. 2^finest), so the
         * sum is ism_pack() of the corner */
        uint64_t ds = (uint64_t)(ism_grid_cell_steps(g, nd->level) >> pk.shift);
        uint64_t k0 = ism_pack(&pk, 2, nd->org), dx = ds << ism_pack_shift(&pk, 2, 0),
                 dy = ds << ism_pack_shift(&pk, 2, 1), dz = ds << ism_pack_shift(&pk, 2, 2);
        for (int c = 0; c < 8; c++) {
            uint64_t key = k0 + (c & 1 ? dx : 0) + (c & 2 ? dy : 0) + (c & 4 ? dz : 0);
            uint64_t *slot = &seen[ism_cache_mix(key) & ((1u << CORNER_FILTER_BITS) - 1)];
            if (*slot == key + 1)
                continue;
            *slot = key + 1;
            *k++ = key;
        }
    }
    w->gathered[blk] = (size_t)(k - first);
}

/* The block's gathered corners from w->tk to their place in w->k, blocks end to end. */
static void pack_gathered(void *ctx, size_t blk, int thread)
{
    (void)thread;
    builder *w = ctx;
    size_t end = blk + 1 < w->nblocks ? w->gathered[blk + 1] : w->n;
    memcpy(w->k + w->gathered[blk], w->tk + 8 * w->per_block[blk],
           (end - w->gathered[blk]) * sizeof *w->k);
}

/* ---- LSD radix sort ------------------------------------------------------------------- */

static void count_digits(void *ctx, size_t blk, int thread)
{
    (void)thread;
    builder *w = ctx;
    size_t *c = w->count + blk * RADIX;
    const uint64_t *src = w->src;
    int shift = w->shift;
    range r = block(w, blk);
    memset(c, 0, RADIX * sizeof *c);
    for (size_t i = r.lo; i < r.hi; i++)
        c[(src[i] >> shift) & (RADIX - 1)]++;
}

static void scatter(void *ctx, size_t blk, int thread)
{
    (void)thread;
    builder *w = ctx;
    size_t *c = w->count + blk * RADIX;
    const uint64_t *src = w->src;
    uint64_t *dst = w->dst;
    const uint32_t *vsrc = w->vsrc;
    uint32_t *vdst = w->vdst;
    int shift = w->shift;
    range r = block(w, blk);
    for (size_t i = r.lo; i < r.hi; i++) {
        size_t at = c[(src[i] >> shift) & (RADIX - 1)]++;
        dst[at] = src[i];
        if (vsrc)
            vdst[at] = vsrc[i];
    }
}

/* Where each block's keys of each digit go: digits in order, blocks in order within a
 * digit (what keeps the sort stable). False when one digit holds every key (nothing moves). */
static bool digit_offsets(builder *w, size_t n)
{
    size_t sum = 0;
    for (size_t d = 0; d < RADIX; d++) {
        size_t in_digit = 0;
        for (size_t blk = 0; blk < w->nblocks; blk++) {
            size_t *c = &w->count[blk * RADIX + d];
            size_t k = *c;
            *c = sum;
            sum += k;
            in_digit += k;
        }
        if (in_digit == n)
            return false;
    }
    return true;
}

/* Sorts the n keys of a, `bits` bits each, by their bits from `low` up, stably (keys equal
 * there keep their order: a sorted by its lower bits already ends sorted whole), carrying
 * vals along when not NULL (tk, tv: room for n more of each). */
static void radix_sort(builder *w, uint64_t *a, uint32_t *vals, uint64_t *tk, uint32_t *tv,
                       size_t n, int low, int bits)
{
    w->src = a, w->dst = tk, w->vsrc = vals, w->vdst = tv;
    for (w->shift = low; w->shift < bits && n; w->shift += RADIX_BITS) {
        run_blocks(w, n, count_digits);
        if (!digit_offsets(w, n))
            continue;
        run_blocks(w, n, scatter);
        uint64_t *s = w->src;
        w->src = w->dst, w->dst = s;
        uint32_t *vs = w->vsrc;
        w->vsrc = w->vdst, w->vdst = vs;
    }
    if (w->src != a) {
        memcpy(a, w->src, n * sizeof *a);
        if (vals)
            memcpy(vals, w->vsrc, n * sizeof *vals);
    }
}

/* ---- duplicates ----------------------------------------------------------------------- */

static bool first_of_run(const uint64_t *a, size_t i) { return i == 0 || a[i - 1] != a[i]; }

static void count_distinct(void *ctx, size_t blk, int thread)
{
    (void)thread;
    builder *w = ctx;
    size_t m = 0;
    range r = block(w, blk);
    for (size_t i = r.lo; i < r.hi; i++)
        m += first_of_run(w->k, i);
    w->per_block[blk] = m;
}

static void copy_distinct(void *ctx, size_t blk, int thread)
{
    (void)thread;
    builder *w = ctx;
    const uint64_t *k = w->k;
    uint64_t *out = w->tk + w->per_block[blk];
    range r = block(w, blk);
    for (size_t i = r.lo; i < r.hi; i++)
        if (first_of_run(k, i))
            *out++ = k[i];
}

/* ---- successors along x and y ----------------------------------------------------------- */

static void rekey(void *ctx, size_t blk, int thread)
{
    (void)thread;
    builder *w = ctx;
    const ism_packing pk = w->pk;
    const uint64_t *k = w->k;
    uint64_t *ak = w->ak;
    uint32_t *idx = w->idx;
    int axis = w->axis;
    range r = block(w, blk);
    for (size_t i = r.lo; i < r.hi; i++) {
        ak[i] = ism_repack(&pk, axis, k[i]);
        idx[i] = (uint32_t)i;
    }
}

static void link_block(void *ctx, size_t blk, int thread)
{
    (void)thread;
    builder *w = ctx;
    const ism_packing pk = w->pk;
    const uint64_t *ak = w->ak;
    const uint32_t *idx = w->idx;
    int32_t *next = w->next[w->axis];
    size_t n = w->n;
    range r = block(w, blk);
    for (size_t i = r.lo; i < r.hi; i++)
        next[idx[i]] = successor(&pk, ak, n, i);
}

/* The successors along `axis` (0 or 1) of the n points of w->k: re-keyed line by line along
 * it with their index, sorted, and read off consecutive pairs on one line. Sorted by the
 * line alone (the two top fields: a pass fewer wherever 2 cb fits in fewer digits than 3 cb):
 * w->k is sorted along z, by (x, y, z), so the points of one line already come in order
 * along it, x ascending for a line (y, z) and y ascending for a line (z, x), and the stable
 * sort keeps that order: the same array as sorting the whole keys (all distinct). */
static void link_axis(builder *w, size_t n, int axis)
{
    w->axis = axis;
    run_blocks(w, n, rekey);
    radix_sort(w, w->ak, w->idx, w->tk, w->tv, n, w->pk.cb, 3 * w->pk.cb);
    run_blocks(w, n, link_block);
}

/* ---- the table -------------------------------------------------------------------------- */

/* A new point's slot (the point is not in the table yet): the first empty slot of its probe
 * run that this thread wins (compare-and-swap: other threads fill the table too). */
static ism_break_point *insert(ism_breaks *b, const int32_t p[3])
{
    uint64_t key = ism_lattice_key(p);
    for (size_t s = ism_cache_mix(key) & b->mask;; s = (s + 1) & b->mask) {
        uint64_t empty = 0;
        if (__atomic_load_n(&b->slots[s].key, __ATOMIC_RELAXED) == 0 &&
            __atomic_compare_exchange_n(&b->slots[s].key, &empty, key, false, __ATOMIC_RELAXED,
                                        __ATOMIC_RELAXED))
            return &b->slots[s];
    }
}

/* The block's points of w->k (sorted along z, so each one's successor along z is the next
 * one on its line), with their successors along x and y. */
static void fill_block(void *ctx, size_t blk, int thread)
{
    (void)thread;
    builder *w = ctx;
    const ism_packing pk = w->pk;
    const uint64_t *k = w->k;
    const int32_t *nx = w->next[0], *ny = w->next[1];
    ism_breaks *b = w->b;
    size_t n = w->n;
    range r = block(w, blk);
    for (size_t i = r.lo; i < r.hi; i++) {
        int32_t p[3];
        if (i + LOOKAHEAD < r.hi) {
            ism_unpack(&pk, 2, k[i + LOOKAHEAD], p);
            ism_breaks_prefetch(b, p);
        }
        ism_unpack(&pk, 2, k[i], p);
        ism_break_point *e = insert(b, p);
        e->next[0] = nx[i];
        e->next[1] = ny[i];
        e->next[2] = successor(&pk, k, n, i);
    }
}

static bool fill_table(builder *w, size_t n)
{
    size_t cap = 16;
    while (cap < SLOTS_PER_POINT * n)
        cap *= 2;
    /* zeroed by writing: the inserts' probes read a slot before they write it */
    if (!(w->b->slots = ism_zeroed_alloc(w->pool, cap, sizeof *w->b->slots, w->cost)))
        return false;
    w->b->mask = cap - 1;
    w->b->n = n;
    run_blocks(w, n, fill_block);
    return true;
}

/* ---- the build -------------------------------------------------------------------------- */

static bool alloc_points(builder *w, size_t m)
{
    size_t room = m ? m : 1;
    return (w->ak = malloc(room * sizeof *w->ak)) && (w->idx = malloc(room * sizeof *w->idx)) &&
           (w->tv = malloc(room * sizeof *w->tv)) &&
           (w->next[0] = malloc(room * sizeof *w->next[0])) &&
           (w->next[1] = malloc(room * sizeof *w->next[1]));
}

/* The corners of every leaf, sorted along z and without duplicates, in w->k; their count. */
static bool distinct_corners(builder *w, size_t *out)
{
    const ism_octree *t = w->t;
    run_blocks(w, t->n, count_leaves);
    int finest = 0;
    for (size_t blk = 0; blk < w->nblocks; blk++)
        finest = w->finest[blk] > finest ? w->finest[blk] : finest;
    w->pk = (ism_packing){t->grid.depth - finest, finest + 1}; /* coordinates 0 .. 2^finest */
    size_t n = 8 * ism_counts_to_offsets(w->per_block, w->nblocks), room = n ? n : 1;
    if (!(w->k = malloc(room * sizeof *w->k)) || !(w->tk = malloc(room * sizeof *w->tk)))
        return false;
    run_blocks(w, t->n, gather_corners);
    n = ism_counts_to_offsets(w->gathered, w->nblocks);
    run_blocks(w, n, pack_gathered);
    radix_sort(w, w->k, NULL, w->tk, NULL, n, 0, 3 * w->pk.cb);
    run_blocks(w, n, count_distinct);
    *out = ism_counts_to_offsets(w->per_block, w->nblocks);
    run_blocks(w, n, copy_distinct);
    uint64_t *s = w->k;
    w->k = w->tk, w->tk = s;
    return *out < UINT32_MAX;
}

static void builder_free(builder *w)
{
    free(w->per_block);
    free(w->gathered);
    free(w->finest);
    free(w->count);
    free(w->k);
    free(w->tk);
    free(w->ak);
    free(w->idx);
    free(w->tv);
    free(w->next[0]);
    free(w->next[1]);
}

bool ism_breaks_build(ism_breaks *b, const ism_octree *t, const uint8_t *take, ism_pool *pool,
                      ism_par_cost *cost)
{
    memset(b, 0, sizeof *b);
    builder w;
    memset(&w, 0, sizeof w);
    w.t = t;
    w.take = take;
    w.b = b;
    w.cost = cost;
    w.pool = pool;
    w.threads = ism_pool_threads(pool);
    /* one block per thread; a tree with few leaves has few nodes too: one block */
    w.nblocks = 8 * t->n < ISM_BREAKS_MIN_PARALLEL_CORNERS ? 1 : (size_t)w.threads;
    size_t m = 0;
    bool ok = (w.per_block = malloc(w.nblocks * sizeof *w.per_block)) &&
              (w.gathered = malloc(w.nblocks * sizeof *w.gathered)) &&
              (w.finest = malloc(w.nblocks * sizeof *w.finest)) &&
              (w.count = malloc(w.nblocks * RADIX * sizeof *w.count)) &&
              distinct_corners(&w, &m) && alloc_points(&w, m);
    if (ok) {
        link_axis(&w, m, 0);
        link_axis(&w, m, 1);
        ok = fill_table(&w, m);
    }
    builder_free(&w);
    if (!ok)
        ism_breaks_free(b);
    return ok;
}

void ism_breaks_free(ism_breaks *b)
{
    free(b->slots);
    memset(b, 0, sizeof *b);
}
