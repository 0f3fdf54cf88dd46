/* covered.c — candidate boxes that hold mesh vertices (see covered.h). Vertices are filed
 * by the finest cells that contain them (up to eight when a vertex lies on cell faces) in an
 * open-addressing set of cell keys; each box looks up its own cell. */
#include "core/singular/covered.h"

#include <math.h>
#include <stdint.h>
#include <stdlib.h>

/* A vertex within this fraction of a cell from a cell face also belongs to the cell across:
 * lattice points are computed from integer coordinates, so a vertex on a face lies on it up
 * to rounding (1e-9 of a cell is a million ulps at depth 16). */
#define FACE_SLACK 1e-9

typedef struct key_set {
    uint64_t *slot; /* 0: empty; keys are stored + 1 */
    size_t mask;
} key_set;

static uint64_t mix(uint64_t k)
{
    k ^= k >> 33;
    k *= 0xff51afd7ed558ccdULL;
    k ^= k >> 33;
    return k;
}

static void set_add(key_set *s, uint64_t key)
{
    size_t i = mix(key) & s->mask;
    while (s->slot[i] && s->slot[i] != key + 1)
        i = (i + 1) & s->mask;
    s->slot[i] = key + 1;
}

static bool set_has(const key_set *s, uint64_t key)
{
    for (size_t i = mix(key) & s->mask; s->slot[i]; i = (i + 1) & s->mask)
        if (s->slot[i] == key + 1)
            return true;
    return false;
}

static uint64_t cell_key(const int64_t c[3])
{
    return ((uint64_t)c[0] << 42) ^ ((uint64_t)c[1] << 21) ^ (uint64_t)c[2];
}

/* The cell range [c0, c1] per axis holding x (two cells when x is on a face). */
static void cells_of(double x, double lo, double cell, int64_t n, int64_t *c0, int64_t *c1)
{
    double t = (x - lo) / cell;
    double f = floor(t);
    *c0 = *c1 = (int64_t)f;
    if (t - f < FACE_SLACK)
        *c0 -= 1;
    else if (f + 1 - t < FACE_SLACK)
        *c1 += 1;
    *c0 = *c0 < 0 ? 0 : *c0 >= n ? n - 1 : *c0;
    *c1 = *c1 < 0 ? 0 : *c1 >= n ? n - 1 : *c1;
}

static void file_vertex(key_set *s, const double p[3], const double lo[3], const double cell[3],
                        int64_t n)
{
    int64_t a[3], b[3], c[3];
    for (int k = 0; k < 3; k++)
        cells_of(p[k], lo[k], cell[k], n, &a[k], &b[k]);
    for (c[0] = a[0]; c[0] <= b[0]; c[0]++)
        for (c[1] = a[1]; c[1] <= b[1]; c[1]++)
            for (c[2] = a[2]; c[2] <= b[2]; c[2]++)
                set_add(s, cell_key(c));
}

bool ism_locus_mark_covered(ism_locus *l, const ism_locus_options *o, const ism_mesh *m)
{
    if (!m->ntris || !l->nboxes)
        return true;
    int64_t n = (int64_t)1 << o->max_depth;
    double lo[3], cell[3];
    for (int k = 0; k < 3; k++) {
        lo[k] = o->box[k];
        cell[k] = (o->box[k + 3] - o->box[k]) / (double)n;
    }
    size_t want = 16 * 3 * m->ntris, cap = 1024; /* up to 8 cells a corner, half full */
    while (cap < want)
        cap *= 2;
    key_set s = {calloc(cap, sizeof(uint64_t)), cap - 1};
    if (!s.slot)
        return false;
    for (size_t t = 0; t < 3 * m->ntris; t++) /* triangle corners: segments cover nothing */
        file_vertex(&s, m->pos + 3 * (size_t)m->tri[t], lo, cell, n);
    for (size_t i = 0; i < l->nboxes; i++) {
        ism_lbox *b = &l->boxes[i];
        int64_t c[3];
        bool finest = true;
        for (int k = 0; k < 3; k++) {
            finest = finest && b->hi[k] - b->lo[k] <= 1.5 * cell[k];
            c[k] = (int64_t)floor((0.5 * (b->lo[k] + b->hi[k]) - lo[k]) / cell[k]);
        }
        if (finest && set_has(&s, cell_key(c)))
            b->flags |= ISM_LBOX_USED;
    }
    free(s.slot);
    return true;
}
