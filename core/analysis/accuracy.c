/* accuracy.c — how far the mesh lies from f = 0 between its vertices: the distance at every
 * triangle's centroid and every edge's midpoint, with the maximum, the mean and the 99th
 * percentile of each (and of the vertex distances implicit.c measured).
 * Every point first gets the estimate |f| / |∇f|, capped by the bound through the element's
 * corners (dist_bound.h: |p − v| + v's own distance, which implicit.c measured). The
 * estimate overstates beside singular points and curves (∇f vanishes on the surface there):
 * the points whose estimate could reach the maximum or the 99th percentile are measured again
 * by finding the surface near them (nearest.c; an estimate only ever comes down), from the
 * largest estimate down until the largest values are settled, so the two figures are those
 * of every point measured so. A point where |∇f| vanishes has no estimate: it is left out
 * and counted as skipped (neither the bound nor the search adds a point). Per-item distances
 * go to arrays and are summed in item order, so the figures never depend on the thread
 * count.
 * Under a bound E (the mesh's max_error) the estimate may fall short by its curvature term
 * just within it: there (ism_first_order_unsure) a point is also measured one Newton step
 * further, by the polygoniser's own rule (ism_stepped_dist, dist_bound.h), and the maximum
 * (so "met") takes those figures, measured again in turn where they pass it (band_max). The
 * mean and the 99th percentile stay the estimates': the same with a bound or without. Why
 * not step every point, bound or not, for one estimator throughout: that evaluates f's
 * gradient once more at every centroid and midpoint, for figures that change by a
 * second-order term (the mean) or are measured again anyway (the 99th percentile). Callgrind,
 * `isomesh --surface S --stats --threads 1` at the default bound, ism_analyse's instructions:
 * stepping every point sphere +14.4%, torus +12.9%, gyroid-ball +36.5% (the whole run +3.4 /
 * +3.1 / +4.5%); stepping the band for the maximum only, as here, +3.3 / +1.7 / +0.6%. */
#include "core/analysis/accuracy.h"
#include "core/analysis/blocks.h"
#include "core/util/parallel.h"
#include "core/analysis/select.h"
#include "core/analysis/nearest.h"
#include "core/util/dist_bound.h"
#include "core/util/vec3.h"

#include <math.h>
#include <stdlib.h>

/* Points measured again per task: each is a few hundred evaluations of f. */
#define NEAREST_BLOCK 16
/* The first round measures again the points from the 99th percentile's rank up and
 * NEAREST_EXTRA more: enough where few estimates come down (Steiner's surface at its
 * default bound: one round); each further round four times as many. */
#define NEAREST_EXTRA 64
/* Rays are searched (nearest.h) from points whose |∇f| is below this share of its median at
 * the vertices (the function's scale): beside singular points and curves, where ∇f vanishes
 * on the surface and the first-order estimate and Newton's foot overstate. On Steiner's
 * surface at its default bound (1e-3 box), of the 700 largest estimates the 168 the rays
 * brought down all had |∇f| under 0.3 of the median; none of the 524 above it needed them. */
#define RAYS_BELOW_MEDIAN 0.5

typedef struct sample_pass {
    const ism_mesh *m;
    const ism_tape *f;
    const ism_an_edge_table *et;
    double threshold; /* |∇f| at or below this vanishes */
    double max_error; /* the mesh's bound (0: none): estimates just within it step further */
    double *stepped;  /* per item under a bound: the band's distance (distance_at), else NULL */
    const float *vdist;      /* per vertex: its distance (implicit.c) */
    const uint8_t *singular; /* per vertex: ∇f vanishes there (no distance) */
    double *dist;     /* per item: distance, NaN when skipped or not a point */
    size_t nitems;
    /* item's point into p, its corners into idx; how many corners (0: the item is no point,
     * a collapsed triangle) */
    int (*point)(const struct sample_pass *sp, size_t item, double p[3], uint32_t idx[3]);
    const double *first; /* per item: the first-order estimate (while measuring again) */
    double rays_below;   /* rays searched from a point whose |∇f| is below this */
    const size_t *again; /* the items to measure again, and how many */
    size_t nagain;
} sample_pass;

/* The corners idx[0..n) (n <= ISM_DIST_CORNERS) of the element a point p lies in: their
 * positions, their own distances (NaN: singular, none) once asked, and the squared distance
 * from p to the nearest. */
typedef struct corners {
    const double *v[ISM_DIST_CORNERS];
    double dv[ISM_DIST_CORNERS];
    double near_sq;
    bool have_dv;
} corners;

static void corners_of(const sample_pass *sp, const double p[3], const uint32_t *idx, int n,
                       corners *c)
{
    for (int k = 0; k < n; k++)
        c->v[k] = sp->m->pos + 3 * (size_t)idx[k];
    c->near_sq = ism_nearest_corner_sq(p, c->v, n);
    c->have_dv = false;
}

/* d (an estimate at p, NaN: none) capped by the bound through the corners where it passes
 * the nearest (dist_bound.h); NaN stays: skipped, as before the bound (a figure only ever
 * shrinks). */
static double capped(const sample_pass *sp, const double p[3], double d, const uint32_t *idx,
                     int n, corners *c)
{
    if (!(d * d > c->near_sq))
        return d;
    for (int k = 0; k < n && !c->have_dv; k++)
        c->dv[k] = sp->singular[idx[k]] ? NAN : (double)sp->vdist[idx[k]];
    c->have_dv = true;
    return ism_dist_through_corners(d, p, c->v, c->dv, n);
}

/* The distances at p between vertices idx[0..n): the estimate into dist[i] (NaN, skipped,
 * where there is none) and, under a bound and in its band, the polygoniser's distance one
 * Newton step further into stepped[i] (NaN elsewhere); each capped by the corners. */
static void distance_at(const sample_pass *sp, ism_eval_ws *ws, size_t i, const double p[3],
                        const uint32_t *idx, int n)
{
    double g[3];
    double fv = ism_eval_gradient(sp->f, ws, p[0], p[1], p[2], g);
    double gn = ism_norm3(g), d = fabs(fv) / gn;
    if (!(gn > sp->threshold && isfinite(d)))
        d = NAN;
    corners c;
    corners_of(sp, p, idx, n, &c);
    sp->dist[i] = capped(sp, p, d, idx, n, &c);
    if (!sp->stepped)
        return;
    sp->stepped[i] = NAN;
    if (!ism_first_order_unsure(d, sp->max_error))
        return;
    double x[3], gx[3];
    ism_newton_foot(p, fv, g, x);
    double fx = ism_eval_gradient(sp->f, ws, x[0], x[1], x[2], gx);
    sp->stepped[i] = capped(sp, p, ism_stepped_dist(d, fx, gx), idx, n, &c);
}

static int centroid_of(const sample_pass *sp, size_t t, double c[3], uint32_t idx[3])
{
    const ism_mesh *m = sp->m;
    if (ism_an_tri_collapsed(m->tri, t))
        return 0;
    c[0] = c[1] = c[2] = 0;
    for (int k = 0; k < 3; k++) {
        idx[k] = m->tri[3 * t + k];
        for (int i = 0; i < 3; i++)
            c[i] += m->pos[3 * m->tri[3 * t + k] + i] / 3;
    }
    return 3;
}

static int midpoint_of(const sample_pass *sp, size_t e, double c[3], uint32_t idx[3])
{
    ism_an_edge_ends(sp->m, sp->et, (uint32_t)e, &idx[0], &idx[1]);
    const double *a = sp->m->pos + 3 * (size_t)idx[0], *b = sp->m->pos + 3 * (size_t)idx[1];
    for (int i = 0; i < 3; i++)
        c[i] = 0.5 * (a[i] + b[i]);
    return 2;
}

static void estimate_block(void *ctx, ism_eval_ws *ws, size_t block)
{
    sample_pass *sp = ctx;
    size_t end = ism_block_end(block, ISM_AN_EVAL_BLOCK, sp->nitems);
    for (size_t i = block * ISM_AN_EVAL_BLOCK; i < end; i++) {
        double c[3];
        uint32_t idx[3];
        int n = sp->point(sp, i, c, idx);
        if (n) {
            distance_at(sp, ws, i, c, idx, n);
            continue;
        }
        sp->dist[i] = NAN;
        if (sp->stepped)
            sp->stepped[i] = NAN;
    }
}

static void nearest_block(void *ctx, ism_eval_ws *ws, size_t block)
{
    sample_pass *sp = ctx;
    size_t end = ism_block_end(block, NEAREST_BLOCK, sp->nagain);
    for (size_t j = block * NEAREST_BLOCK; j < end; j++) {
        size_t i = sp->again[j];
        double c[3];
        uint32_t idx[3];
        sp->point(sp, i, c, idx); /* a point: it has an estimate */
        sp->dist[i] = ism_an_nearest_zero(sp->f, ws, c, sp->first[i], sp->rays_below,
                                           NULL);
    }
}

/* measure_largest's scans over the items, in blocks of ISM_AN_TRI_BLOCK on the pool: each
 * block counts into its own slot, the counts become offsets, and a second pass writes each
 * block's items there, so the lists are in item order on any number of threads. */
typedef struct scan_pass {
    sample_pass *sp;
    double *first, *tmp; /* the estimates, and those that are points */
    size_t *again;       /* the items measured again now */
    size_t *at;          /* per block: its count, then where its items go */
    double *left;        /* per block: its largest estimate not measured again */
    double below, done_above; /* measured again now: estimates in [below, done_above) */
    double left_max;          /* the largest of left[], for settled_block */
} scan_pass;

static size_t scan_end(const scan_pass *s, size_t blk)
{
    return ism_block_end(blk, ISM_AN_TRI_BLOCK, s->sp->nitems);
}

/* first := the estimates; counts those that are points. */
static void copy_block(void *ctx, size_t blk, int thread)
{
    (void)thread;
    scan_pass *s = ctx;
    size_t n = 0;
    for (size_t i = blk * ISM_AN_TRI_BLOCK, end = scan_end(s, blk); i < end; i++) {
        s->first[i] = s->sp->dist[i];
        n += !isnan(s->first[i]);
    }
    s->at[blk] = n;
}

static void points_block(void *ctx, size_t blk, int thread)
{
    (void)thread;
    scan_pass *s = ctx;
    size_t o = s->at[blk];
    for (size_t i = blk * ISM_AN_TRI_BLOCK, end = scan_end(s, blk); i < end; i++)
        if (!isnan(s->first[i]))
            s->tmp[o++] = s->first[i];
}

static bool again_now(const scan_pass *s, double e)
{
    return !isnan(e) && e < s->done_above && e >= s->below;
}

/* Counts the items measured again now; the largest estimate of the rest not yet measured. */
static void count_again_block(void *ctx, size_t blk, int thread)
{
    (void)thread;
    scan_pass *s = ctx;
    size_t n = 0;
    double left = -INFINITY;
    for (size_t i = blk * ISM_AN_TRI_BLOCK, end = scan_end(s, blk); i < end; i++) {
        double e = s->first[i];
        if (again_now(s, e))
            n++;
        else if (!isnan(e) && e < s->done_above)
            left = fmax(left, e);
    }
    s->at[blk] = n;
    s->left[blk] = left;
}

static void again_block(void *ctx, size_t blk, int thread)
{
    (void)thread;
    scan_pass *s = ctx;
    size_t o = s->at[blk];
    for (size_t i = blk * ISM_AN_TRI_BLOCK, end = scan_end(s, blk); i < end; i++)
        if (again_now(s, s->first[i]))
            s->again[o++] = i;
}

/* Counts the points measured again at or above `below` whose distance is at least the
 * largest estimate left (left_max). */
static void settled_block(void *ctx, size_t blk, int thread)
{
    (void)thread;
    scan_pass *s = ctx;
    size_t n = 0;
    for (size_t i = blk * ISM_AN_TRI_BLOCK, end = scan_end(s, blk); i < end; i++)
        n += !isnan(s->first[i]) && s->first[i] >= s->below && s->sp->dist[i] >= s->left_max;
    s->at[blk] = n;
}

/* The sum of the blocks' counts (at: the counts, then where each block's items go). */
static size_t scan_offsets(scan_pass *s, size_t nblocks)
{
    return ism_counts_to_offsets(s->at, nblocks);
}

/* measure_largest's rounds (s: its scans' slots, nblocks of items). */
static bool measure_rounds(scan_pass *s, ism_pool *pool, size_t nblocks)
{
    sample_pass *sp = s->sp;
    ism_pool_for(pool, nblocks, copy_block, s, NULL);
    size_t count = scan_offsets(s, nblocks);
    if (count == 0)
        return true;
    ism_pool_for(pool, nblocks, points_block, s, NULL);
    size_t need = count - ism_an_p99_rank(count); /* ranks from the p99's up */
    size_t want = need + NEAREST_EXTRA;
    sp->first = s->first;
    sp->again = s->again;
    for (;;) {
        want = want < count ? want : count;
        /* the want-th largest */
        s->below = ism_an_select_double_on(pool, s->tmp, count, count - want);
        ism_pool_for(pool, nblocks, count_again_block, s, NULL);
        s->left_max = -INFINITY; /* the largest estimate not measured again */
        for (size_t b = 0; b < nblocks; b++)
            s->left_max = fmax(s->left_max, s->left[b]);
        sp->nagain = scan_offsets(s, nblocks);
        ism_pool_for(pool, nblocks, again_block, s, NULL);
        if (!ism_an_run_blocks(sp->f, pool, ism_blocks(sp->nagain, NEAREST_BLOCK),
                               nearest_block, sp))
            return false;
        s->done_above = s->below; /* estimates at or above this were measured again */
        ism_pool_for(pool, nblocks, settled_block, s, NULL);
        size_t settled = scan_offsets(s, nblocks);
        if (settled >= need || want == count)
            return true;
        want *= 4;
    }
}

/* Measures again, largest estimate first, until the values at or above the 99th percentile's
 * rank are all measured ones at least as large as every estimate left (which can only come
 * down): the maximum and the 99th percentile are then those of every point measured again.
 * first: a copy of the estimates; again: room for nitems indices; tmp: for nitems values. */
static bool measure_largest(sample_pass *sp, ism_pool *pool, double *first, size_t *again,
                            double *tmp)
{
    size_t nblocks = ism_blocks(sp->nitems, ISM_AN_TRI_BLOCK), room = nblocks ? nblocks : 1;
    scan_pass s = {sp, first, tmp, again, malloc(room * sizeof *s.at),
                   malloc(room * sizeof *s.left), 0, INFINITY, -INFINITY};
    bool ok = s.at && s.left && measure_rounds(&s, pool, nblocks);
    free(s.at);
    free(s.left);
    return ok;
}

void ism_an_distance_figures(double *dist, size_t n, ism_pool *pool, ism_an_distances *out)
{
    size_t count = 0;
    double sum = 0, max = 0;
    for (size_t i = 0; i < n; i++) {
        if (isnan(dist[i]))
            continue;
        sum += dist[i];
        max = dist[i] > max ? dist[i] : max;
        dist[count++] = dist[i];
    }
    out->max = max;
    out->mean = count ? sum / (double)count : 0;
    out->p99 = count ? ism_an_select_double_on(pool, dist, count, ism_an_p99_rank(count)) : 0;
    out->skipped = n - count;
}

/* Under a bound, after measure_largest: the largest of the band's distances one step further
 * (sp->stepped) that passes the estimates' maximum, measured again as those were (nearest.c,
 * from the stepped figure), into *max (0: none passes). Only such a point can raise the
 * maximum; one the search already brought down (dist < first: it found a point of the
 * surface that near, a proof) keeps that figure, at most the maximum. again: room for nitems
 * indices. */
static bool band_max(sample_pass *sp, ism_pool *pool, const double *first, size_t *again,
                     double *max)
{
    double plain = 0;
    for (size_t i = 0; i < sp->nitems; i++)
        if (sp->dist[i] > plain) /* NaN: skipped */
            plain = sp->dist[i];
    size_t n = 0;
    for (size_t i = 0; i < sp->nitems; i++)
        if (sp->stepped[i] > plain && !(sp->dist[i] < first[i]))
            again[n++] = i;
    sample_pass band = *sp;
    band.dist = band.stepped; /* nearest_block reads first[i], then writes dist[i] */
    band.first = band.stepped;
    band.again = again;
    band.nagain = n;
    if (!ism_an_run_blocks(sp->f, pool, ism_blocks(n, NEAREST_BLOCK), nearest_block, &band))
        return false;
    *max = 0;
    for (size_t j = 0; j < n; j++)
        *max = fmax(*max, sp->stepped[again[j]]);
    return true;
}

static bool sample(const ism_mesh *m, const ism_tape *f, const ism_an_edge_table *et,
                   const ism_analysis *a, double max_error, ism_pool *pool, size_t nitems,
                   int (*point)(const sample_pass *, size_t, double[3], uint32_t[3]),
                   ism_an_distances *out)
{
    size_t n = nitems ? nitems : 1;
    sample_pass sp = {.m = m,
                      .f = f,
                      .et = et,
                      .threshold = a->singular_threshold,
                      .max_error = max_error,
                      .stepped = max_error > 0 ? malloc(n * sizeof(double)) : NULL,
                      .vdist = a->distance,
                      .singular = a->singular,
                      .dist = malloc(n * sizeof(double)),
                      .nitems = nitems,
                      .point = point,
                      .rays_below = RAYS_BELOW_MEDIAN * a->gradient_scale};
    double *first = malloc(n * sizeof *first), *tmp = malloc(n * sizeof *tmp), band = 0;
    size_t *again = malloc(n * sizeof *again);
    bool ok = sp.dist && first && tmp && again && (sp.stepped || !(max_error > 0)) &&
              ism_an_run_blocks(f, pool, ism_blocks(nitems, ISM_AN_EVAL_BLOCK), estimate_block,
                                &sp) &&
              measure_largest(&sp, pool, first, again, tmp) &&
              (!sp.stepped || band_max(&sp, pool, first, again, &band));
    if (ok) {
        ism_an_distance_figures(sp.dist, nitems, pool, out);
        out->max = fmax(out->max, band);
    }
    free(sp.dist);
    free(sp.stepped);
    free(first);
    free(tmp);
    free(again);
    return ok;
}

bool ism_an_between_vertices(const ism_mesh *m, const ism_tape *f, const ism_an_edge_table *et,
                             double max_error, ism_pool *pool, ism_analysis *a)
{
    ism_an_distances c = {0}, e = {0};
    if (!a->distance || !a->singular)
        return false; /* ism_an_implicit_figures with accuracy first */
    if (!sample(m, f, et, a, max_error, pool, m->ntris, centroid_of, &c) ||
        !sample(m, f, et, a, max_error, pool, et->nedges, midpoint_of, &e))
        return false;
    a->max_dist_centroid = c.max;
    a->mean_dist_centroid = c.mean;
    a->p99_dist_centroid = c.p99;
    a->max_dist_midpoint = e.max;
    a->mean_dist_midpoint = e.mean;
    a->p99_dist_midpoint = e.p99;
    /* collapsed triangles are not points at all; the rest were skipped for a vanishing ∇f */
    a->accuracy_skipped += c.skipped - a->collapsed_triangles + e.skipped;
    return true;
}
