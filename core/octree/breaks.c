/* breaks.c — the break-point registry: every non-empty leaf's corners keyed by lattice line,
 * radix-sorted and deduplicated into one array; queries are binary searches. */
#include "core/octree/breaks.h"

#include <stdlib.h>
#include <string.h>

#define COORD_BITS 18
#define FIXED_BITS 17

static uint64_t line_key(int axis, const int32_t p[3])
{
    int u = (axis + 1) % 3, v = (axis + 2) % 3;
    return ((uint64_t)axis << (COORD_BITS + 2 * FIXED_BITS)) |
           ((uint64_t)p[u] << (COORD_BITS + FIXED_BITS)) | ((uint64_t)p[v] << COORD_BITS);
}

/* LSD radix sort of 64-bit keys using 16-bit digits (the keys use 54 bits). */
static bool radix_sort(uint64_t *a, size_t n)
{
    uint64_t *tmp = malloc((n ? n : 1) * sizeof *tmp);
    size_t *count = malloc(65536 * sizeof *count);
    if (!tmp || !count) {
        free(tmp);
        free(count);
        return false;
    }
    uint64_t *src = a, *dst = tmp;
    for (int shift = 0; shift < 64; shift += 16) {
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
    /* four passes: the result is back in a */
    free(tmp);
    free(count);
    return true;
}

bool ism_breaks_build(ism_breaks *b, const ism_octree *t)
{
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
                k[n++] = line_key(axis, p) | (uint64_t)p[axis];
        }
    }
    if (!radix_sort(k, n)) {
        free(k);
        return false;
    }
    size_t m = 0;
    for (size_t i = 0; i < n; i++)
        if (m == 0 || k[m - 1] != k[i])
            k[m++] = k[i];
    b->keys = k;
    b->n = m;
    return true;
}

void ism_breaks_free(ism_breaks *b)
{
    free(b->keys);
    b->keys = NULL;
    b->n = 0;
}

static size_t lower_bound(const uint64_t *a, size_t n, uint64_t key)
{
    size_t lo = 0, hi = n;
    while (lo < hi) {
        size_t mid = lo + (hi - lo) / 2;
        if (a[mid] < key)
            lo = mid + 1;
        else
            hi = mid;
    }
    return lo;
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
    uint64_t line = line_key(axis, p);
    if (!push(out, lo))
        return false;
    for (size_t i = lower_bound(b->keys, b->n, line | (uint64_t)(lo + 1)); i < b->n; i++) {
        uint64_t k = b->keys[i];
        if ((k & ~(((uint64_t)1 << COORD_BITS) - 1)) != line)
            break;
        int32_t c = (int32_t)(k & (((uint64_t)1 << COORD_BITS) - 1));
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
