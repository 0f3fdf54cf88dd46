/* accuracy.c — how far the mesh lies from f = 0 between its vertices: the distance estimate
 * |f| / |∇f| at every triangle's centroid and every edge's midpoint, capped by the bound
 * through the element's corners (dist_bound.h: |p − v| + v's own distance, which implicit.c
 * measured), with the maximum, the mean and the 99th percentile of each (and of the vertex
 * distances). A point where |∇f| vanishes has no estimate: it is left out and counted as
 * skipped (the bound only ever lowers an estimate, never adds a point). Per-item
 * distances go to arrays and are summed in item order, so the figures never depend on the
 * thread count. */
#include "core/analysis/accuracy.h"
#include "core/analysis/blocks.h"
#include "core/util/parallel.h"
#include "core/analysis/select.h"
#include "core/util/dist_bound.h"

#include <math.h>
#include <stdlib.h>

#define PERCENTILE 0.99 /* the "p99" figures: 99 of 100 points are at most this far */

typedef struct sample_pass {
    const ism_mesh *m;
    const ism_tape *f;
    const ism_an_edge_table *et;
    double threshold; /* |∇f| at or below this vanishes */
    const float *vdist;      /* per vertex: its distance (implicit.c) */
    const uint8_t *singular; /* per vertex: ∇f vanishes there (no distance) */
    double *dist;     /* per item: distance, NaN when skipped or not a point */
    size_t nitems;
} sample_pass;

/* The distance at p between vertices idx[0..n) (n <= ISM_DIST_CORNERS): the estimate, capped
 * by the bound through the corners where it passes the nearest (dist_bound.h); NaN (skipped)
 * where there is no estimate. */
static double distance_at(const sample_pass *sp, ism_eval_ws *ws, const double p[3],
                          const uint32_t *idx, int n)
{
    double g[3];
    double fv = ism_eval_gradient(sp->f, ws, p[0], p[1], p[2], g);
    double gn = sqrt(g[0] * g[0] + g[1] * g[1] + g[2] * g[2]), d = fabs(fv) / gn;
    if (!(gn > sp->threshold && isfinite(d)))
        d = NAN;
    const double *v[ISM_DIST_CORNERS];
    double dv[ISM_DIST_CORNERS];
    for (int k = 0; k < n; k++) {
        v[k] = sp->m->pos + 3 * (size_t)idx[k];
        dv[k] = sp->singular[idx[k]] ? NAN : (double)sp->vdist[idx[k]];
    }
    if (!(d * d > ism_nearest_corner_sq(p, v, n)))
        return d; /* NaN stays: skipped, as before the bound (a figure only ever shrinks) */
    return ism_dist_through_corners(d, p, v, dv, n);
}

static void centroid_block(void *ctx, ism_eval_ws *ws, size_t block)
{
    sample_pass *sp = ctx;
    const ism_mesh *m = sp->m;
    size_t end = ism_block_end(block, ISM_AN_EVAL_BLOCK, sp->nitems);
    for (size_t t = block * ISM_AN_EVAL_BLOCK; t < end; t++) {
        sp->dist[t] = NAN;
        if (ism_an_tri_collapsed(m->tri, t))
            continue;
        double c[3] = {0, 0, 0};
        for (int k = 0; k < 3; k++)
            for (int i = 0; i < 3; i++)
                c[i] += m->pos[3 * m->tri[3 * t + k] + i] / 3;
        sp->dist[t] = distance_at(sp, ws, c, m->tri + 3 * t, 3);
    }
}

static void midpoint_block(void *ctx, ism_eval_ws *ws, size_t block)
{
    sample_pass *sp = ctx;
    size_t end = ism_block_end(block, ISM_AN_EVAL_BLOCK, sp->nitems);
    for (size_t e = block * ISM_AN_EVAL_BLOCK; e < end; e++) {
        uint32_t lo, hi;
        ism_an_edge_ends(sp->m, sp->et, (uint32_t)e, &lo, &hi);
        const double *a = sp->m->pos + 3 * (size_t)lo, *b = sp->m->pos + 3 * (size_t)hi;
        double c[3] = {0.5 * (a[0] + b[0]), 0.5 * (a[1] + b[1]), 0.5 * (a[2] + b[2])};
        sp->dist[e] = distance_at(sp, ws, c, (const uint32_t[2]){lo, hi}, 2);
    }
}

void ism_an_distance_figures(double *dist, size_t n, ism_an_distances *out)
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
    out->p99 = count ? ism_an_select_double(dist, count, (size_t)(PERCENTILE * (count - 1))) : 0;
    out->skipped = n - count;
}

static bool sample(const ism_mesh *m, const ism_tape *f, const ism_an_edge_table *et,
                   const ism_analysis *a, ism_pool *pool, size_t nitems, ism_an_block_fn fn,
                   ism_an_distances *out)
{
    sample_pass sp = {m,           f,
                      et,          a->singular_threshold,
                      a->distance, a->singular,
                      malloc((nitems ? nitems : 1) * sizeof(double)), nitems};
    bool ok = sp.dist &&
              ism_an_run_blocks(f, pool, ism_blocks(nitems, ISM_AN_EVAL_BLOCK), fn, &sp);
    if (ok)
        ism_an_distance_figures(sp.dist, nitems, out);
    free(sp.dist);
    return ok;
}

bool ism_an_between_vertices(const ism_mesh *m, const ism_tape *f, const ism_an_edge_table *et,
                             ism_pool *pool, ism_analysis *a)
{
    ism_an_distances c = {0}, e = {0};
    if (!a->distance || !a->singular)
        return false; /* ism_an_implicit_figures with accuracy first */
    if (!sample(m, f, et, a, pool, m->ntris, centroid_block, &c) ||
        !sample(m, f, et, a, pool, et->nedges, midpoint_block, &e))
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
