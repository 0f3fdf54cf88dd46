/* conform_point.c — the surgery at a sheet-carrying singular point (node, cusp, degenerate
 * contact): the triangles within a ball around it are cut (the ball grows until its rim is
 * clear of other sheets), and every rim loop — one per cone or nappe, found again even where
 * the polygoniser had left a nappe as an island — is fanned through projected rings to ONE
 * vertex at the point's position. */
#include "core/singular/conform_internal.h"
#include "core/util/vec3.h"

#include <math.h>
#include <stdlib.h>

/* A point counts as inside the box within this fraction of a cell. */
#define BOX_SLACK 1e-6
/* The ball never reaches past this fraction of the distance to the nearest other point or
 * curve of the locus: two balls never overlap, and a small part of the surface between two
 * nodes is never swallowed whole. */
#define RHO_SEPARATION 0.45
/* A lone point (nothing else of the locus in the box: its clearance is infinite) has no
 * distance to bound its ball by, and its ball does not grow: it keeps its start radius
 * (CF_RHO_CELLS cells, or CF_RHO_EDGES × the longest edge there — what the polygoniser's
 * confusion needs), except to seek a lost mesh (below). Growing while the rim sees another
 * sheet close by swallowed both sheets at a coarse depth: the horn cyclide at depth 3 (cell
 * 4, ball 10 → up to 75) joined its two horns into one rim loop (one cone, χ 2 instead of
 * 1), and the wide cone x² + y² = 36 z² in ±1 at depth 3 its two nappes (χ 2 or 0 in the
 * shifted boxes instead of 1); there the other sheet stays close to the rim at any radius.
 * With no mesh within the ball (sheets thinner than a cell near the point, lost by the
 * polygoniser), the ball grows by SEEK_GROW up to SEEK_CELLS cells looking for their rims. */
#define SEEK_GROW 1.5
#define SEEK_CELLS 8.0
/* A rim loop that steps backwards round the point (seen from it, against the loop's own
 * turning) gives fan and ring triangles turned over: the polygoniser's pleats reach past the
 * start radius. Two unit spheres touching, depth 5, box 0.37 cell off the lattice: a loop of
 * 134 vertices with 23 backward steps at 2.5 cells, 149 folded edges; star-shaped loops from
 * 3 cells on, no fold. The ball then grows by STAR_GROW while its loops step backwards, up to
 * SEEK_CELLS cells (and never past the clearance), as long as it cuts as many loops as at the
 * start (a merge of two sheets' rims is never taken); with no star-shaped cut within that,
 * the start radius is kept. */
#define STAR_GROW 1.2
/* A lone point's ball grows the same way past the polygoniser's folds (an edge whose two
 * triangles face apart) within SEEK_CELLS cells of it: where a sheet grazes a lattice plane
 * beside the other sheet the pleat can lie wholly outside a star-shaped rim. Two unit spheres
 * touching, depth 6, box moved by irrational fractions of a cell: the right sphere meets the
 * plane x = 0.0285 (0.41 cell) at 13° along the circle r = √(2 × 0.0285) = 3.5 cells, where
 * the left sphere is 0.8 cell away in the same cells; four edges there fold (123–159°) outside
 * the 2.5-cell ball (test remesh_needles/touching_spheres_keep_topology_and_lose_needles). A
 * node or curve with a clearance grows its cut until its rim is clear instead (cf_cut_clean). */
/* NODE_SEEK: a node (certified: the surface passes through it) with other parts of the locus
 * in the box seeks the mesh round it up to its clearance, not SEEK_CELLS finest cells: under
 * an error bound the cells near a node are sized by E, not by the finest depth, and the
 * polygoniser may cap both nappes farther than 8 finest cells from it (Chmutov's quartic at
 * E = 1e-2, depth 10 at most (cell 0.0023), box ±1.2 moved by 0.37 / -0.23 / 0.41 of a
 * depth-9 cell: nothing within 0.019 of the node (-1/√2, 0, 1/√2), the node left out).
 * The first radius that cuts any mesh is kept, so the nearest sheet is taken.
 *
 * A node (a cone of two nappes) whose cut finds one rim loop: the polygoniser capped the other
 * nappe beyond the start radius (its cells sized by the error bound, not by the node). The
 * ball then grows by SEEK_GROW, up to SEEK_CELLS × the larger of the finest cell and the
 * loop's mean edge (never past the clearance), until it cuts two loops; with none, the
 * radius it had is kept. Chmutov's quartic at E = 1e-2 in the box ±1.2 moved by 1e-3: two
 * of its 12 nodes cut one loop of 4 vertices at radius 0.013, the other nappe capped; at
 * 0.37 cell off the lattice three (χ 6 and 8 instead of 4). */

static bool in_box(const double box[6], const double p[3], double slack)
{
    for (int k = 0; k < 3; k++)
        if (!(p[k] >= box[k] - slack && p[k] <= box[k + 3] + slack))
            return false;
    return true;
}

typedef struct ball {
    double p[3], r;
} ball;

static bool tri_in_ball(const cf_ctx *c, uint32_t t, void *arg)
{
    const ball *b = arg;
    const uint32_t *v = c->m->tri + 3 * (size_t)t;
    const double *P = c->m->pos;
    return cf_point_triangle_d2(b->p, P + 3 * (size_t)v[0], P + 3 * (size_t)v[1],
                                P + 3 * (size_t)v[2]) < b->r * b->r;
}

/* The triangles whose boxes meet the ball's cube: every one within r of its centre. */
static bool gather_ball(cf_ctx *c, void *arg, cf_tris *out)
{
    const ball *b = arg;
    double lo[3], hi[3];
    cf_query_box(b->p, b->p, b->r, lo, hi);
    return cf_tgrid_gather(&c->grid, c->m, lo, hi, c->dead, out);
}

static double loop_mean_dist(const cf_ctx *c, const cf_loop *l, const double p[3])
{
    double s = 0;
    for (size_t i = 0; i < l->n; i++)
        s += sqrt(ism_sqdist3(c->m->pos + 3 * (size_t)l->v[i], p)) / (double)l->n;
    return s;
}

/* Closed loop l steps backwards round p somewhere: the turn (a − p) × (b − p) of one of its
 * edges ab does not point along the sum of them all. */
static bool steps_backwards(const cf_ctx *c, const cf_loop *l, const double p[3])
{
    double sum[3] = {0, 0, 0}, t[3];
    for (size_t i = 0; l->closed && i < l->n; i++) {
        ism_tri_cross3(p, c->m->pos + 3 * (size_t)l->v[i],
                       c->m->pos + 3 * (size_t)l->v[(i + 1) % l->n], t);
        for (int k = 0; k < 3; k++)
            sum[k] += t[k];
    }
    for (size_t i = 0; l->closed && i < l->n; i++) {
        ism_tri_cross3(p, c->m->pos + 3 * (size_t)l->v[i],
                       c->m->pos + 3 * (size_t)l->v[(i + 1) % l->n], t);
        if (!(ism_dot3(t, sum) > 0))
            return true;
    }
    return false;
}

static bool star_shaped(const cf_ctx *c, const cf_loops *ls, const double p[3])
{
    for (size_t k = 0; k < ls->n; k++)
        if (steps_backwards(c, &ls->l[k], p))
            return false;
    return true;
}

/* *found: a live triangle within r of p has an edge of two live triangles facing apart (their
 * normals more than 90° apart). False when out of memory. */
static bool folded_near(cf_ctx *c, const double p[3], double r, bool *found)
{
    ball q = {{p[0], p[1], p[2]}, r};
    cf_tris cand = {0};
    cf_tgrid_begin(&c->grid);
    bool ok = gather_ball(c, &q, &cand);
    *found = false;
    const double *P = c->m->pos;
    for (size_t i = 0; ok && !*found && i < cand.n && !cf_poll(c, 1); i++) {
        uint32_t t = cand.t[i], tt[3];
        if (!tri_in_ball(c, t, &q))
            continue;
        const uint32_t *v = c->m->tri + 3 * (size_t)t;
        double n[3], m[3];
        ism_tri_cross3(P + 3 * (size_t)v[0], P + 3 * (size_t)v[1], P + 3 * (size_t)v[2], n);
        for (int k = 0; k < 3 && !*found; k++) {
            if (cf_live_on_edge(c, v[k], v[(k + 1) % 3], tt, 3) != 2)
                continue;
            const uint32_t *w = c->m->tri + 3 * (size_t)(tt[0] == t ? tt[1] : tt[0]);
            ism_tri_cross3(P + 3 * (size_t)w[0], P + 3 * (size_t)w[1], P + 3 * (size_t)w[2], m);
            *found = ism_dot3(n, m) < 0;
        }
    }
    free(cand.t);
    return ok;
}

/* Cuts ball b into *ls, *rm, *nrm, the cut growing while its rim is unclear up to the
 * clearance (a lone point's not at all); false when out of memory. */
static bool cut_ball(cf_ctx *c, const cf_cutter *cut, ball *b, double clear_r, cf_loops *ls,
                     uint32_t **rm, size_t *nrm)
{
    return cf_cut_clean(c, cut, &b->r, isfinite(clear_r) ? clear_r : b->r, ls, rm, nrm);
}

/* Puts back the cut and cuts again at radius r. */
static bool recut(cf_ctx *c, const cf_cutter *cut, ball *b, double r, double clear_r,
                  size_t nt0, size_t nv0, cf_loops *ls, uint32_t **rm, size_t *nrm)
{
    cf_undo(c, *rm, *nrm, nt0, nv0);
    free(*rm);
    cf_loops_free(ls);
    b->r = r;
    return cut_ball(c, cut, b, clear_r, ls, rm, nrm);
}

/* For a node whose cut holds fewer than two loops: cuts again at balls SEEK_GROW times larger
 * up to max_r; the first cut with two loops or more is kept, else the cut at the radius it
 * started from. False when out of memory. */
static bool cut_both_nappes(cf_ctx *c, const cf_cutter *cut, ball *b, double clear_r,
                            double max_r, size_t nt0, size_t nv0, cf_loops *ls, uint32_t **rm,
                            size_t *nrm)
{
    double r0 = b->r;
    while (!c->stopped && ls->n < 2) {
        double next = b->r * SEEK_GROW;
        if (next > max_r)
            return recut(c, cut, b, r0, clear_r, nt0, nv0, ls, rm, nrm);
        if (!recut(c, cut, b, next, clear_r, nt0, nv0, ls, rm, nrm))
            return false;
    }
    return true;
}

/* While the cut's loops step backwards round the point — or, past_folds (a lone point), a
 * fold lies within max_r of it — cuts again at a ball STAR_GROW times larger up to max_r; the
 * first star-shaped cut with as many loops and no such fold is kept, else the first
 * star-shaped one, else the cut at the radius it started from. False when out of memory. */
static bool cut_star_shaped(cf_ctx *c, const cf_cutter *cut, ball *b, double clear_r,
                            double max_r, bool past_folds, size_t nt0, size_t nv0,
                            cf_loops *ls, uint32_t **rm, size_t *nrm)
{
    double back = b->r;
    bool star_seen = false;
    size_t nloops = ls->n;
    for (;;) {
        bool star = star_shaped(c, ls, b->p), fold = false;
        if (star && !star_seen) {
            back = b->r;
            star_seen = true;
        }
        if (star && past_folds && !folded_near(c, b->p, max_r, &fold))
            return false;
        if (c->stopped || (star && !fold))
            return true;
        double next = b->r * STAR_GROW;
        if (next > max_r)
            return recut(c, cut, b, back, clear_r, nt0, nv0, ls, rm, nrm);
        if (!recut(c, cut, b, next, clear_r, nt0, nv0, ls, rm, nrm))
            return false;
        if (!c->stopped && ls->n != nloops)
            return recut(c, cut, b, back, clear_r, nt0, nv0, ls, rm, nrm);
    }
}

bool cf_conform_point(cf_run *r, size_t i)
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
    double r0 = CF_RHO_CELLS * c->cell, longest;
    if (!cf_longest_edge_near(c, pt->p, r0, &longest))
        return false;
    if (c->stopped)
        return true;
    ball b = {{pt->p[0], pt->p[1], pt->p[2]}, fmax(r0, CF_RHO_EDGES * longest)};
    cf_cutter cut = {tri_in_ball, gather_ball, &b};
    size_t nt0 = c->m->ntris, nv0 = c->m->nverts, nrm;
    uint32_t *rm;
    cf_loops ls;
    double clear_r = RHO_SEPARATION * ism_locus_clearance(r->l, i);
    double star_r = fmin(clear_r, SEEK_CELLS * c->cell);
    /* see NODE_SEEK's comment */
    double seek_r = pt->type == ISM_SING_NODE && isfinite(clear_r) ? clear_r : star_r;
    for (;;) {
        /* a lone point keeps its ball's radius (see SEEK_GROW's comment) */
        if (!cut_ball(c, &cut, &b, clear_r, &ls, &rm, &nrm))
            return false;
        if (c->stopped) {
            c->st->items_stopped++;
            return true;
        }
        if (ls.n > 0 || b.r * SEEK_GROW > seek_r)
            break;
        /* nothing round the point yet (thin horns the polygoniser lost): look further */
        cf_undo(c, rm, nrm, nt0, nv0);
        free(rm);
        cf_loops_free(&ls);
        b.r *= SEEK_GROW;
    }
    if (ls.n == 1 && pt->type == ISM_SING_NODE) { /* see NODE_SEEK's comment */
        double both_r = fmin(clear_r, SEEK_CELLS * fmax(c->cell, cf_loop_mean_edge(c, &ls.l[0])));
        if (!cut_both_nappes(c, &cut, &b, clear_r, both_r, nt0, nv0, &ls, &rm, &nrm))
            return false;
    }
    if (ls.n > 0 && !cut_star_shaped(c, &cut, &b, clear_r, star_r, !isfinite(clear_r), nt0,
                                     nv0, &ls, &rm, &nrm))
        return false;
    if (c->stopped) {
        c->st->items_stopped++;
        free(rm);
        cf_loops_free(&ls);
        return true;
    }
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
    for (size_t k = 0; ok && k < ls.n && !c->stopped; k++)
        ok = cf_fan(c, &ls.l[k], apex, pt->p,
                    cf_ring_count(loop_mean_dist(c, &ls.l[k], pt->p), cf_loop_mean_edge(c, &ls.l[k])));
    if (ok && c->stopped)
        c->st->items_stopped++;
    if (!ok || c->stopped) {
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

