/* project.c — the optional clean-up step: move manifold vertices onto f = 0 by Newton steps
 * along ∇f. Conservative by design: only class-0 vertices move (never a boundary or
 * non-manifold feature), never where ∇f vanishes, never further than half the vertex's
 * shortest edge (so no triangle folds over), and only when Newton converged. The normal is
 * re-aimed along ∇f at the new place, on the old normal's side. */
#include "core/analysis/project.h"
#include "core/analysis/checks.h"
#include "core/analysis/options.h"
#include "core/analysis/blocks.h"
#include "core/util/parallel.h"
#include "core/analysis/select.h"
#include "core/util/vec3.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#define CONVERGED_REL 1e-6 /* last Newton step below this fraction of the shortest edge */

enum outcome { KEPT_FEATURE, KEPT_SINGULAR, KEPT_FAR, MOVED };

typedef struct project_pass {
    ism_mesh *m;
    const ism_tape *f;
    const ism_analysis *a;
    int steps;
    double threshold;
    double *shortest;  /* per vertex: shortest incident edge */
    double *gnorm;     /* per vertex, for the scale when the analysis has none */
    uint8_t *outcome;  /* per vertex */
    double *move;      /* per vertex */
    ism_pool *pool;    /* the evaluations' threads (NULL: the calling thread) */
} project_pass;

static void shortest_edges(const ism_mesh *m, double *shortest)
{
    for (size_t v = 0; v < m->nverts; v++)
        shortest[v] = INFINITY;
    for (size_t t = 0; t < m->ntris; t++)
        for (int k = 0; k < 3; k++) {
            uint32_t i = m->tri[3 * t + k], j = m->tri[3 * t + (k + 1) % 3];
            const double *p = m->pos + 3 * i, *q = m->pos + 3 * j;
            double d[3] = {p[0] - q[0], p[1] - q[1], p[2] - q[2]}, len = ism_norm3(d);
            if (i != j && len < shortest[i])
                shortest[i] = len;
            if (i != j && len < shortest[j])
                shortest[j] = len;
        }
}

static void gnorm_block(void *ctx, ism_eval_ws *ws, size_t block)
{
    project_pass *pp = ctx;
    size_t end = ism_block_end(block, ISM_AN_EVAL_BLOCK, pp->m->nverts);
    for (size_t v = block * ISM_AN_EVAL_BLOCK; v < end; v++) {
        const double *p = pp->m->pos + 3 * v;
        double g[3];
        ism_eval_gradient(pp->f, ws, p[0], p[1], p[2], g);
        pp->gnorm[v] = ism_norm3(g);
    }
}

/* The singular threshold: from the analysis when it evaluated f, else measured here. */
static bool find_threshold(project_pass *pp, const ism_analysis_options *o)
{
    if (pp->a->gradient_scale > 0) {
        pp->threshold = o->singular_rel * pp->a->gradient_scale;
        return true;
    }
    size_t nv = pp->m->nverts, n = 0;
    pp->gnorm = malloc((nv ? nv : 1) * sizeof *pp->gnorm);
    if (!pp->gnorm || !ism_an_run_blocks(pp->f, pp->pool, ism_blocks(nv, ISM_AN_EVAL_BLOCK),
                                         gnorm_block, pp))
        return false;
    for (size_t v = 0; v < nv; v++)
        if (pp->a->vertex_class[v] != ISM_VERTEX_ISOLATED && isfinite(pp->gnorm[v]))
            pp->gnorm[n++] = pp->gnorm[v];
    pp->threshold = n ? o->singular_rel * ism_an_select_double_on(pp->pool, pp->gnorm, n, n / 2) : 0;
    return true;
}

static void aim_normal(float *normal, const double g[3])
{
    double len = ism_norm3(g), side = normal[0] * g[0] + normal[1] * g[1] + normal[2] * g[2];
    double s = (side < 0 ? -1 : 1) / len;
    for (int k = 0; k < 3; k++)
        normal[k] = (float)(g[k] * s);
}

/* Newton from vertex v; moves it when every condition holds. */
static enum outcome project_vertex(project_pass *pp, ism_eval_ws *ws, size_t v)
{
    if (pp->a->vertex_class[v] != ISM_VERTEX_MANIFOLD)
        return KEPT_FEATURE;
    double *pos = pp->m->pos + 3 * v, p[3] = {pos[0], pos[1], pos[2]}, g[3];
    double last = INFINITY;
    for (int i = 0; i < pp->steps; i++) {
        double fv = ism_eval_gradient(pp->f, ws, p[0], p[1], p[2], g);
        double gn = ism_norm3(g);
        if (!(gn > pp->threshold) || !isfinite(fv) || !isfinite(gn))
            return i == 0 ? KEPT_SINGULAR : KEPT_FAR;
        double s = fv / (gn * gn);
        for (int k = 0; k < 3; k++)
            p[k] -= s * g[k];
        last = fabs(s) * gn;
        if (last <= CONVERGED_REL * pp->shortest[v])
            break;
    }
    double d[3] = {p[0] - pos[0], p[1] - pos[1], p[2] - pos[2]}, dist = ism_norm3(d);
    if (!(last <= CONVERGED_REL * pp->shortest[v]) || !(dist <= 0.5 * pp->shortest[v]))
        return KEPT_FAR;
    ism_eval_gradient(pp->f, ws, p[0], p[1], p[2], g);
    if (!(ism_norm3(g) > pp->threshold) || !isfinite(ism_norm3(g)))
        return KEPT_FAR;
    memcpy(pos, p, sizeof p);
    aim_normal(pp->m->normal + 3 * v, g);
    pp->move[v] = dist;
    return MOVED;
}

static void project_block(void *ctx, ism_eval_ws *ws, size_t block)
{
    project_pass *pp = ctx;
    size_t end = ism_block_end(block, ISM_AN_EVAL_BLOCK, pp->m->nverts);
    for (size_t v = block * ISM_AN_EVAL_BLOCK; v < end; v++)
        pp->outcome[v] = (uint8_t)project_vertex(pp, ws, v);
}

static void tally(const project_pass *pp, ism_projection *out)
{
    memset(out, 0, sizeof *out);
    for (size_t v = 0; v < pp->m->nverts; v++) {
        switch (pp->outcome[v]) {
        case KEPT_FEATURE: out->kept_feature++; break;
        case KEPT_SINGULAR: out->kept_singular++; break;
        case KEPT_FAR: out->kept_far++; break;
        default:
            out->moved++;
            out->max_move = fmax(out->max_move, pp->move[v]);
        }
    }
}

bool ism_analysis_project(ism_mesh *m, const ism_tape *f, const ism_analysis *a,
                          const ism_analysis_options *o, ism_projection *out, ism_error *err)
{
    ism_analysis_options defaults;
    if (!o) {
        ism_analysis_options_default(&defaults);
        o = &defaults;
    }
    if (!f)
        return ism_an_fail(err, "projection: no function to project onto");
    if (!a->vertex_class || a->nverts != m->nverts)
        return ism_an_fail(err, "projection: the analysis is not of this mesh");
    if (!ism_an_check_options(o, err) || !ism_an_check_mesh(m, err))
        return false;
    size_t n = m->nverts ? m->nverts : 1;
    project_pass pp = {.m = m, .f = f, .a = a, .steps = o->newton_steps};
    /* threads made once for both loops, when there is more than one block of vertices */
    pp.pool = ism_an_pool_new(o->threads, m->nverts > ISM_AN_EVAL_BLOCK);
    pp.shortest = malloc(n * sizeof *pp.shortest);
    pp.outcome = malloc(n);
    pp.move = calloc(n, sizeof *pp.move);
    bool ok = pp.shortest && pp.outcome && pp.move && find_threshold(&pp, o);
    if (ok) {
        shortest_edges(m, pp.shortest);
        ok = ism_an_run_blocks(f, pp.pool, ism_blocks(m->nverts, ISM_AN_EVAL_BLOCK),
                               project_block, &pp);
    }
    if (ok && out)
        tally(&pp, out);
    free(pp.shortest);
    free(pp.outcome);
    free(pp.move);
    free(pp.gnorm);
    ism_pool_free(pp.pool);
    return ok ? true : ism_an_fail(err, "projection: out of memory");
}
