/* conform.c — the conformance pass's driver: double curves first (their ends may be pinch or
 * triple points shared by several curves), then the sheet-carrying singular points, each by
 * surgery (cut, chain the rim, refill); then compaction and the count of artefacts. */
#include "core/singular/conform.h"
#include "core/singular/conform_internal.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include "core/util/clock.h"

/* Radius of the ball or tube cut around the locus, in finest cells: the polygoniser's
 * confusion (digon loops, island caps in a neighbour cell, polygons crossing without a shared
 * edge) stays in the cells that hold the singularity and their neighbours, within about
 * 2√3 cells; a triangle is cut when any part of it comes this close. */
#define RHO_CELLS 2.5
/* ... and at least this many times the longest edge of the triangles there, where the
 * octree did not reach its finest depth. */
#define RHO_EDGES 1.25
/* The rim must lie where no other sheet comes within this many cells along its normals
 * (two spheres touching stay closer than a cell out to about √(cell × radius)); until then
 * the cut grows by GROW, at most MAX_GROW times. */
#define CLEAR_CELLS 1.5
#define GROW 1.4
#define MAX_GROW 6
/* Curve points closer than this many finest cells to the previous kept one are skipped (a
 * tracer's fine steps would only make slivers). */
#define CURVE_MIN_SPACING 0.5
/* A point counts as inside the box within this fraction of a cell. */
#define BOX_SLACK 1e-6

typedef struct conform_run {
    cf_ctx c;
    ism_locus *l;
    const ism_locus_options *o;
    uint32_t *point_vertex; /* per locus point: its mesh vertex, or CF_NONE */
} conform_run;

static double d2(const double *a, const double *b)
{
    double x = a[0] - b[0], y = a[1] - b[1], z = a[2] - b[2];
    return x * x + y * y + z * z;
}

static bool in_box(const double box[6], const double p[3], double slack)
{
    for (int k = 0; k < 3; k++)
        if (!(p[k] >= box[k] - slack && p[k] <= box[k + 3] + slack))
            return false;
    return true;
}

/* Cuts the triangles pred selects, growing *radius (read by pred through arg) until the rim
 * is clear of other sheets. */
static bool cut_clean(cf_ctx *c, cf_tri_pred pred, const void *arg, double *radius,
                      cf_loops *ls, uint32_t **rm, size_t *nrm)
{
    for (int k = 0;; k++) {
        if (!cf_cut_hole(c, pred, arg, ls, rm, nrm))
            return false;
        if (k == MAX_GROW || ls->n == 0 || cf_rim_clear(c, ls, CLEAR_CELLS * c->cell))
            return true;
        cf_undo(c, *rm, *nrm, c->m->ntris, c->m->nverts);
        free(*rm);
        cf_loops_free(ls);
        *radius *= GROW;
    }
}

/* ---- points ---- */

typedef struct ball {
    double p[3], r;
} ball;

static bool tri_in_ball(const cf_ctx *c, uint32_t t, const void *arg)
{
    const ball *b = arg;
    const uint32_t *v = c->m->tri + 3 * (size_t)t;
    const double *P = c->m->pos;
    return cf_point_triangle_d2(b->p, P + 3 * (size_t)v[0], P + 3 * (size_t)v[1],
                                P + 3 * (size_t)v[2]) < b->r * b->r;
}

static double loop_mean_dist(const cf_ctx *c, const cf_loop *l, const double p[3])
{
    double s = 0;
    for (size_t i = 0; i < l->n; i++)
        s += sqrt(d2(c->m->pos + 3 * (size_t)l->v[i], p)) / (double)l->n;
    return s;
}

static bool carries_sheets(int type)
{
    return type == ISM_SING_NODE || type == ISM_SING_CUSP || type == ISM_SING_DEGENERATE;
}

/* Cuts a ball around point i and fans each rim loop to one vertex at the point. False only
 * when out of memory (the mesh is then as before). */
static bool conform_point(conform_run *r, size_t i)
{
    cf_ctx *c = &r->c;
    ism_sing_point *pt = &r->l->points[i];
    if (!in_box(r->o->box, pt->p, BOX_SLACK * c->cell)) {
        pt->cones = 0;
        c->st->points_failed++;
        return true;
    }
    if (!cf_ctx_prepare(c))
        return false;
    double r0 = RHO_CELLS * c->cell;
    ball b = {{pt->p[0], pt->p[1], pt->p[2]}, fmax(r0, RHO_EDGES * cf_longest_edge_near(c, pt->p, r0))};
    size_t nt0 = c->m->ntris, nv0 = c->m->nverts, nrm;
    uint32_t *rm;
    cf_loops ls;
    if (!cut_clean(c, tri_in_ball, &b, &b.r, &ls, &rm, &nrm))
        return false;
    if (ls.n == 0) { /* no mesh around the point: nothing to join */
        cf_undo(c, rm, nrm, nt0, nv0);
        free(rm);
        cf_loops_free(&ls);
        pt->cones = 0;
        c->st->points_failed++;
        return true;
    }
    uint32_t apex = cf_add_vertex(c, pt->p, true);
    bool ok = apex != CF_NONE;
    for (size_t k = 0; ok && k < ls.n; k++)
        ok = cf_fan(c, &ls.l[k], apex, pt->p,
                    cf_ring_count(loop_mean_dist(c, &ls.l[k], pt->p), cf_loop_mean_edge(c, &ls.l[k])));
    if (!ok) {
        cf_undo(c, rm, nrm, nt0, nv0);
    } else {
        r->point_vertex[i] = apex;
        pt->cones = (int)ls.n;
        c->st->vertices_added++;
        c->st->points_conformed++;
        c->st->triangles_removed += nrm;
        c->st->triangles_added += c->m->ntris - nt0;
        if (pt->type == ISM_SING_NODE && ls.n < 2)
            c->st->points_short_cones++;
    }
    free(rm);
    cf_loops_free(&ls);
    return ok;
}

/* ---- curves ---- */

typedef struct tube {
    const cf_polyline *pl;
    double r;
} tube;

static bool tri_in_tube(const cf_ctx *c, uint32_t t, const void *arg)
{
    const tube *tb = arg;
    const uint32_t *v = c->m->tri + 3 * (size_t)t;
    const double *a = c->m->pos + 3 * (size_t)v[0], *b = c->m->pos + 3 * (size_t)v[1],
                 *d = c->m->pos + 3 * (size_t)v[2];
    /* the corners, the edge midpoints and the centroid: a triangle the curve passes through
     * has one of them within half its longest edge of the curve */
    double q[7][3];
    for (int k = 0; k < 3; k++) {
        q[0][k] = a[k];
        q[1][k] = b[k];
        q[2][k] = d[k];
        q[3][k] = (a[k] + b[k]) / 2;
        q[4][k] = (b[k] + d[k]) / 2;
        q[5][k] = (d[k] + a[k]) / 2;
        q[6][k] = (a[k] + b[k] + d[k]) / 3;
    }
    for (int j = 0; j < 7; j++)
        if (isfinite(cf_polyline_nearest(tb->pl, q[j], tb->r, NULL, NULL)))
            return true;
    return false;
}

/* The curve's points spaced at least min_step apart (the ends of an open curve kept). */
static double *thin_curve(const ism_sing_curve *cu, double min_step, size_t *n)
{
    double *p = malloc(3 * (cu->n + 1) * sizeof *p), m2 = min_step * min_step;
    if (!p)
        return NULL;
    size_t k = 0;
    for (size_t i = 0; i < cu->n; i++) {
        const double *q = cu->xyz + 3 * i;
        bool last = i == cu->n - 1, near_prev = k > 0 && d2(q, p + 3 * (k - 1)) < m2;
        if (near_prev && !last)
            continue;
        if (last && cu->closed && k > 1 && (near_prev || d2(q, p) < m2))
            continue;
        if (last && !cu->closed && near_prev && k > 1)
            k--; /* the true end replaces the kept point just before it */
        for (int j = 0; j < 3; j++)
            p[3 * k + j] = q[j];
        k++;
    }
    *n = k;
    return p;
}

/* Longest edge of the live triangles at vertices within r of the polyline. */
static double longest_edge_near_curve(const cf_ctx *c, const cf_polyline *pl, double r)
{
    double best = 0;
    for (size_t v = 0; v < c->inc_nverts; v++) {
        if (!isfinite(cf_polyline_nearest(pl, c->m->pos + 3 * v, r, NULL, NULL)))
            continue;
        best = fmax(best, cf_vertex_longest_edge(c, (uint32_t)v));
    }
    return best;
}

/* The mesh vertex of the curve's point i: a locus point's shared vertex at an end. */
static uint32_t curve_point_vertex(conform_run *r, const ism_sing_curve *cu, const double *p,
                                   size_t i, size_t n)
{
    int e = cu->closed ? -1 : i == 0 ? cu->end_point[0] : i == n - 1 ? cu->end_point[1] : -1;
    if (e >= 0 && (size_t)e < r->l->npoints) {
        if (r->point_vertex[e] == CF_NONE) {
            r->point_vertex[e] = cf_add_vertex(&r->c, r->l->points[e].p, true);
            r->c.st->vertices_added += r->point_vertex[e] != CF_NONE;
        }
        return r->point_vertex[e];
    }
    uint32_t v = cf_add_vertex(&r->c, p + 3 * i, true);
    r->c.st->vertices_added += v != CF_NONE;
    return v;
}

static bool conform_curve(conform_run *r, size_t ci)
{
    cf_ctx *c = &r->c;
    const ism_sing_curve *cu = &r->l->curves[ci];
    size_t n;
    double *p = thin_curve(cu, CURVE_MIN_SPACING * c->cell, &n);
    if (!p)
        return false;
    cf_polyline pl;
    double r0 = RHO_CELLS * c->cell;
    bool ok = cf_ctx_prepare(c) && cf_polyline_init(&pl, p, n, cu->closed && n >= 3, r0);
    if (!ok) {
        cf_polyline_free(&pl);
        free(p);
        c->st->curves_failed += n < 2;
        return n < 2; /* a curve of one point is nothing to conform to */
    }
    tube tb = {&pl, fmax(r0, RHO_EDGES * longest_edge_near_curve(c, &pl, r0))};
    size_t nt0 = c->m->ntris, nv0 = c->m->nverts, nrm = 0;
    uint32_t *rm = NULL, *cv = malloc(n * sizeof *cv);
    cf_loops ls = {0};
    ok = cv && cut_clean(c, tri_in_tube, &tb, &tb.r, &ls, &rm, &nrm);
    if (ok && ls.n == 0) {
        cf_undo(c, rm, nrm, nt0, nv0);
        c->st->curves_failed++;
    } else if (ok) {
        for (size_t i = 0; ok && i < n; i++)
            ok = (cv[i] = curve_point_vertex(r, cu, p, i, n)) != CF_NONE;
        ok = ok && cf_zip_loops(c, &pl, cv, &ls, tb.r);
        if (!ok) {
            cf_undo(c, rm, nrm, nt0, nv0);
            for (size_t i = 0; i < r->l->npoints; i++)
                if (r->point_vertex[i] != CF_NONE && r->point_vertex[i] >= nv0)
                    r->point_vertex[i] = CF_NONE;
        } else {
            c->st->curves_conformed++;
            c->st->triangles_removed += nrm;
            c->st->triangles_added += c->m->ntris - nt0;
        }
    }
    free(rm);
    free(cv);
    cf_loops_free(&ls);
    cf_polyline_free(&pl);
    free(p);
    return ok;
}

/* ---- driver ---- */

static bool stop_now(const ism_locus_options *o)
{
    return (o->cancel && *o->cancel) || (o->deadline_ms > 0 && ism_now_ms() > o->deadline_ms);
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

static bool run_items(conform_run *r)
{
    for (size_t i = 0; i < r->l->npoints; i++)
        r->l->points[i].cones = -1;
    for (size_t i = 0; i < r->l->ncurves; i++) {
        if (stop_now(r->o))
            return true;
        if (r->l->curves[i].kind != ISM_CURVE_DOUBLE) {
            r->c.st->curves_skipped++;
            continue;
        }
        if (!conform_curve(r, i))
            return false;
    }
    for (size_t i = 0; i < r->l->npoints; i++) {
        if (stop_now(r->o))
            return true;
        if (!carries_sheets(r->l->points[i].type)) {
            r->c.st->points_skipped++;
            continue;
        }
        if (!conform_point(r, i))
            return false;
    }
    return true;
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
    conform_run r = {.l = locus, .o = o};
    /* the longest side's cell: the octree's cells are boxes, the surgery must span them */
    double side = fmax(o->box[3] - o->box[0], fmax(o->box[4] - o->box[1], o->box[5] - o->box[2]));
    r.c = (cf_ctx){.f = f, .m = mesh, .st = st, .cell = ldexp(side, -o->max_depth),
                   .diag = sqrt(d2(o->box, o->box + 3))};
    r.c.ws = ism_eval_ws_new(f);
    r.point_vertex = malloc((locus->npoints + 1) * sizeof *r.point_vertex);
    bool ok = r.c.ws && r.point_vertex;
    for (size_t i = 0; ok && i < locus->npoints; i++)
        r.point_vertex[i] = CF_NONE;
    ok = ok && run_items(&r);
    if (ok && stop_now(o) && !locus->incomplete) {
        locus->incomplete = true;
        snprintf(locus->incomplete_why, sizeof locus->incomplete_why,
                 "conformance cut short (deadline or cancel)");
    }
    /* compaction also after a failure: what was refilled stays, nothing is left dead */
    bool compacted = r.c.dead == NULL || cf_compact(&r.c);
    if (!ok || !compacted)
        ism_error_set(err, "conform: out of memory");
    else
        ok = cf_count_artefacts(mesh, locus, ISM_CONFORM_ARTEFACT_TOL * r.c.diag,
                                &st->artefact_edges, &st->artefact_vertices, err);
    cf_ctx_free(&r.c);
    ism_eval_ws_free(r.c.ws);
    free(r.point_vertex);
    st->time_ms = ism_now_ms() - t0;
    return ok && compacted;
}
