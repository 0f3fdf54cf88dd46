/* covered.c — candidate boxes that hold mesh vertices (see covered.h). The finest boxes'
 * cells go into a hash map (a few thousand at most: the candidates of the singular search);
 * each vertex of a triangle looks up the cells that contain it (up to eight when it lies on
 * cell faces) and marks those it finds. */
#include "core/singular/covered.h"

#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include "core/singular/key_map.h"

/* A vertex within this fraction of a cell from a cell face also belongs to the cell across:
 * lattice points are computed from integer coordinates, so a vertex on a face lies on it up
 * to rounding (1e-9 of a cell is a million ulps at depth 16). */
#define FACE_SLACK 1e-9

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

/* Whether some index in [a, b] is marked in row (a lattice row's cells that hold a box). */
static bool any_in(const uint8_t *row, int64_t a, int64_t b)
{
    for (int64_t i = a; i <= b; i++)
        if (row[i])
            return true;
    return false;
}

/* Marks hit[] for every finest box's cell (cells: key → number) that holds vertex p. A vertex
 * whose cell range misses every box's row on some axis (rows[k][i]: a box's cell has index i
 * on axis k) holds none: most of a mesh lies away from the few rows of its candidates. */
static void hit_cells(const ism_key_map *cells, uint8_t *hit, const double p[3],
                      const double lo[3], const double cell[3], int64_t n,
                      uint8_t *const rows[3])
{
    int64_t a[3], b[3], c[3];
    for (int k = 2; k >= 0; k--) { /* z first: candidates often lie in few z rows (the heart) */
        cells_of(p[k], lo[k], cell[k], n, &a[k], &b[k]);
        if (!any_in(rows[k], a[k], b[k]))
            return;
    }
    for (c[0] = a[0]; c[0] <= b[0]; c[0]++)
        for (c[1] = a[1]; c[1] <= b[1]; c[1]++)
            for (c[2] = a[2]; c[2] <= b[2]; c[2]++) {
                uint32_t i = ism_key_map_find(cells, cell_key(c));
                if (i != ISM_KEY_NONE)
                    hit[i] = 1;
            }
}

/* The cell of each finest box not yet used (UINT32_MAX for the larger ones, and for those a
 * point or curve already explains: marking them again changes nothing) as a number in
 * cells. */
static bool box_cells(const ism_locus *l, const double lo[3], const double cell[3],
                      int64_t n, ism_key_map *cells, uint32_t *which, uint8_t *const rows[3])
{
    for (size_t i = 0; i < l->nboxes; i++) {
        const ism_lbox *b = &l->boxes[i];
        int64_t c[3];
        bool finest = !(b->flags & ISM_LBOX_USED), added;
        for (int k = 0; k < 3; k++) {
            finest = finest && b->hi[k] - b->lo[k] <= 1.5 * cell[k];
            c[k] = (int64_t)floor((0.5 * (b->lo[k] + b->hi[k]) - lo[k]) / cell[k]);
        }
        which[i] = finest ? ism_key_map_add(cells, cell_key(c), &added) : UINT32_MAX;
        if (finest && which[i] == ISM_KEY_NONE)
            return false;
        for (int k = 0; finest && k < 3; k++)
            if (c[k] >= 0 && c[k] < n)
                rows[k][c[k]] = 1;
    }
    return true;
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
    ism_key_map cells;
    ism_key_map_init(&cells);
    uint32_t *which = malloc(l->nboxes * sizeof *which);
    uint8_t *used = calloc(m->nverts + 1, 1), *hit = NULL;
    uint8_t *rows[3] = { calloc((size_t)n, 1), calloc((size_t)n, 1), calloc((size_t)n, 1) };
    bool ok = which && used && rows[0] && rows[1] && rows[2] &&
              box_cells(l, lo, cell, n, &cells, which, rows) && (hit = calloc(cells.n + 1, 1));
    if (ok && cells.n > 0) {
        for (size_t t = 0; t < 3 * m->ntris; t++) /* triangle corners: segments cover nothing */
            used[m->tri[t]] = 1;
        for (size_t v = 0; v < m->nverts; v++)
            if (used[v])
                hit_cells(&cells, hit, m->pos + 3 * v, lo, cell, n, rows);
        for (size_t i = 0; i < l->nboxes; i++)
            if (which[i] != UINT32_MAX && hit[which[i]])
                l->boxes[i].flags |= ISM_LBOX_USED;
    }
    ism_key_map_free(&cells);
    for (int k = 0; k < 3; k++)
        free(rows[k]);
    free(which);
    free(used);
    free(hit);
    return ok;
}
