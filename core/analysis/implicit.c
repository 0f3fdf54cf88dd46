/* implicit.c — the figures that need f itself: curvature at every vertex (one Hessian
 * evaluation each), the singular flag where ∇f vanishes, the distance estimate |f|/|∇f| at
 * vertices (between vertices: accuracy.c), and the Newton projection distance. The evaluations run
 * in blocks on the analysis's threads (blocks.c); per-vertex results go to arrays and per-block
 * partial sums are added in block order, so the figures never depend on the thread count.
 *
 * "Vanishing" is relative to the function's own scale: |∇f| <= singular_rel * G where G is
 * the median of |∇f| over the vertices used by triangles (scaling f by any factor flags the
 * same vertices). */
#include "core/analysis/implicit.h"
#include "core/analysis/curvature.h"
#include "core/analysis/accuracy.h"
#include "core/analysis/blocks.h"
#include "core/util/parallel.h"
#include "core/analysis/select.h"
#include "core/util/vec3.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#define NEWTON_STALL 1e-6 /* stop Newton where |∇f| fell below this fraction of its start */

typedef struct implicit_pass {
    const ism_mesh *m;
    const ism_tape *f;
    const ism_analysis_options *o;
    const ism_an_vertex_facts *vf;
    ism_analysis *a;
    double *fval, *gnorm, *newton; /* per vertex; gnorm NaN where f misbehaves */
    double threshold;
    ism_pool *pool; /* the threads of the medians and percentiles (NULL: the caller's) */
} implicit_pass;

float ism_an_finite_float(double x)
{
    if (isnan(x))
        return 0;
    return (float)(x > 1e30 ? 1e30 : x < -1e30 ? -1e30 : x);
}

/* Distance moved by up to `steps` Newton steps p -= f ∇f / |∇f|² from p0, where f and g are
 * already known at p0. */
static double newton_distance(const implicit_pass *ip, ism_eval_ws *ws, const double p0[3],
                              double fv, const double g0[3])
{
    double p[3] = {p0[0], p0[1], p0[2]}, g[3] = {g0[0], g0[1], g0[2]};
    double g_start = ism_norm3(g0);
    for (int i = 0; i < ip->o->newton_steps; i++) {
        if (i > 0)
            fv = ism_eval_gradient(ip->f, ws, p[0], p[1], p[2], g);
        double gg = g[0] * g[0] + g[1] * g[1] + g[2] * g[2];
        if (!isfinite(fv) || !isfinite(gg) || !(sqrt(gg) > NEWTON_STALL * g_start))
            break;
        double s = fv / gg, move = fabs(s) * sqrt(gg);
        for (int k = 0; k < 3; k++)
            p[k] -= s * g[k];
        if (move <= 1e-15 * (1 + ism_norm3(p)))
            break;
    }
    double d[3] = {p[0] - p0[0], p[1] - p0[1], p[2] - p0[2]};
    double dist = ism_norm3(d);
    return isfinite(dist) ? dist : 0;
}

static void store_curvature(ism_analysis *a, size_t v, const double g[3], const double h[6],
                            bool *ok)
{
    double mean, gauss, k1, k2;
    *ok = ism_curvature_from_derivatives(g, h, &mean, &gauss, &k1, &k2) && *ok;
    a->mean_curvature[v] = ism_an_finite_float(mean);
    a->gauss_curvature[v] = ism_an_finite_float(gauss);
    a->k1[v] = ism_an_finite_float(k1);
    a->k2[v] = ism_an_finite_float(k2);
}

static void vertex_block(void *ctx, ism_eval_ws *ws, size_t block)
{
    implicit_pass *ip = ctx;
    size_t end = ism_block_end(block, ISM_AN_EVAL_BLOCK, ip->m->nverts);
    for (size_t v = block * ISM_AN_EVAL_BLOCK; v < end; v++) {
        ip->gnorm[v] = NAN;
        if (ip->vf->corners[v] == 0)
            continue;
        const double *p = ip->m->pos + 3 * v;
        double g[3], h[6], fv;
        bool ok = true;
        if (ip->o->curvature) {
            fv = ism_eval_hessian(ip->f, ws, p[0], p[1], p[2], g, h);
            store_curvature(ip->a, v, g, h, &ok);
        } else {
            fv = ism_eval_gradient(ip->f, ws, p[0], p[1], p[2], g);
        }
        double gn = ism_norm3(g);
        ok = ok && isfinite(fv) && isfinite(gn);
        ip->fval[v] = fv;
        ip->gnorm[v] = ok ? gn : NAN;
        if (ip->o->accuracy && ok)
            ip->newton[v] = newton_distance(ip, ws, p, fv, g);
    }
}

/* Median of |∇f| over the vertices where it is known: the function's scale. */
static bool gradient_scale(implicit_pass *ip)
{
    size_t nv = ip->m->nverts, n = 0;
    double *tmp = malloc((nv ? nv : 1) * sizeof *tmp);
    if (!tmp)
        return false;
    for (size_t v = 0; v < nv; v++)
        if (isfinite(ip->gnorm[v]))
            tmp[n++] = ip->gnorm[v];
    ip->a->gradient_scale = n ? ism_an_select_double_on(ip->pool, tmp, n, n / 2) : 0;
    ip->threshold = ip->o->singular_rel * ip->a->gradient_scale;
    ip->a->singular_threshold = ip->threshold;
    free(tmp);
    return true;
}

static void clear_curvature(ism_analysis *a, size_t v)
{
    a->mean_curvature[v] = a->gauss_curvature[v] = a->k1[v] = a->k2[v] = 0;
}

/* Flags singular vertices and adds up the per-vertex figures, in vertex order. */
static void vertex_figures(implicit_pass *ip)
{
    ism_analysis *a = ip->a;
    size_t counted = 0;
    double newton_sum = 0;
    for (size_t v = 0; v < ip->m->nverts; v++) {
        double f = ip->fval[v];
        ip->fval[v] = NAN; /* from here on: the vertex's distance, NaN when not measured */
        if (ip->vf->corners[v] == 0)
            continue;
        bool singular = !(ip->gnorm[v] > ip->threshold);
        a->singular[v] = singular;
        a->singular_vertices += singular;
        if (a->mean_curvature && singular)
            clear_curvature(a, v);
        if (a->mean_curvature && !singular) {
            a->total_gauss += a->gauss_curvature[v] * a->vertex_area[v];
            a->total_abs_gauss += fabs(a->gauss_curvature[v]) * a->vertex_area[v];
        }
        if (!a->distance)
            continue;
        if (singular) {
            a->accuracy_skipped++;
            continue;
        }
        double d = fabs(f) / ip->gnorm[v];
        a->distance[v] = ism_an_finite_float(d);
        ip->fval[v] = d;
        newton_sum += ip->newton[v];
        a->max_newton_dist = fmax(a->max_newton_dist, ip->newton[v]);
        counted++;
    }
    if (counted)
        a->mean_newton_dist = newton_sum / (double)counted;
    ism_an_distances vd;
    ism_an_distance_figures(ip->fval, ip->m->nverts, ip->pool, &vd);
    a->max_dist_vertex = vd.max;
    a->mean_dist_vertex = vd.mean;
    a->p99_dist_vertex = vd.p99;
}

static bool allocate_outputs(const ism_mesh *m, const ism_analysis_options *o, ism_analysis *a)
{
    size_t n = m->nverts ? m->nverts : 1;
    a->singular = calloc(n, 1);
    if (o->curvature) {
        a->mean_curvature = calloc(n, sizeof(float));
        a->gauss_curvature = calloc(n, sizeof(float));
        a->k1 = calloc(n, sizeof(float));
        a->k2 = calloc(n, sizeof(float));
        if (!a->mean_curvature || !a->gauss_curvature || !a->k1 || !a->k2)
            return false;
    }
    if (o->accuracy && !(a->distance = calloc(n, sizeof(float))))
        return false;
    return a->singular != NULL;
}

bool ism_an_implicit_figures(const ism_mesh *m, const ism_tape *f, const ism_analysis_options *o,
                             const ism_an_vertex_facts *vf, ism_pool *pool, ism_analysis *a)
{
    if (!f || !(o->curvature || o->accuracy))
        return true;
    size_t n = m->nverts ? m->nverts : 1;
    size_t vblocks = ism_blocks(m->nverts, ISM_AN_EVAL_BLOCK);
    implicit_pass ip = {.m = m, .f = f, .o = o, .vf = vf, .a = a, .pool = pool};
    ip.fval = malloc(n * sizeof *ip.fval);
    ip.gnorm = malloc(n * sizeof *ip.gnorm);
    ip.newton = calloc(n, sizeof *ip.newton);
    bool ok = ip.fval && ip.gnorm && ip.newton && allocate_outputs(m, o, a) &&
              ism_an_run_blocks(f, pool, vblocks, vertex_block, &ip) && gradient_scale(&ip);
    if (ok)
        vertex_figures(&ip);
    free(ip.fval);
    free(ip.gnorm);
    free(ip.newton);
    return ok;
}
