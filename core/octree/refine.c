/* refine.c — measuring a leaf's emitted triangles and the split set (see refine.h). */
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
typedef struct measured {
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
    int np = 1;
    for (int k = 0; k < 3; k++) {
        if (t > first_tri && has_side(tri - 3, tri[k], tri[(k + 1) % 3]))
            continue;
        const double *a = v[k], *b = v[(k + 1) % 3];
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
