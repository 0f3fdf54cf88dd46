/* accuracy.c — how far the mesh lies from f = 0 between its vertices: the distance estimate
 * |f| / |∇f| at every triangle's centroid and every edge's midpoint, with the maximum, the
 * mean and the 99th percentile of each (and of the vertex distances implicit.c measured).
 * Points where |∇f| vanishes are left out and counted as skipped. Per-item distances go to
 * arrays and are summed in item order, so the figures never depend on the thread count. */
#include "core/analysis/accuracy.h"
#include "core/analysis/blocks.h"
#include "core/util/parallel.h"
#include "core/analysis/select.h"

#include <math.h>
#include <stdlib.h>

#define PERCENTILE 0.99 /* the "p99" figures: 99 of 100 points are at most this far */

typedef struct sample_pass {
    const ism_mesh *m;
    const ism_tape *f;
    const ism_an_edge_table *et;
    double threshold; /* |∇f| at or below this vanishes */
    double *dist;     /* per item: distance, NaN when skipped or not a point */
    size_t nitems;
} sample_pass;

static double distance_at(const sample_pass *sp, ism_eval_ws *ws, const double p[3])
{
    double g[3];
    double fv = ism_eval_gradient(sp->f, ws, p[0], p[1], p[2], g);
    double gn = sqrt(g[0] * g[0] + g[1] * g[1] + g[2] * g[2]), d = fabs(fv) / gn;
    return gn > sp->threshold && isfinite(d) ? d : NAN;
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
        sp->dist[t] = distance_at(sp, ws, c);
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
        sp->dist[e] = distance_at(sp, ws, c);
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
                   double threshold, ism_pool *pool, size_t nitems, ism_an_block_fn fn,
                   ism_an_distances *out)
{
    sample_pass sp = {m, f, et, threshold, malloc((nitems ? nitems : 1) * sizeof(double)),
                      nitems};
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
    double th = a->singular_threshold;
    if (!sample(m, f, et, th, pool, m->ntris, centroid_block, &c) ||
        !sample(m, f, et, th, pool, et->nedges, midpoint_block, &e))
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
