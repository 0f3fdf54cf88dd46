/* refine.c — measuring a leaf's emitted triangles (one leaf, or several leaves' at once)
 * and the split set (see refine.h). */
#include "core/octree/refine.h"
#include "core/octree/sample_dist.h"
#include "core/util/grow.h"

#include <math.h>
#include <string.h>
#include <stdbool.h>
#include <stdlib.h>

/* Is a-b (vertex indices, either way round) a side of triangle t? */
static bool has_side(const uint32_t *t, uint32_t a, uint32_t b)
{
    for (int k = 0; k < 3; k++) {
        uint32_t p = t[k], q = t[(k + 1) % 3];
        if ((p == a && q == b) || (p == b && q == a))
            return true;
    }
    return false;
}

/* Points measured in one batch: whole triangles (each at most a centroid and three
 * midpoints) up to this many; under a finite bound the points after the first beyond it are
 * evaluated for nothing, so no more than the gradient evaluator's chunk. */
#define MEASURE_BATCH ISM_GRAD_BATCH

/* A point to measure and the corners of its element (a triangle's or a side's). */
typedef struct ism_measured {
    const double *v[3];
    int n;
} measured;

/* Triangle t's points in ism_emitted_error's order: the centroid, then the midpoints of the
 * sides not shared with the triangle before (a fan's or a quad's triangles come in order,
 * each sharing a side with the one before: that side's midpoint, the same bits either way
 * round, was measured already). Returns how many (1..4). */
static int tri_points(const ism_cell_out *out, size_t first_tri, size_t t, double (*p)[3],
                      measured *m)
{
    const uint32_t *tri = &out->tris[3 * t];
    const double *v[3];
    for (int k = 0; k < 3; k++)
        v[k] = out->verts[tri[k]].p;
    for (int a = 0; a < 3; a++)
        p[0][a] = (v[0][a] + v[1][a] + v[2][a]) / 3;
    m[0] = (measured){{v[0], v[1], v[2]}, 3};
    /* which corners the triangle before has: two distinct ones of them make one of its
       sides (a triangle's every two corners do); a side with both ends one index asks
       has_side */
    bool in[3] = {false, false, false};
    if (t > first_tri)
        for (int k = 0; k < 3; k++)
            in[k] = tri[k] == tri[-3] || tri[k] == tri[-2] || tri[k] == tri[-1];
    int np = 1;
    for (int k = 0; k < 3; k++) {
        int k1 = (k + 1) % 3;
        if (in[k] && in[k1] && (tri[k] != tri[k1] || has_side(tri - 3, tri[k], tri[k1])))
            continue;
        const double *a = v[k], *b = v[k1];
        for (int c = 0; c < 3; c++)
            p[np][c] = (a[c] + b[c]) / 2;
        m[np++] = (measured){{a, b, NULL}, 2};
    }
    return np;
}

double ism_emitted_error(ism_sampler *s, const ism_cell_out *out, size_t first_tri,
                         double bound)
{
    return ism_emitted_error_kept(s, out, first_tri, bound, NULL);
}

double ism_emitted_error_kept(ism_sampler *s, const ism_cell_out *out, size_t first_tri,
                              double bound, double (*centroid_g)[3])
{
    double worst = 0;
    size_t t = first_tri;
    while (t < out->ntris && !(worst > bound)) {
        /* the gradients of whole triangles' points in one batch, then each point's figure in
         * order (ism_sample_dist_between's), stopping after the first triangle beyond bound
         * as a point-by-point walk does */
        double p[MEASURE_BATCH][3], f[MEASURE_BATCH], g[MEASURE_BATCH][3];
        measured m[MEASURE_BATCH];
        size_t ends[MEASURE_BATCH], ntri = 0;
        int np = 0;
        while (t + ntri < out->ntris && np + 4 <= MEASURE_BATCH) {
            np += tri_points(out, first_tri, t + ntri, p + np, m + np);
            ends[ntri++] = (size_t)np;
        }
        ism_sample_grad_batch(s, (const double (*)[3])p, f, g, (size_t)np);
        double plain[MEASURE_BATCH];
        ism_plain_dists(s, (const double (*)[3])p, f, (const double (*)[3])g, s->dist_above,
                        plain, (size_t)np);
        for (size_t k = 0; centroid_g && k < ntri; k++) /* point 0 of each: its centroid */
            memcpy(centroid_g[t + k - first_tri], g[k ? ends[k - 1] : 0], sizeof g[0]);
        for (size_t k = 0, i = 0; k < ntri && !(worst > bound); k++, t++)
            for (; i < ends[k]; i++)
                worst = fmax(worst, ism_dist_beyond(s, p[i], plain[i], m[i].v, m[i].n));
    }
    return worst;
}

/* Room for n points in w (its contents not kept). */
static bool reserve(ism_measure_scratch *w, size_t n)
{
    if (n <= w->cap)
        return true;
    ism_measure_scratch_free(w);
    size_t cap = n < 256 ? 256 : 2 * n;
    w->m = malloc(cap * sizeof *w->m);
    w->p = malloc(cap * sizeof *w->p);
    w->g = malloc(cap * sizeof *w->g);
    w->x = malloc(cap * sizeof *w->x);
    w->gx = malloc(cap * sizeof *w->gx);
    w->cg = malloc(cap * sizeof *w->cg);
    w->f = malloc(cap * sizeof *w->f);
    w->fx = malloc(cap * sizeof *w->fx);
    w->plain = malloc(cap * sizeof *w->plain);
    w->tape = malloc(cap * sizeof *w->tape);
    w->step = malloc(cap * sizeof *w->step);
    if (!w->m || !w->p || !w->g || !w->x || !w->gx || !w->cg || !w->f || !w->fx ||
        !w->plain || !w->tape || !w->step) {
        ism_measure_scratch_free(w);
        return false;
    }
    w->cap = cap;
    return true;
}

void ism_measure_scratch_free(ism_measure_scratch *w)
{
    free(w->m), free(w->p), free(w->g), free(w->x), free(w->gx), free(w->cg);
    free(w->f), free(w->fx), free(w->plain), free(w->tape), free(w->step);
    memset(w, 0, sizeof *w);
}

/* Every leaf's points into w in ism_emitted_error_kept's order (leaf[k]'s from p0 to p1),
 * each with its leaf's tape there, each triangle's centroid's index in w->step; their
 * count. */
static size_t gather(ism_sampler *s, const ism_cell_out *out, ism_leaf_span *leaf, size_t n,
                     ism_measure_scratch *w)
{
    size_t np = 0, ntri = 0;
    for (size_t k = 0; k < n; k++) {
        ism_sampler_leaf_set(s, &leaf[k].leaf);
        leaf[k].cg0 = ntri;
        leaf[k].p0 = np;
        for (size_t t = leaf[k].t0; t < leaf[k].t1; t++) {
            w->step[ntri++] = np;
            int tp = tri_points(out, leaf[k].t0, t, w->p + np, w->m + np);
            for (int j = 0; j < tp; j++, np++)
                w->tape[np] = ism_sampler_tape_at(s, w->p[np]);
        }
        leaf[k].p1 = np;
    }
    return np;
}

bool ism_emitted_errors(ism_sampler *s, const ism_cell_out *out, ism_leaf_span *leaf,
                        size_t n, ism_measure_scratch *w)
{
    size_t most = 0, ntri = 0;
    for (size_t k = 0; k < n; k++)
        most += 4 * (leaf[k].t1 - leaf[k].t0);
    if (!reserve(w, most))
        return false;
    size_t np = gather(s, out, leaf, n, w);
    for (size_t k = 0; k < n; k++)
        ntri += leaf[k].t1 - leaf[k].t0;
    ism_sample_grad_tapes(s, w->tape, (const double (*)[3])w->p, w->f, w->g, np);
    for (size_t t = 0; t < ntri; t++) /* step[t]: triangle t's centroid (gather) */
        memcpy(w->cg[t], w->g[w->step[t]], sizeof w->g[0]);
    /* ism_plain_dists' first halves, point by point; the second steps of all leaves at once,
       each on its leaf's tape at the foot */
    double e = s->dist_above;
    size_t m = 0;
    for (size_t k = 0; k < n; k++) {
        ism_sampler_leaf_set(s, &leaf[k].leaf);
        for (size_t i = leaf[k].p0; i < leaf[k].p1; i++) {
            w->plain[i] = ism_first_order_dist(w->f[i], w->g[i]);
            if (ism_first_order_unsure(w->plain[i], e)) {
                ism_newton_foot(w->p[i], w->f[i], w->g[i], w->x[m]);
                w->tape[m] = ism_sampler_tape_at(s, w->x[m]);
                w->step[m++] = i;
            }
        }
    }
    ism_sample_grad_tapes(s, w->tape, (const double (*)[3])w->x, w->fx, w->gx, m);
    for (size_t j = 0; j < m; j++)
        w->plain[w->step[j]] = ism_stepped_dist(w->plain[w->step[j]], w->fx[j], w->gx[j]);
    /* each point's figure in order (ism_dist_beyond may search from it, on its leaf) */
    for (size_t k = 0; k < n; k++) {
        ism_sampler_leaf_set(s, &leaf[k].leaf);
        double worst = 0;
        for (size_t i = leaf[k].p0; i < leaf[k].p1; i++)
            worst = fmax(worst, ism_dist_beyond(s, w->p[i], w->plain[i], w->m[i].v, w->m[i].n));
        leaf[k].err = worst;
    }
    return true;
}

/* A node's origin is below 2^ISM_GRID_MAX_DEPTH (19 bits a coordinate), the level fits in 5. */
uint64_t ism_node_key(const ism_node *nd)
{
    return (uint64_t)nd->level << 57 | (uint64_t)(uint32_t)nd->org[0] << 38 |
           (uint64_t)(uint32_t)nd->org[1] << 19 | (uint64_t)(uint32_t)nd->org[2];
}

int ism_node_key_decode(uint64_t key, int32_t org[3])
{
    org[0] = (int32_t)(key >> 38 & 0x7ffff);
    org[1] = (int32_t)(key >> 19 & 0x7ffff);
    org[2] = (int32_t)(key & 0x7ffff);
    return (int)(key >> 57);
}

bool ism_split_set_add(ism_split_set *s, uint64_t key)
{
    if (!ism_grow((void **)&s->keys, &s->cap, s->n + 1, sizeof *s->keys, 64))
        return false;
    s->keys[s->n++] = key;
    return true;
}

static int by_key(const void *a, const void *b)
{
    uint64_t x = *(const uint64_t *)a, y = *(const uint64_t *)b;
    return (x > y) - (x < y);
}

void ism_split_set_sort(ism_split_set *s)
{
    if (s->n)
        qsort(s->keys, s->n, sizeof *s->keys, by_key);
}

bool ism_split_set_has(const ism_split_set *s, uint64_t key)
{
    size_t lo = 0, hi = s ? s->n : 0;
    while (lo < hi) {
        size_t mid = lo + (hi - lo) / 2;
        if (s->keys[mid] < key)
            lo = mid + 1;
        else
            hi = mid;
    }
    return s && lo < s->n && s->keys[lo] == key;
}

void ism_split_set_free(ism_split_set *s)
{
    free(s->keys);
    s->keys = NULL;
    s->n = s->cap = 0;
}
