/* resolvable.c — the coarse pass of resolvable.h: a grid of interval evaluations finds the
 * cells that may hold the zero set, a few points spread over them are probed, and each probe
 * compares f's enclosure over a tiny cell with its enclosure over the cell twice as large. */
#include "core/octree/resolvable.h"

#include <math.h>
#include <stdbool.h>
#include <stdio.h>
#include <stdlib.h>

#include "core/eval/eval.h"

/* Depth of the coarse grid (8^4 = 4096 cells): deep enough that a thin slab holding the zero
 * set is found (it keeps a few hundred cells), cheap enough for any request. */
#define GRID_DEPTH 4
/* Tape operations the grid may cost; a long tape gets a coarser grid (4096 cells of a
 * 1000-operation tape; the longest tapes take a 64-cell grid: milliseconds either way). */
#define GRID_OP_BUDGET (1u << 22)
/* Probes spread over the cells that may hold the zero set. */
#define PROBES 64
/* The probe cells are this many levels below the box: 2^-20 of it across, four levels below
 * the deepest depth.max a request may ask (16). An f that cannot be resolved there cannot be
 * resolved by any octree a request makes; a smooth f is linear to many digits there. */
#define PROBE_DEPTH 20
/* Which cells are probed: the kept cells' list at the fractional parts of multiples of the
 * golden ratio (evenly spread, and never in step with the rows of the grid, which a regular
 * stride can be: every probe then fell in the first kept cell of a row). */
#define GOLDEN 0.6180339887498949
/* Where in a grid cell the probe sits (fractions of the cell): off its centre, so that no
 * probe lies on a symmetry plane of a centred box (where kinks and singular points lie). */
#define PROBE_OFFSET 0.5371
/* A probe finds f unresolved when the part of its enclosure that does not shrink with the
 * cell (2 w(h) - w(2h), the width extrapolated to a cell of size 0) is more than this share
 * of the enclosure w(h). Smooth f: about 0 (the width is linear in h); a term sin(huge x):
 * about 1. A square-root singularity inside the probe cell gives 0.59, below the mark (and
 * only a probe on that measure-zero set sees it). */
#define UNRESOLVED_SHARE 0.75
/* The verdicts need at least this share of the probes (the zero set may be mostly fine and
 * hopeless only in part: that part alone is not refused). */
#define VERDICT_SHARE 0.5

static ism_interval span(double c, double half)
{
    ism_interval r = {c - half, c + half};
    return r;
}

static double width(ism_interval v)
{
    return v.hi - v.lo;
}

static int grid_depth(const ism_tape *t)
{
    size_t len = ism_tape_length(t) + 1;
    int d = GRID_DEPTH;
    while (d > 1 && ((size_t)1 << (3 * d)) * len > GRID_OP_BUDGET)
        d--;
    return d;
}

/* The cells of the grid (index = (iz * k + iy) * k + ix) whose enclosure holds 0, in order;
 * returns their count. */
static size_t zero_cells(const ism_tape *t, ism_eval_ws *ws, const double box[6], int d,
                         unsigned *out)
{
    unsigned k = 1u << d;
    double s[3];
    for (int a = 0; a < 3; a++)
        s[a] = (box[a + 3] - box[a]) / k;
    size_t n = 0;
    for (unsigned i = 0; i < k * k * k; i++) {
        unsigned ix = i % k, iy = (i / k) % k, iz = i / (k * k);
        ism_interval x = {box[0] + s[0] * ix, box[0] + s[0] * (ix + 1)};
        ism_interval y = {box[1] + s[1] * iy, box[1] + s[1] * (iy + 1)};
        ism_interval z = {box[2] + s[2] * iz, box[2] + s[2] * (iz + 1)};
        ism_interval v = ism_eval_interval(t, ws, x, y, z);
        if (v.lo <= 0 && v.hi >= 0)
            out[n++] = i;
    }
    return n;
}

typedef struct probe_counts {
    unsigned probes, zero, unresolved;
    double spread;  /* the largest enclosure width an unresolved probe kept */
} probe_counts;

/* One probe at p: is f exactly 0 there, does its enclosure shrink? */
static void probe(const ism_tape *t, ism_eval_ws *ws, const double p[3], const double h[3],
                  probe_counts *c)
{
    c->probes++;
    if (ism_eval_point(t, ws, p[0], p[1], p[2]) == 0) {
        c->zero++;
        return;
    }
    double w1 = width(ism_eval_interval(t, ws, span(p[0], h[0] / 2), span(p[1], h[1] / 2),
                                        span(p[2], h[2] / 2)));
    double w2 = width(ism_eval_interval(t, ws, span(p[0], h[0]), span(p[1], h[1]),
                                        span(p[2], h[2])));
    if (!isfinite(w1) || !isfinite(w2) || w1 <= 0)
        return;
    if (2 * w1 - w2 > UNRESOLVED_SHARE * w1) {
        c->unresolved++;
        c->spread = fmax(c->spread, w1);
    }
}

ism_resolvable ism_resolvable_check(const ism_tape *t, const double box[6], char *why,
                                    size_t n)
{
    int d = grid_depth(t);
    unsigned k = 1u << d;
    unsigned *cells = malloc((size_t)k * k * k * sizeof *cells);
    ism_eval_ws *ws = ism_eval_ws_new(t);
    if (!cells || !ws) {
        free(cells);
        ism_eval_ws_free(ws);
        return ISM_RESOLVABLE_NO_MEMORY;
    }
    size_t kept = zero_cells(t, ws, box, d, cells);
    double s[3], h[3];
    for (int a = 0; a < 3; a++) {
        s[a] = (box[a + 3] - box[a]) / k;
        h[a] = ldexp(box[a + 3] - box[a], -PROBE_DEPTH);
    }
    probe_counts c = {0, 0, 0, 0};
    size_t nprobes = kept < PROBES ? kept : PROBES;
    for (size_t j = 0; j < nprobes; j++) {
        unsigned i = cells[(size_t)(fmod((j + 0.5) * GOLDEN, 1.0) * kept)];
        unsigned ix[3] = {i % k, (i / k) % k, i / (k * k)};
        double p[3];
        for (int a = 0; a < 3; a++)
            p[a] = box[a] + s[a] * (ix[a] + PROBE_OFFSET);
        probe(t, ws, p, h, &c);
    }
    free(cells);
    ism_eval_ws_free(ws);
    if (c.probes && c.zero >= VERDICT_SHARE * c.probes) {
        snprintf(why, n,
                 "f is exactly 0 throughout a volume (at %u of %u points probed near its zero "
                 "set): every cell would hold surface and there is nothing to mesh; check "
                 "the expression", c.zero, c.probes);
        return ISM_RESOLVABLE_ZERO_VOLUME;
    }
    if (c.probes && c.unresolved >= VERDICT_SHARE * c.probes) {
        snprintf(why, n,
                 "f varies faster than any cell can resolve: over cells 2^-%d of the box "
                 "across its range still spans %.3g (at %u of %u points probed near its zero "
                 "set), as sin of a huge argument does; the octree would refine everywhere "
                 "and give noise", PROBE_DEPTH, c.spread, c.unresolved, c.probes);
        return ISM_RESOLVABLE_TOO_FINE;
    }
    return ISM_RESOLVABLE_OK;
}
