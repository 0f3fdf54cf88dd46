/* conform_tube.c — the surgery along double curves: the triangles within a tube around a
 * group of curves (those meeting at shared end points: pinch and triple points, one vertex
 * for all) are cut, the tube growing until its rim is clear of other sheets; the curves'
 * points become mesh vertices, and every rim loop — one per side of each sheet — is zipped
 * to them (conform_zip.c), so each curve edge ends up with the crossing sheets' triangles. */
#include "core/singular/conform_internal.h"
#include "core/singular/curve_cell.h"
#include "core/util/vec3.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

/* Curve points closer than this many finest cells to the previous kept one are skipped (a
 * tracer's fine steps would only make slivers). */
#define CURVE_MIN_SPACING 0.5
/* Curve segments are gathered in runs at most this many tube radii across. */
#define CHUNK_RHO 2.0

typedef struct cf_tube {
    const cf_polyline *pl;
    size_t n;
    double r;
    double lo[3], hi[3]; /* the curves' bounding box */
    double reach;        /* edges up to this long are judged from vd alone */
    double vd_r;         /* the radius the memo holds distances for (0: none yet, -1:
                            the reach changed) */
    uint32_t gen_base;   /* the memo's generation at the group's first radius */
} tube;

/* A tube of radius r and reach round the n polylines pl: their points' box, no memo yet. */
static tube tube_make(const cf_polyline *pl, size_t n, double r, double reach)
{
    tube tb = {pl, n, r, {INFINITY, INFINITY, INFINITY}, {-INFINITY, -INFINITY, -INFINITY},
               reach, 0, 0};
    for (size_t k = 0; k < n; k++)
        for (size_t i = 0; i < pl[k].n; i++)
            for (int j = 0; j < 3; j++) {
                tb.lo[j] = fmin(tb.lo[j], pl[k].p[3 * i + j]);
                tb.hi[j] = fmax(tb.hi[j], pl[k].p[3 * i + j]);
            }
    return tb;
}

/* Vertex v's distance to the nearest of the group's curves, asked of the polylines and
 * memoised (vertex_distance). */
static __attribute__((noinline)) double vertex_query(const cf_ctx *c, const tube *tb,
                                                     uint32_t v, uint32_t *curve)
{
    const double *p = c->m->pos + 3 * (size_t)v;
    double d = INFINITY;
    bool in = true;
    for (int k = 0; k < 3; k++)
        in = in && p[k] >= tb->lo[k] - tb->r - tb->reach && p[k] <= tb->hi[k] + tb->r + tb->reach;
    *curve = 0;
    double mag = cf_max2(fabs(p[0]), cf_max2(fabs(p[1]), fabs(p[2])));
    for (size_t i = 0; in && i < tb->n; i++) {
        /* a curve whose box is farther than the nearest so far can be neither nearer nor
         * as near (the first of equals is kept) */
        if (isfinite(d) && cf_polyline_box_distance(&tb->pl[i], p) > d + CF_QUERY_SLACK * (d + mag))
            continue;
        double di = cf_polyline_nearest(&tb->pl[i], p, tb->r + tb->reach, NULL, NULL);
        if (di < d) {
            d = di;
            *curve = (uint32_t)i;
        }
    }
    c->memo_gen[v] = c->gen;
    c->memo_i[v] = *curve;
    c->memo_d[v] = d;
    return d;
}

/* Whether the memo holds vertex v's distance for the tube's radius. */
static inline bool memo_holds(const cf_ctx *c, const tube *tb, uint32_t v)
{
    /* a distance found at a smaller radius of the same group stands: it is the distance to
     * the nearest segment, which a wider search finds again (only "nothing within reach"
     * must be asked again) */
    return c->memo_gen[v] == c->gen || (c->memo_gen[v] >= tb->gen_base && isfinite(c->memo_d[v]));
}

/* Vertex v's distance to the nearest of the group's curves (INFINITY beyond r + reach) and
 * that curve, memoised in the context for the current radius. Inline but for the query: the
 * callers ask only the corners they need, most answered by the memo. */
static inline double vertex_distance(const cf_ctx *c, const tube *tb, uint32_t v,
                                     uint32_t *curve)
{
    if (memo_holds(c, tb, v)) {
        *curve = c->memo_i[v];
        return c->memo_d[v];
    }
    return vertex_query(c, tb, v, curve);
}

bool cf_far_by_corners(const double q[3], const double *const corner[3], const double vd[3],
                       double r, double reach)
{
    double lb = 0, mag = cf_max2(fabs(q[0]), cf_max2(fabs(q[1]), fabs(q[2])));
    for (int k = 0; k < 3; k++) {
        double dk = isfinite(vd[k]) ? vd[k] : r + reach;
        lb = cf_max2(lb, dk - ism_dist3(q, corner[k]));
    }
    return lb > r + CF_QUERY_SLACK * (lb + mag);
}

static bool tri_in_tube(const cf_ctx *c, uint32_t t, void *arg)
{
    tube *tb = arg;
    const uint32_t *v = c->m->tri + 3 * (size_t)t;
    const double *a = c->m->pos + 3 * (size_t)v[0], *b = c->m->pos + 3 * (size_t)v[1],
                 *d = c->m->pos + 3 * (size_t)v[2];
    uint32_t vc[3];
    double vd[3];
    /* a corner within r decides: the memoised corners are read first, then the others asked
     * one by one until one is (a corner no triangle needs is never asked: Klein bottle at
     * E 0.00327, asking all three of every candidate's cost 34K queries) */
    bool known[3];
    for (int k = 0; k < 3; k++)
        if ((known[k] = memo_holds(c, tb, v[k])) && c->memo_d[v[k]] <= tb->r)
            return true;
    for (int k = 0; k < 3; k++) {
        vd[k] = vertex_distance(c, tb, v[k], &vc[k]);
        if (!known[k] && vd[k] <= tb->r)
            return true;
    }
    /* no corner within r; every corner farther than r + the longest edge: decided */
    double dmin = cf_min2(vd[0], cf_min2(vd[1], vd[2]));
    double edge = sqrt(cf_max2(ism_sqdist3(a, b), cf_max2(ism_sqdist3(b, d), ism_sqdist3(d, a))));
    if (edge <= tb->reach && !(dmin <= tb->r + edge))
        return false;
    /* the corners, the edge midpoints and the centroid: a triangle the curve passes through
     * has one of them within half its longest edge of the curve. The corners are known to be
     * farther than r from every curve (vd is the nearest curve's distance, or beyond the
     * tube's box grown by r + reach when not finite; a query within r would find the same
     * nearest segment), so only the other four are asked, those the corners' bound
     * (cf_far_by_corners) leaves. */
    double q[4][3];
    for (int k = 0; k < 3; k++) {
        q[0][k] = (a[k] + b[k]) / 2;
        q[1][k] = (b[k] + d[k]) / 2;
        q[2][k] = (d[k] + a[k]) / 2;
        q[3][k] = (a[k] + b[k] + d[k]) / 3;
    }
    const double *corner[3] = {a, b, d};
    bool ask[4];
    for (int j = 0; j < 4; j++)
        ask[j] = !cf_far_by_corners(q[j], corner, vd, tb->r, tb->reach);
    /* near the rim of the cut only: the curves nearest its corners (all of them when a
     * corner is beyond the memo's reach, a triangle longer than reach) */
    bool all = !(isfinite(vd[0]) && isfinite(vd[1]) && isfinite(vd[2]));
    for (size_t i = 0; i < tb->n; i++) {
        if (!all && vc[0] != i && vc[1] != i && vc[2] != i)
            continue;
        for (int j = 0; j < 4; j++)
            if (ask[j] && isfinite(cf_polyline_nearest(&tb->pl[i], q[j], tb->r, NULL, NULL)))
                return true;
    }
    return false;
}

/* The triangles whose boxes meet a segment's box grown by r, for every segment of the
 * curves: all those with a point within r of a curve. The segments are queried in runs
 * whose box spans at most CHUNK_RHO radii (a run's box and a segment's differ little along
 * the curve; each query reads the grid cells of its box grown by r on every side, so runs
 * about 2r long read the fewest cells per length of curve). */
static bool gather_runs(cf_ctx *c, const cf_polyline *pl, size_t n, double r, cf_tris *out)
{
    for (size_t k = 0; k < n; k++) {
        size_t segs = pl[k].closed ? pl[k].n : pl[k].n - 1;
        for (size_t i = 0; i < segs;) {
            double lo[3], hi[3];
            for (int j = 0; j < 3; j++)
                lo[j] = hi[j] = pl[k].p[3 * i + j];
            for (; i < segs; i++) { /* add segment i while the run stays short */
                const double *b = pl[k].p + 3 * ((i + 1) % pl[k].n);
                double ext = 0;
                for (int j = 0; j < 3; j++)
                    ext = cf_max2(ext, cf_max2(hi[j], b[j]) - cf_min2(lo[j], b[j]));
                if (ext > CHUNK_RHO * r && (hi[0] > lo[0] || hi[1] > lo[1] || hi[2] > lo[2]))
                    break;
                for (int j = 0; j < 3; j++) {
                    lo[j] = cf_min2(lo[j], b[j]);
                    hi[j] = cf_max2(hi[j], b[j]);
                }
            }
            double qlo[3], qhi[3];
            cf_query_box(lo, hi, r, qlo, qhi);
            if (!cf_tgrid_gather(&c->grid, c->m, qlo, qhi, c->dead, out))
                return false;
        }
    }
    return true;
}

/* The memo made current for the tube's radius: at a new radius a new generation (the
 * group's first: gen_base), the distances found at smaller ones kept (memo_holds). False
 * when out of memory. */
static bool tube_memo_current(cf_ctx *c, tube *tb)
{
    if (tb->vd_r != tb->r) { /* a new radius: the memoised distances are stale */
        if (!cf_memo_reset(c))
            return false;
        if (tb->vd_r == 0)
            tb->gen_base = c->gen;
        tb->vd_r = tb->r;
    }
    return true;
}

static bool gather_tube(cf_ctx *c, void *arg, cf_tris *out)
{
    tube *tb = arg;
    if (!tube_memo_current(c, tb))
        return false;
    /* the curves' box grown by r holds every run's query box: one pass over the mesh files
     * what the runs need, and (ahead by r) what the next widenings need */
    double lo[3], hi[3];
    cf_query_box(tb->lo, tb->hi, tb->r, lo, hi);
    return cf_tgrid_cover(&c->grid, c->m, lo, hi, tb->r) &&
           gather_runs(c, tb->pl, tb->n, tb->r, out);
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
        bool last = i == cu->n - 1, near_prev = k > 0 && ism_sqdist3(q, p + 3 * (k - 1)) < m2;
        if (near_prev && !last)
            continue;
        if (last && cu->closed && k > 1 && (near_prev || ism_sqdist3(q, p) < m2))
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

/* Longest edge of the live triangles with a vertex within tb->r of one of the curves (*out;
 * false when out of memory). A triangle no longer than the longest so far cannot raise it:
 * its corners are not asked (the maximum is the same; the cut that follows asks the
 * distances it needs, memoised from the first gather_tube of the group on). Asking every
 * candidate's corners cost the Klein bottle at E 0.00327 23.7K queries here, 51M
 * instructions, most of them for vertices the cut asked again at its wider reach. */
static bool longest_edge_near_curves(cf_ctx *c, tube *tb, double *out)
{
    cf_tris cand = {0};
    cf_tgrid_begin(&c->grid);
    bool ok = gather_tube(c, tb, &cand);
    double best = 0;
    for (size_t i = 0; ok && i < cand.n && !cf_poll(c, 1); i++) {
        double e2 = cf_triangle_longest_edge2(c->m, cand.t[i]);
        if (!(e2 > best))
            continue; /* no longer than the longest so far */
        const uint32_t *v = c->m->tri + 3 * (size_t)cand.t[i];
        bool near = false;
        for (int k = 0; k < 3 && !near; k++) {
            uint32_t curve;
            near = vertex_distance(c, tb, v[k], &curve) <= tb->r;
        }
        if (near)
            best = e2;
    }
    free(cand.t);
    *out = sqrt(best);
    return ok;
}

/* The mesh vertex of the curve's point i: a locus point's shared vertex at an end. */
static uint32_t curve_point_vertex(cf_run *r, const ism_sing_curve *cu, const double *p,
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

/* The group's polylines (thinned copies of the curves' points). */
typedef struct group {
    size_t n;
    const ism_sing_curve **cu;
    double **pts;
    size_t *npts;
    cf_polyline *pl;
    uint32_t **cv;
} group;

static void group_free(group *g)
{
    for (size_t k = 0; k < g->n; k++) {
        if (g->pl)
            cf_polyline_free(&g->pl[k]);
        if (g->pts)
            free(g->pts[k]);
        if (g->cv)
            free(g->cv[k]);
    }
    free(g->cu);
    free(g->pts);
    free(g->npts);
    free(g->pl);
    free(g->cv);
}

/* False when out of memory; curves of fewer than two points are left out (counted failed). */
static bool group_init(cf_run *r, const size_t *idx, size_t n, group *g)
{
    memset(g, 0, sizeof *g);
    g->cu = calloc(n, sizeof *g->cu);
    g->pts = calloc(n, sizeof *g->pts);
    g->npts = calloc(n, sizeof *g->npts);
    g->pl = calloc(n, sizeof *g->pl);
    g->cv = calloc(n, sizeof *g->cv);
    if (!g->cu || !g->pts || !g->npts || !g->pl || !g->cv)
        return false;
    double r0 = CF_RHO_CELLS * r->c.cell;
    for (size_t i = 0; i < n; i++) {
        const ism_sing_curve *cu = &r->l->curves[idx[i]];
        size_t k = g->n, m;
        if (!(g->pts[k] = thin_curve(cu, CURVE_MIN_SPACING * r->c.cell, &m)))
            return false;
        g->n++;
        if (m < 2) {
            r->c.st->curves_failed++;
            free(g->pts[k]);
            g->pts[k] = NULL;
            g->n--;
            continue;
        }
        g->cu[k] = cu;
        g->npts[k] = m;
        if (!cf_polyline_init(&g->pl[k], g->pts[k], m, cu->closed && m >= 3, r0) ||
            !(g->cv[k] = malloc(m * sizeof *g->cv[k])))
            return false;
        for (int e = 0; e < 2 && !g->pl[k].closed; e++)
            g->pl[k].pinch[e] = cu->end_type[e] == ISM_END_PINCH;
    }
    return true;
}

/* The surgery round a group of curves, on the scale of its cells (set by cf_conform_curves). */
static bool conform_group(cf_run *r, const size_t *idx, size_t n);

bool cf_conform_curves(cf_run *r, const size_t *idx, size_t n)
{
    /* the group's scale: the finest cell the octree split its nodes to along its curves
     * (curve_cell.h), else the depth's */
    double depth_cell = r->c.cell;
    for (size_t i = 0; i < n; i++)
        r->c.cell = fmin(r->c.cell, ism_curve_mesh_cell(&r->l->curves[idx[i]], depth_cell));
    bool ok = conform_group(r, idx, n);
    r->c.cell = depth_cell;
    return ok;
}

static bool conform_group(cf_run *r, const size_t *idx, size_t n)
{
    cf_ctx *c = &r->c;
    group g;
    bool ok = cf_ctx_prepare(c) && group_init(r, idx, n, &g);
    if (!ok || g.n == 0) {
        group_free(&g);
        return ok;
    }
    /* on lattice lines the polygoniser's mesh may hold the curves already: no surgery */
    if (cf_curves_kept(r, g.pl, g.cu, g.n)) {
        c->st->curves_conformed += g.n;
        c->st->curves_kept += g.n;
        group_free(&g);
        return true;
    }
    /* the tube's radius and reach from the longest edge near the curves, measured with a
     * reach of r0 (the finest cells' edges are shorter) */
    double r0 = CF_RHO_CELLS * c->cell, longest = 0;
    tube tb = tube_make(g.pl, g.n, r0, r0);
    if (!longest_edge_near_curves(c, &tb, &longest) || c->stopped) {
        group_free(&g);
        return c->stopped; /* stopped: nothing cut yet */
    }
    tb.r = fmax(r0, CF_RHO_EDGES * longest);
    /* as wide as the sheets' crossing angle asks (no wider than the cut could grow) */
    tb.r = fmax(tb.r, fmin(cf_crossing_radius(c, g.pl, g.n), tb.r * pow(CF_GROW, CF_MAX_GROW)));
    if (fmax(longest, r0) != tb.reach) { /* "nothing within reach" answers are stale */
        tb.reach = fmax(longest, r0);
        tb.vd_r = -1;
    }
    cf_cutter cut = {tri_in_tube, gather_tube, &tb};
    size_t nt0 = c->m->ntris, nv0 = c->m->nverts, nrm = 0;
    uint32_t *rm = NULL;
    cf_loops ls = {0};
    ok = cf_cut_clean(c, &cut, &tb.r, INFINITY, &ls, &rm, &nrm);
    if (ok && !c->stopped && ls.n > 0 && g.n == 1) {
        /* a lone curve: the kept triangles sticking into its hole cut too (conform_ears.c) */
        ok = cf_drop_spikes(c, &ls, &rm, &nrm);
        if (!ok)
            cf_undo(c, rm, nrm, nt0, nv0); /* out of memory: as before */
    }
    if (ok && c->stopped) {
        c->st->items_stopped++;
    } else if (ok && ls.n == 0) {
        cf_undo(c, rm, nrm, nt0, nv0);
        c->st->curves_failed += g.n;
    } else if (ok) {
        for (size_t k = 0; k < g.n; k++)
            for (size_t i = 0; ok && i < g.npts[k]; i++)
                ok = (g.cv[k][i] = curve_point_vertex(r, g.cu[k], g.pts[k], i, g.npts[k])) !=
                     CF_NONE;
        ok = ok && cf_zip_loops(c, g.pl, (const uint32_t *const *)g.cv, g.n, &ls, tb.r);
        if (ok && c->stopped)
            c->st->items_stopped++;
        if (!ok || c->stopped) {
            cf_undo(c, rm, nrm, nt0, nv0);
            for (size_t i = 0; i < r->l->npoints; i++)
                if (r->point_vertex[i] != CF_NONE && r->point_vertex[i] >= nv0)
                    r->point_vertex[i] = CF_NONE;
        } else {
            c->st->curves_conformed += g.n;
            c->st->triangles_removed += nrm;
            c->st->triangles_added += c->m->ntris - nt0;
        }
    }
    free(rm);
    cf_loops_free(&ls);
    group_free(&g);
    return ok;
}

cf_tube *cf_tube_new(const cf_polyline *pl, size_t npl, double r, double reach)
{
    tube *tb = malloc(sizeof *tb);
    if (tb)
        *tb = tube_make(pl, npl, r, reach);
    return tb;
}

bool cf_tube_radius(cf_ctx *c, cf_tube *tb, double r)
{
    tb->r = r;
    return tube_memo_current(c, tb);
}

bool cf_tube_selects(const cf_ctx *c, cf_tube *tb, uint32_t t)
{
    return tri_in_tube(c, t, tb);
}

void cf_tube_free(cf_tube *tb)
{
    free(tb);
}
