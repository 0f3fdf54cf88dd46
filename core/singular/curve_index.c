/* curve_index.c — a grid over the candidate boxes (entries sorted by cell key, looked up by
 * binary search) and per-box lists of traced segments. See curve_index.h. */
#include "core/singular/curve_index.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>
#include "core/singular/curve_jet.h"

/* Grid coordinates per axis: 21 bits, so a cell key packs into 63 bits (a search of depth
 * ≤ 20 has ≤ 2^20 cells a side). Each box is filed once, under the cell of its centre. */
#define CINDEX_AXIS_BITS 21
#define CINDEX_AXIS_MAX ((1 << CINDEX_AXIS_BITS) - 1)

typedef struct ism_cindex_key ism_cindex_key;

static int axis_cell(const ism_cindex *x, int k, double v)
{
    double c = floor((v - x->origin[k]) / x->cell);
    return c < 0 ? 0 : c > CINDEX_AXIS_MAX ? CINDEX_AXIS_MAX : (int)c;
}

static uint64_t cell_key(int i, int j, int k)
{
    return (uint64_t)i << (2 * CINDEX_AXIS_BITS) | (uint64_t)j << CINDEX_AXIS_BITS |
           (uint64_t)k;
}

static int cmp_key(const void *pa, const void *pb)
{
    const ism_cindex_key *a = pa, *b = pb;
    if (a->key != b->key)
        return a->key < b->key ? -1 : 1;
    return a->box < b->box ? -1 : a->box > b->box;
}

bool ism_cindex_build(ism_cindex *x, ism_lbox *boxes, size_t n, const double box[6],
                      double cell)
{
    memset(x, 0, sizeof *x);
    if (n >= INT32_MAX)
        return false;
    x->boxes = boxes;
    x->nboxes = n;
    x->cell = cell;
    for (size_t b = 0; b < n; b++)
        for (int k = 0; k < 3; k++)
            x->cell = fmax(x->cell, boxes[b].hi[k] - boxes[b].lo[k]);
    memcpy(x->origin, box, sizeof x->origin);
    ism_cindex_key *keys = malloc((n + 1) * sizeof *keys);
    x->stamp = calloc(n + 1, sizeof *x->stamp);
    x->head = malloc((n + 1) * sizeof *x->head);
    if (!keys || !x->stamp || !x->head) {
        free(keys);
        ism_cindex_free(x);
        return false;
    }
    size_t m = 0;
    for (size_t b = 0; b < n; b++) { /* each box in the cell of its centre */
        x->head[b] = -1;
        int c[3];
        for (int k = 0; k < 3; k++)
            c[k] = axis_cell(x, k, 0.5 * (boxes[b].lo[k] + boxes[b].hi[k]));
        keys[m++] = (ism_cindex_key){cell_key(c[0], c[1], c[2]), (uint32_t)b};
    }
    qsort(keys, m, sizeof *keys, cmp_key);
    x->keys = keys;
    x->nkeys = m;
    return true;
}

void ism_cindex_free(ism_cindex *x)
{
    free(x->keys);
    free(x->stamp);
    free(x->head);
    free(x->links);
    free(x->segs);
    memset(x, 0, sizeof *x);
}

typedef void (*visit_fn)(ism_cindex *x, uint32_t box, void *ctx);

/* Calls fn once for every box that may meet the axis-aligned box [lo, hi]: those whose centre
 * is within half a grid cell of it (a box's side is at most a cell). Callers pass regions of
 * at most a cell or so; the range is capped at four cells a side. */
static void visit(ism_cindex *x, const double lo[3], const double hi[3], visit_fn fn, void *ctx)
{
    int a[3], b[3];
    for (int k = 0; k < 3; k++) {
        a[k] = axis_cell(x, k, lo[k] - 0.5 * x->cell);
        b[k] = axis_cell(x, k, hi[k] + 0.5 * x->cell);
        if (b[k] > a[k] + 3)
            b[k] = a[k] + 3;
    }
    if (++x->query == 0) { /* wrapped: restart the stamps */
        memset(x->stamp, 0, x->nboxes * sizeof *x->stamp);
        x->query = 1;
    }
    /* The cells (i, j, a[2] .. b[2]) of one row are consecutive keys (k in the low bits), so
     * their entries are one run of the sorted keys, in the same order as cell by cell: one
     * binary search a row instead of one a cell (curve tracing on the cross-cap: 64 → 16). */
    for (int i = a[0]; i <= b[0]; i++)
        for (int j = a[1]; j <= b[1]; j++) {
            uint64_t first = cell_key(i, j, a[2]), last = cell_key(i, j, b[2]);
            size_t l = 0, r = x->nkeys;
            while (l < r) {
                size_t m = l + (r - l) / 2;
                if (x->keys[m].key < first)
                    l = m + 1;
                else
                    r = m;
            }
            for (; l < x->nkeys && x->keys[l].key <= last; l++) {
                uint32_t box = x->keys[l].box;
                if (x->stamp[box] != x->query) {
                    x->stamp[box] = x->query;
                    fn(x, box, ctx);
                }
            }
        }
}

/* Does the segment a→b meet the box [lo − g, hi + g]? (slab test) */
static bool segment_meets_box(const double a[3], const double b[3], const ism_lbox *bx,
                              double g)
{
    double t0 = 0.0, t1 = 1.0;
    for (int k = 0; k < 3; k++) {
        double lo = bx->lo[k] - g, hi = bx->hi[k] + g, d = b[k] - a[k];
        if (d == 0.0) {
            if (a[k] < lo || a[k] > hi)
                return false;
            continue;
        }
        double u = (lo - a[k]) / d, v = (hi - a[k]) / d;
        if (u > v) {
            double s = u;
            u = v;
            v = s;
        }
        t0 = fmax(t0, u);
        t1 = fmin(t1, v);
        if (t0 > t1)
            return false;
    }
    return true;
}

typedef struct seg_ctx {
    const double *a, *b;
    double delta;
    uint32_t seg;
    bool oom;
} seg_ctx;

static void add_to_box(ism_cindex *x, uint32_t box, void *vctx)
{
    seg_ctx *c = vctx;
    ism_lbox *bx = &x->boxes[box];
    if (segment_meets_box(c->a, c->b, bx, 0.0) ||
        ((bx->flags & ISM_LBOX_PROJECTED) && ism_dist_segment(bx->q, c->a, c->b, NULL) <= c->delta))
        bx->flags |= ISM_LBOX_USED;
    if (!segment_meets_box(c->a, c->b, bx, 2.0 * c->delta))
        return;
    if (x->nlinks == x->cap_links) {
        size_t cap = x->cap_links ? 2 * x->cap_links : 256;
        void *p = realloc(x->links, cap * sizeof *x->links);
        if (!p) {
            c->oom = true;
            return;
        }
        x->links = p;
        x->cap_links = cap;
    }
    x->links[x->nlinks] = (struct ism_cindex_link){c->seg, x->head[box]};
    x->head[box] = (int32_t)x->nlinks++;
}

bool ism_cindex_add_segment(ism_cindex *x, const double a[3], const double b[3], double delta)
{
    if (x->nsegs == x->cap_segs) {
        size_t cap = x->cap_segs ? 2 * x->cap_segs : 256;
        void *p = realloc(x->segs, cap * sizeof *x->segs);
        if (!p)
            return false;
        x->segs = p;
        x->cap_segs = cap;
    }
    if (x->nsegs >= INT32_MAX || x->nlinks >= INT32_MAX - 64)
        return false;
    double *s = x->segs[x->nsegs];
    memcpy(s, a, 3 * sizeof *s);
    memcpy(s + 3, b, 3 * sizeof *s);
    seg_ctx c = {a, b, delta, (uint32_t)x->nsegs++, false};
    double lo[3], hi[3];
    for (int k = 0; k < 3; k++) {
        lo[k] = fmin(a[k], b[k]) - 2.0 * delta;
        hi[k] = fmax(a[k], b[k]) + 2.0 * delta;
    }
    visit(x, lo, hi, add_to_box, &c);
    return !c.oom;
}

typedef struct ball_ctx {
    const double *p;
    double r;
    bool hit;
} ball_ctx;

/* L∞ distance from p to the box (0 inside). */
static double box_distance(const ism_lbox *b, const double p[3])
{
    double d = 0.0;
    for (int k = 0; k < 3; k++)
        d = fmax(d, fmax(b->lo[k] - p[k], p[k] - b->hi[k]));
    return d;
}

static void mark_box(ism_cindex *x, uint32_t box, void *vctx)
{
    ball_ctx *c = vctx;
    if (box_distance(&x->boxes[box], c->p) <= c->r)
        x->boxes[box].flags |= ISM_LBOX_USED;
}

void ism_cindex_mark_ball(ism_cindex *x, const double p[3], double r)
{
    ball_ctx c = {p, r, false};
    double lo[3] = {p[0] - r, p[1] - r, p[2] - r}, hi[3] = {p[0] + r, p[1] + r, p[2] + r};
    visit(x, lo, hi, mark_box, &c);
}

static void near_box(ism_cindex *x, uint32_t box, void *vctx)
{
    ball_ctx *c = vctx;
    if (c->hit || box_distance(&x->boxes[box], c->p) > c->r)
        return;
    for (int32_t l = x->head[box]; l >= 0; l = x->links[l].next) {
        const double *s = x->segs[x->links[l].seg];
        if (ism_dist_segment(c->p, s, s + 3, NULL) <= c->r) {
            c->hit = true;
            return;
        }
    }
}

bool ism_cindex_near_segment(ism_cindex *x, const double p[3], double delta)
{
    ball_ctx c = {p, delta, false};
    double lo[3] = {p[0] - delta, p[1] - delta, p[2] - delta};
    double hi[3] = {p[0] + delta, p[1] + delta, p[2] + delta};
    visit(x, lo, hi, near_box, &c);
    return c.hit;
}
