/* conform.c — the conformance pass's driver: double curves first, in groups that share end
 * points (pinch, triple points: one vertex for all), then the sheet-carrying singular points,
 * each by surgery (cut, chain the rim, refill); then compaction and the count of artefacts. */
#include "core/singular/conform.h"
#include "core/singular/conform_internal.h"

#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include "core/util/clock.h"
#include "core/util/parallel.h"

static bool carries_sheets(int type)
{
    return type == ISM_SING_NODE || type == ISM_SING_CUSP || type == ISM_SING_DEGENERATE;
}

/* Between items: the reasons cf_poll stops on inside them (the budget is its own). */
static bool stop_now(cf_run *r)
{
    const ism_locus_options *o = r->o;
    if ((o->cancel && *o->cancel) || (o->deadline_ms > 0 && ism_now_ms() > o->deadline_ms))
        r->c.stopped = true;
    return r->c.stopped;
}

static bool check_input(const ism_tape *f, const ism_locus_options *o, const ism_locus *l,
                        const ism_mesh *m, ism_error *err)
{
    if (!f || !o || !l || !m)
        return ism_error_set(err, "conform: missing argument");
    for (int k = 0; k < 3; k++)
        if (!(o->box[k + 3] > o->box[k]) || !isfinite(o->box[k]) || !isfinite(o->box[k + 3]))
            return ism_error_set(err, "conform: empty or non-finite box on axis %d", k);
    if (o->max_depth < 0 || o->max_depth > 30)
        return ism_error_set(err, "conform: max_depth %d out of 0..30", o->max_depth);
    for (size_t i = 0; i < 3 * m->ntris; i++)
        if (m->tri[i] >= m->nverts)
            return ism_error_set(err, "conform: triangle vertex index out of range");
    return true;
}

static size_t find(size_t *parent, size_t i)
{
    while (parent[i] != i)
        i = parent[i] = parent[parent[i]];
    return i;
}

/* Double curves joined when they end at the same point of the locus: parent[] (union-find,
 * the root is the group's smallest curve index). owner has one slot per point. */
static void group_curves(const ism_locus *l, size_t *parent, size_t *owner)
{
    for (size_t i = 0; i < l->npoints; i++)
        owner[i] = SIZE_MAX;
    for (size_t i = 0; i < l->ncurves; i++)
        parent[i] = i;
    for (size_t i = 0; i < l->ncurves; i++) {
        const ism_sing_curve *cu = &l->curves[i];
        for (int e = 0; e < 2 && cu->kind == ISM_CURVE_DOUBLE && !cu->closed; e++) {
            int p = cu->end_point[e];
            if (p < 0 || (size_t)p >= l->npoints)
                continue;
            if (owner[p] == SIZE_MAX) {
                owner[p] = i;
                continue;
            }
            size_t a = find(parent, i), b = find(parent, owner[p]);
            parent[a > b ? a : b] = a < b ? a : b;
        }
    }
}

static bool run_curves(cf_run *r)
{
    size_t nc = r->l->ncurves;
    size_t *parent = malloc((nc + 1) * sizeof *parent), *idx = malloc((nc + 1) * sizeof *idx);
    size_t *owner = malloc((r->l->npoints + 1) * sizeof *owner);
    bool ok = parent && idx && owner;
    if (ok)
        group_curves(r->l, parent, owner);
    for (size_t g = 0; ok && g < nc && !stop_now(r); g++) {
        if (r->l->curves[g].kind != ISM_CURVE_DOUBLE) {
            r->c.st->curves_skipped++;
            continue;
        }
        if (find(parent, g) != g)
            continue;
        size_t n = 0;
        for (size_t i = g; i < nc; i++)
            if (r->l->curves[i].kind == ISM_CURVE_DOUBLE && find(parent, i) == g)
                idx[n++] = i;
        ok = cf_conform_curves(r, idx, n);
    }
    free(parent);
    free(idx);
    free(owner);
    return ok;
}

/* The points left to conform (sheet-carrying, no curve's end vertex, in the box) when they
 * are CF_COVER_PLAIN_PASSES or more: the box holding each one's first query
 * (cf_longest_edge_near's, CF_RHO_CELLS cells around it) is covered in one pass over the mesh,
 * where one pass a point would come first and then the growth's, which covers the box holding
 * every query (conform_grid.c): Barth's sextic, 30 nodes, took 11 passes (ism_conform_mesh,
 * callgrind: 79.0M -> 61.9M at E 0.0259, 126.9M -> 88.1M at E 0.00389). Not grown ahead for
 * the widenings as cf_longest_edge_near's own cover is: that filed triangles no query came to
 * (the same passes; 0.95M, 0.77M, 0.56M more at E 0.0259, 0.00389, 0.00109).
 * The triangles are filed in another order in their cells then, which two readers see: the
 * pinch untangling's list (conform_refine.c), so not done where the locus has a pinch point;
 * and folded_near's work count (conform_point.c: it stops at the first fold), which runs only
 * for a lone point (no finite clearance), and with 8 points here none is lone.
 * False when out of memory. */
static bool cover_points(cf_run *r)
{
    const ism_locus *l = r->l;
    double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
    size_t n = 0;
    for (size_t i = 0; i < l->npoints; i++) {
        const double *p = l->points[i].p;
        if (l->points[i].type == ISM_SING_PINCH)
            return true;
        bool in = carries_sheets(l->points[i].type) && r->point_vertex[i] == CF_NONE;
        for (int k = 0; k < 3 && in; k++)
            in = p[k] >= r->o->box[k] && p[k] <= r->o->box[k + 3];
        if (!in)
            continue; /* not conformed, or asking its own pass (a point just outside) */
        n++;
        for (int k = 0; k < 3; k++) {
            lo[k] = fmin(lo[k], p[k]);
            hi[k] = fmax(hi[k], p[k]);
        }
    }
    if (n < CF_COVER_PLAIN_PASSES || stop_now(r))
        return true;
    double qlo[3], qhi[3];
    cf_query_box(lo, hi, CF_RHO_CELLS * r->c.cell, qlo, qhi);
    return cf_ctx_prepare(&r->c) && cf_tgrid_cover(&r->c.grid, r->c.m, qlo, qhi, 0);
}

static bool run_items(cf_run *r)
{
    for (size_t i = 0; i < r->l->npoints; i++)
        r->l->points[i].cones = -1;
    if (!run_curves(r) || !cover_points(r))
        return false;
    for (size_t i = 0; i < r->l->npoints; i++) {
        if (stop_now(r))
            return true;
        if (!carries_sheets(r->l->points[i].type) || r->point_vertex[i] != CF_NONE) {
            r->c.st->points_skipped++; /* no sheet, or already a curve's end vertex */
            continue;
        }
        if (!cf_conform_point(r, i))
            return false;
    }
    return true;
}

/* Marks the locus incomplete (unless an earlier stage did), naming what was left as the
 * polygoniser made it: the double curves and sheet-carrying points not conformed. */
static void say_cut_short(const cf_run *r)
{
    ism_locus *l = r->l;
    if (l->incomplete)
        return;
    size_t curves = 0, points = 0;
    for (size_t i = 0; i < l->ncurves; i++)
        curves += l->curves[i].kind == ISM_CURVE_DOUBLE;
    curves -= r->c.st->curves_conformed + r->c.st->curves_failed;
    for (size_t i = 0; i < l->npoints; i++)
        points += carries_sheets(l->points[i].type) && l->points[i].cones < 0 &&
                  r->point_vertex[i] == CF_NONE;
    l->incomplete = true;
    const ism_locus_options *o = r->o;
    const char *why = o->cancel && *o->cancel ? "cancelled"
                      : o->conform_work_max && r->c.st->work > o->conform_work_max
                          ? "past its work budget"
                          : "past the deadline";
    snprintf(l->incomplete_why, sizeof l->incomplete_why,
             "conformance %s: %zu double curves, %zu points not conformed", why, curves, points);
}

/* The surgery's scale is the longest side's cell: the octree's cells are boxes, the surgery
 * must span them. */
static double longest_side(const ism_locus_options *o)
{
    return fmax(o->box[3] - o->box[0], fmax(o->box[4] - o->box[1], o->box[5] - o->box[2]));
}

double ism_conform_min_radius(const ism_locus_options *o)
{
    return CF_RHO_CELLS * ldexp(longest_side(o), -o->max_depth);
}

bool ism_conform_mesh(const ism_tape *f, const ism_locus_options *o, ism_locus *locus,
                      ism_mesh *mesh, ism_conform_stats *st, ism_error *err)
{
    double t0 = ism_now_ms();
    ism_conform_stats local;
    if (!st)
        st = &local;
    memset(st, 0, sizeof *st);
    if (!check_input(f, o, locus, mesh, err))
        return false;
    cf_run r = {.l = locus, .o = o};
    double side = longest_side(o);
    r.c = (cf_ctx){.f = f, .m = mesh, .st = st, .cell = ldexp(side, -o->max_depth),
                   .origin = {o->box[0], o->box[1], o->box[2]}, .extent = side,
                   .cancel = o->cancel, .deadline_ms = o->deadline_ms,
                   .work_max = o->conform_work_max,
                   .threads = ism_threads_resolve(o->threads)};
    r.c.ws = ism_eval_ws_new(f);
    r.point_vertex = malloc((locus->npoints + 1) * sizeof *r.point_vertex);
    bool ok = r.c.ws && r.point_vertex;
    for (size_t i = 0; ok && i < locus->npoints; i++)
        r.point_vertex[i] = CF_NONE;
    size_t nt0 = mesh->ntris;
    ok = ok && run_items(&r);
    int limit = o->limit_depth > 0 ? o->limit_depth : o->max_depth;
    ok = ok && (r.c.stopped || cf_refine_refill(&r.c, nt0, o->max_error, ldexp(side, -limit),
                                                locus));
    if (ok && stop_now(&r))
        say_cut_short(&r);
    /* compaction also after a failure: what was refilled stays, nothing is left dead */
    bool compacted = r.c.dead == NULL || cf_compact(&r.c);
    if (!ok || !compacted)
        ism_error_set(err, "conform: out of memory");
    st->grid_passes = r.c.grid.cover_passes;
    cf_ctx_free(&r.c);
    ism_eval_ws_free(r.c.ws);
    free(r.point_vertex);
    st->time_ms = ism_now_ms() - t0;
    return ok && compacted;
}
