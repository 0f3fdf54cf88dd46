/* fit_box.c — the coarse interval pass that finds where f = 0 lies in a cube (fit_box.h):
 * level by level, each kept box's eight children are evaluated in one interval batch and
 * kept when their interval contains 0; the union of the finest kept boxes, padded by a cell,
 * is the answer. */
#include "core/eval/fit_box.h"
#include "core/eval/eval.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

typedef struct cell {
    unsigned short i, j, k;    /* integer position at the current level */
} cell;

/* The interval of cell coordinate c at level (2^level cells over [lo, hi]). */
static ism_interval span(double lo, double hi, int level, unsigned c)
{
    double n = (double)(1u << level);
    ism_interval v = {lo + (hi - lo) * c / n, lo + (hi - lo) * (c + 1) / n};
    if (c + 1 == (1u << level))
        v.hi = hi;
    return v;
}

/* The kept children of the cells in cur (level) into next (level + 1); returns their count. */
static size_t refine(const ism_tape *t, ism_eval_ws *ws, const double cube[6], int level,
                     const cell *cur, size_t n, cell *next)
{
    size_t kept = 0;
    for (size_t c = 0; c < n; c++) {
        ism_interval x[8], y[8], z[8], f[8];
        cell kids[8];
        for (int q = 0; q < 8; q++) {
            kids[q].i = (unsigned short)(2 * cur[c].i + (q & 1));
            kids[q].j = (unsigned short)(2 * cur[c].j + ((q >> 1) & 1));
            kids[q].k = (unsigned short)(2 * cur[c].k + ((q >> 2) & 1));
            x[q] = span(cube[0], cube[3], level + 1, kids[q].i);
            y[q] = span(cube[1], cube[4], level + 1, kids[q].j);
            z[q] = span(cube[2], cube[5], level + 1, kids[q].k);
        }
        ism_eval_interval_batch(t, ws, x, y, z, f, 8);
        for (int q = 0; q < 8; q++)
            if (f[q].lo <= 0 && f[q].hi >= 0)
                next[kept++] = kids[q];
    }
    return kept;
}

/* The union of the cells, padded by one cell and clipped to the cube. */
static void bound(const double cube[6], int level, const cell *cells, size_t n, double box[6])
{
    unsigned lo[3] = {~0u, ~0u, ~0u}, hi[3] = {0, 0, 0};
    for (size_t c = 0; c < n; c++) {
        unsigned v[3] = {cells[c].i, cells[c].j, cells[c].k};
        for (int a = 0; a < 3; a++) {
            if (v[a] < lo[a])
                lo[a] = v[a];
            if (v[a] > hi[a])
                hi[a] = v[a];
        }
    }
    unsigned top = (1u << level) - 1;
    for (int a = 0; a < 3; a++) {
        unsigned a0 = lo[a] > 0 ? lo[a] - 1 : 0, a1 = hi[a] < top ? hi[a] + 1 : top;
        box[a] = span(cube[a], cube[a + 3], level, a0).lo;
        box[a + 3] = span(cube[a], cube[a + 3], level, a1).hi;
    }
}

bool ism_fit_box(const ism_tape *t, const double cube[6], ism_fit_box_result *out)
{
    memset(out, 0, sizeof *out);
    memcpy(out->box, cube, sizeof out->box);
    ism_eval_ws *ws = ism_eval_ws_new(t);
    if (!ws)
        return false;
    double per_eval = (double)(ism_tape_length(t) + 1);
    ism_interval f = ism_eval_interval(t, ws, (ism_interval){cube[0], cube[3]},
                                       (ism_interval){cube[1], cube[4]},
                                       (ism_interval){cube[2], cube[5]});
    out->evaluations = 1;
    if (!(f.lo <= 0 && f.hi >= 0)) {
        out->empty = true;
        out->complete = true;
        ism_eval_ws_free(ws);
        return true;
    }
    cell *cur = malloc(sizeof *cur), *next = NULL;
    bool ok = cur != NULL;
    size_t n = 1;
    if (ok)
        cur[0] = (cell){0, 0, 0};
    int level = 0;
    while (ok && level < ISM_FIT_MAX_LEVEL) {
        double work = (double)(out->evaluations + 8 * n) * per_eval;
        if (work > ISM_FIT_MAX_WORK)
            break;
        next = malloc(8 * n * sizeof *next);
        if (!next) {
            ok = false;
            break;
        }
        size_t kept = refine(t, ws, cube, level, cur, n, next);
        out->evaluations += 8 * n;
        free(cur);
        cur = next;
        next = NULL;
        n = kept;
        level++;
        if (n == 0)
            break;
    }
    if (ok) {
        out->level = level;
        out->empty = n == 0;
        out->complete = n == 0 || level == ISM_FIT_MAX_LEVEL;
        if (n > 0)
            bound(cube, level, cur, n, out->box);
    }
    free(cur);
    ism_eval_ws_free(ws);
    return ok;
}
