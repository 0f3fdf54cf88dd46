/* breaks.c — the break-point registry: every non-empty leaf's corners keyed by lattice line,
 * radix-sorted and deduplicated into one array; queries are binary searches. */
#include "core/octree/breaks.h"

#include <stdlib.h>
#include <string.h>

/* A key is axis | u | v | position, each coordinate in b->cbits bits (depth + 1: lattice
 * coordinates run from 0 to 2^depth), so that shallow trees sort in fewer radix passes. */
static uint64_t line_key(const ism_breaks *b, int axis, const int32_t p[3])
{
    int u = (axis + 1) % 3, v = (axis + 2) % 3, cb = b->cbits;
    return ((((uint64_t)axis << (2 * cb)) | ((uint64_t)p[u] << cb) | (uint64_t)p[v]) << cb);
}

static uint64_t line_mask(const ism_breaks *b) { return ~(((uint64_t)1 << b->cbits) - 1); }

/* LSD radix sort of keys of `bits` bits, 16 bits per pass. */
static bool radix_sort(uint64_t *a, size_t n, int bits)
{
    uint64_t *tmp = malloc((n ? n : 1) * sizeof *tmp);
    size_t *count = malloc(65536 * sizeof *count);
    if (!tmp || !count) {
        free(tmp);
        free(count);
        return false;
    }
    uint64_t *src = a, *dst = tmp;
    for (int shift = 0; shift < bits; shift += 16) {
        memset(count, 0, 65536 * sizeof *count);
        for (size_t i = 0; i < n; i++)
            count[(src[i] >> shift) & 0xffff]++;
        size_t sum = 0;
        for (size_t d = 0; d < 65536; d++) {
            size_t c = count[d];
            count[d] = sum;
            sum += c;
        }
        for (size_t i = 0; i < n; i++)
            dst[count[(src[i] >> shift) & 0xffff]++] = src[i];
        uint64_t *s = src;
        src = dst;
        dst = s;
    }
    if (src != a) /* an odd number of passes */
        memcpy(a, src, n * sizeof *a);
    free(tmp);
    free(count);
    return true;
}

static size_t line_slot(const ism_breaks *b, uint64_t line)
{
    uint64_t h = (line >> b->cbits) * 0x9e3779b97f4a7c15ull;
    return (size_t)(h ^ (h >> 29)) & b->line_mask;
}

/* Indexes the first key of every line, so a query costs one probe instead of a binary
 * search over every break point of the tree. */
static bool index_lines(ism_breaks *b)
{
    uint64_t mask = line_mask(b);
    size_t lines = 0;
    for (size_t i = 0; i < b->n; i++)
        lines += i == 0 || (b->keys[i] & mask) != (b->keys[i - 1] & mask);
    size_t cap = 16;
    while (cap < 2 * lines)
        cap *= 2;
    b->line_first = calloc(cap, sizeof *b->line_first);
    if (!b->line_first || b->n >= UINT32_MAX)
        return false;
    b->line_mask = cap - 1;
    for (size_t i = 0; i < b->n; i++) {
        if (i > 0 && (b->keys[i] & mask) == (b->keys[i - 1] & mask))
            continue;
        size_t slot = line_slot(b, b->keys[i] & mask);
        while (b->line_first[slot])
            slot = (slot + 1) & b->line_mask;
        b->line_first[slot] = (uint32_t)(i + 1);
    }
    return true;
}

/* Index of the first key on `line`, or b->n when the line has no break points. */
static size_t first_on_line(const ism_breaks *b, uint64_t line)
{
    for (size_t slot = line_slot(b, line);; slot = (slot + 1) & b->line_mask) {
        uint32_t f = b->line_first[slot];
        if (!f)
            return b->n;
        if ((b->keys[f - 1] & line_mask(b)) == line)
            return f - 1;
    }
}

/* Index of the first key above `key` at or after `from` (keys are sorted): a galloping
 * search, so a query near the start of a long line costs a few probes, not a scan of it. */
static size_t first_above(const ism_breaks *b, size_t from, uint64_t key)
{
    size_t lo = from, step = 1;
    while (lo < b->n && b->keys[lo] <= key) {
        size_t next = lo + step;
        if (next >= b->n || b->keys[next] > key) {
            size_t hi = next < b->n ? next : b->n; /* the answer is in (lo, hi] */
            while (hi - lo > 1) {
                size_t mid = lo + (hi - lo) / 2;
                if (b->keys[mid] <= key)
                    lo = mid;
                else
                    hi = mid;
            }
            return hi;
        }
        lo = next;
        step *= 2;
    }
    return lo;
}

bool ism_breaks_build(ism_breaks *b, const ism_octree *t)
{
    b->cbits = t->grid.depth + 1;
    size_t leaves = 0;
    for (size_t i = 0; i < t->n; i++)
        leaves += t->nodes[i].state == ISM_NODE_LEAF;
    uint64_t *k = malloc((leaves ? leaves : 1) * 24 * sizeof *k);
    if (!k)
        return false;
    size_t n = 0;
    for (size_t i = 0; i < t->n; i++) {
        const ism_node *nd = &t->nodes[i];
        if (nd->state != ISM_NODE_LEAF)
            continue;
        int32_t s = ism_grid_cell_steps(&t->grid, nd->level);
        for (int c = 0; c < 8; c++) {
            int32_t p[3];
            for (int a = 0; a < 3; a++)
                p[a] = nd->org[a] + ((c >> a) & 1) * s;
            for (int axis = 0; axis < 3; axis++)
                k[n++] = line_key(b, axis, p) | (uint64_t)p[axis];
        }
    }
    if (!radix_sort(k, n, 2 + 3 * b->cbits)) {
        free(k);
        return false;
    }
    size_t m = 0;
    for (size_t i = 0; i < n; i++)
        if (m == 0 || k[m - 1] != k[i])
            k[m++] = k[i];
    b->keys = k;
    b->n = m;
    return index_lines(b);
}

void ism_breaks_free(ism_breaks *b)
{
    free(b->keys);
    free(b->line_first);
    b->keys = NULL;
    b->line_first = NULL;
    b->n = 0;
}

static bool push(ism_coords *c, int32_t v)
{
    if (c->n == c->cap) {
        size_t cap = c->cap ? c->cap * 2 : 16;
        int32_t *nv = realloc(c->v, cap * sizeof *nv);
        if (!nv)
            return false;
        c->v = nv;
        c->cap = cap;
    }
    c->v[c->n++] = v;
    return true;
}

bool ism_breaks_on(const ism_breaks *b, int axis, const int32_t p[3], int32_t lo, int32_t hi,
                   ism_coords *out)
{
    out->n = 0;
    uint64_t line = line_key(b, axis, p), mask = line_mask(b);
    if (!push(out, lo))
        return false;
    for (size_t i = first_above(b, first_on_line(b, line), line | (uint64_t)lo); i < b->n; i++) {
        uint64_t k = b->keys[i];
        if ((k & mask) != line)
            break;
        int32_t c = (int32_t)(k & ~mask);
        if (c >= hi)
            break;
        if (!push(out, c))
            return false;
    }
    return push(out, hi);
}

void ism_coords_free(ism_coords *c)
{
    free(c->v);
    c->v = NULL;
    c->n = c->cap = 0;
}
