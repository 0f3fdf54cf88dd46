/* conform_refine.c — the refill's triangles checked once every surgery is done: those
 * farther than E from f = 0 (max_error, or without one a quarter of the finest cell: what the
 * polygoniser's flatness test held its cells to) are halved, then those turned over (facing
 * against ∇f) are untangled.
 *
 * Halving. Each live triangle the pass made is measured at its centroid and
 * edge midpoints: |f| / |∇f| first (one evaluation), then, where that is not well within E,
 * Newton's projection along ∇f (the distance to the point it reaches bounds the distance to
 * f = 0 from above). Beside a double curve Newton from a point by one sheet reaches that
 * sheet, the one the triangle lies on. A triangle over E has its longest edge of two
 * triangles (an edge of more is a double curve's) halved at its midpoint moved onto f = 0,
 * both triangles on it replaced by halves; a round measures only the last round's halves.
 * The halving stops where the halves would be shorter than the finest cell of depth.max (the
 * octree's own limit), where the midpoint finds no foot within half the edge, or where a
 * half would face against ∇f (across a fold tighter than the edge, beside a pinch point):
 * such triangles are counted (refill_over_error) and the analysis says met: false. Steiner,
 * Whitney and the cross-cap at E = 2e-3 × the box's width then lie within E in the own,
 * +1e-3 and 0.37-cell boxes (closed form; 1.47 E before), at 1e-3 × width within 1.11 E.
 *
 * Untangling. A ring vertex is placed from its rim vertex alone (conform_zip.c,
 * conform_pinch.c): beside a pinch point the move along the curve's tangent that puts it on
 * f = 0 grows with the rim vertex's distance from the curve (the umbrella's higher-order
 * terms), so two rim vertices a hundredth of a cell apart along the curve but at different
 * distances from it swap their rings' order and a whole strip of ladder quads turns over
 * (cross-cap, depth 7, +1e-3 box: 14 edges on two columns 13–20 cells from its pinch point
 * at (0, 0, 1)); where the rim crosses the fold its own vertices zigzag a hundredth of a cell
 * apart (0.37-cell box). A turned triangle's vertices that may move (not on the locus, not
 * pinned on a pinch point's fold, not on a boundary) go to the mean of their neighbours,
 * moved back onto f = 0 along ∇f (by at most half their mean distance: never onto another
 * sheet) — kept where no more triangles round them face against
 * ∇f than before (a strip straightens over a few rounds, each vertex alone rarely undoes a
 * fold). The polygoniser's own turned triangles beside a pinch point are untangled the same
 * way (those turned when the surgeries end and those round each vertex moved): it pleats the
 * thin lens an umbrella's two sheets make there, beyond the tube (Steiner, depth 7, irrational
 * box: 12 edges on the lattice plane z = 0.4901 at the lens's tip, 8–9 cells from (0, 0, 1/2),
 * 17 such of its 30 turned edges; 22 left, the cross-cap's 6 → 0; the rings on the fold
 * (conform_pinch.c) took the 9 the pass made: 13 left, all the polygoniser's; test
 * tube_folds/pinch_points_few_turned_over).
 *
 *     rim    a0 ──── a1            a1's ring vertex r1 fell behind r0: the quad (a0 a1 r1 r0)
 *             │   ╳   │            crosses itself; r1 to the mean of a1, r0, r2 and its inner
 *     ring   r1 ──── r0            neighbour puts it back between them
 */
#include "core/octree/edge_keys.h"
#include "core/singular/conform_internal.h"
#include "core/util/grow.h"
#include "core/util/vec3.h"

#include <assert.h>
#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

/* Rounds of untangling: each moves every vertex of the turned triangles once (measured on
 * the cross-cap and Steiner at depths 6 and 7 in three boxes: 16 rounds left the same folds
 * as 6). */
#define UNTANGLE_ROUNDS 6
/* The polygoniser's turned triangles are untangled within this many finest cells of a pinch
 * point: beside it the umbrella's two sheets make a lens thinner than a cell (Steiner's at
 * 1/2 − z below (0, 0, 1/2) reaches s = √(z(1 − 2z)) across), where its cells hold both sheets
 * and pleat; at depth 7 in the irrational box its turned triangles there lie 8–13 cells from
 * a pinch point, outside the tube. Elsewhere its turned triangles are left: untangling every
 * one took crossing-spheres' conformance (no pinch point) 224.5M → 275.7M instructions and the
 * cross-cap's 92.6M → 102.1M (callgrind, d7). */
#define PINCH_FOLD_CELLS 16.0
/* Vertices with more triangles than this are not moved (the refill's have 6, the
 * polygoniser's a dozen at most; the fan's neighbours are listed on the stack). */
#define MOVE_FAN_MAX 32
/* A moved vertex must end this near f = 0 (× the finest cell, by |f| / |∇f|), or as near as
 * it was: cf_project's Newton reaches 1e-8 cell in three steps from a fraction of a cell. */
#define RELAX_ON_SURFACE 1e-6
/* ... and leave no centroid round it farther from f = 0 than it was or than this many finest
 * cells (under max_error, than E if less): beside a pinch point the fold is tighter than a
 * cell and the neighbours' mean can pull a triangle across it. The polygoniser's own
 * centroids reach 0.15–0.25 cell at depth 5 (Steiner, conform/steiner_roman_pinch_and_triple
 * _points: near the locus at most twice the rest); 0.35: Steiner d7 turned-over edges 0 / 18
 * / 20 against 0 / 22 / 23 at 0.1, the depth-5 centroids 0.0154 (0.0259 unbounded). */
#define RELAX_CENTROID_CELLS 0.35
/* Rounds of splitting: each halves the longest edge of every triangle over E (a triangle
 * 2^(k/2) times too long needs about k rounds; the refill's triangles are about as long as
 * the polygoniser's beside them, which met E). */
#define SPLIT_ROUNDS 8
/* Without max_error the refill is held to what the polygoniser's cells round it met: the
 * flatness test's absolute tolerance at depth.max (ISM_FLAT_ABS_FRACTION of the finest cell,
 * polygonise.c), an E of this many finest cells. The refill's rows are as far apart as the
 * rim's vertices, and its rim edges are the polygoniser's longest there (1.5 cells beside a
 * cone's apex, where the surface bends fastest): unmeasured, Kummer's 16 nodes at depth 6 in
 * the irrational box had refill centroids 0.35 cell off f = 0 against 0.16 elsewhere, Steiner's
 * pinch points at depth 5 0.71 cell against 0.29 (conform/kummer_sixteen_nodes,
 * steiner_roman_pinch_and_triple_points). */
#define UNBOUNDED_ERROR_CELLS 0.25
/* ... and halved down to halves of this many finest cells (edges of a cell or more are
 * halved): without a bound the finest cell is the mesh's own scale, and the polygoniser's
 * triangles there, cut by the cells' faces, are no larger than a cell and often half. */
#define UNBOUNDED_MIN_EDGE_CELLS 0.5
/* Newton steps of the distance measure (from within a fraction of a cell of f = 0 a few
 * give the foot to rounding). */
#define MEASURE_STEPS 6
/* The first-order estimate |f| / |∇f| is at least half the distance next to a double curve
 * (f ≈ l1 l2: the estimate is d1 d2 / |d2 n1 + d1 n2| ≥ min(d1, d2) / 2) and about the
 * distance elsewhere; points it puts under this share of E are within E without Newton. */
#define ESTIMATE_SHARE 0.5

static void tri_normal(const ism_mesh *m, uint32_t t, double n[3])
{
    const uint32_t *v = m->tri + 3 * (size_t)t;
    ism_tri_cross3(m->pos + 3 * (size_t)v[0], m->pos + 3 * (size_t)v[1],
                   m->pos + 3 * (size_t)v[2], n);
}

/* The centroid gradients the halving measured, for the turned tests after it: split_over
 * evaluates f and ∇f at each refill triangle's centroid (its first measure), and turned()
 * asks the same point again (crossing-spheres: 15.8k gradients, 7.5M instructions,
 * callgrind). An entry holds while none of the triangle's vertices has moved (the untangling
 * clears a vertex's triangles' entries before it moves it; it adds no triangles): the same
 * point, the same bits. */
typedef struct centroids {
    size_t nt0;             /* entry t − nt0 for triangle t */
    double (*g)[4];         /* ∇f and f */
    uint8_t *has;
    size_t cap_g, cap_has;
} centroids;

/* Room for the triangles below nt (a round of the halving measures no other). */
static void centroids_room(centroids *cm, size_t nt)
{
    if (nt > cm->nt0 && cf_grow((void **)&cm->g, &cm->cap_g, nt - cm->nt0, sizeof *cm->g))
        cf_grow((void **)&cm->has, &cm->cap_has, cm->cap_g, 1);
}

static void centroids_keep(centroids *cm, uint32_t t, const double g[3], double fv)
{
    size_t i = t - cm->nt0;
    if (i >= cm->cap_g || i >= cm->cap_has)
        return; /* no room (out of memory): evaluated again when asked */
    cm->g[i][0] = g[0];
    cm->g[i][1] = g[1];
    cm->g[i][2] = g[2];
    cm->g[i][3] = fv;
    cm->has[i] = 1;
}

/* The kept ∇f and f at triangle t's centroid, or NULL. */
static const double *centroids_find(const centroids *cm, uint32_t t)
{
    if (!cm || t < cm->nt0 || t - cm->nt0 >= cm->cap_has || !cm->has[t - cm->nt0])
        return NULL;
    return cm->g[t - cm->nt0];
}

static void centroids_free(centroids *cm)
{
    free(cm->g);
    free(cm->has);
}

/* Triangle t faces against ∇f: at its centroid, or at two of its corners (their normals, ∇f's
 * direction where they were made; 0 at the locus). A triangle across a tight fold (beside a
 * pinch point, where ∇f turns by half a turn within a cell) can face along ∇f at its centroid
 * and against it at both ends of its edge on the fold. off (when not NULL): the centroid's
 * |f| / |∇f| (INFINITY where ∇f vanishes), from the same evaluation (cm's when it holds
 * it). */
static bool turned(cf_ctx *c, uint32_t t, double *off, const centroids *cm)
{
    const uint32_t *v = c->m->tri + 3 * (size_t)t;
    double p[3], n[3], g[3], fv;
    tri_normal(c->m, t, n);
    int against = 0;
    for (int k = 0; k < 3; k++) {
        const float *vn = c->m->normal + 3 * (size_t)v[k];
        against += n[0] * vn[0] + n[1] * vn[1] + n[2] * vn[2] < 0;
    }
    if (against >= 2 && !off)
        return true;
    const double *kept = centroids_find(cm, t);
    if (kept) {
        for (int k = 0; k < 3; k++)
            g[k] = kept[k];
        fv = kept[3];
        if (off) { /* cf_distance_estimate's */
            double gl = sqrt(g[0] * g[0] + g[1] * g[1] + g[2] * g[2]);
            *off = gl > 0 ? fabs(fv) / gl : INFINITY;
        }
        return against >= 2 || ism_dot3(n, g) < 0;
    }
    for (int k = 0; k < 3; k++)
        p[k] = (c->m->pos[3 * (size_t)v[0] + k] + c->m->pos[3 * (size_t)v[1] + k] +
                c->m->pos[3 * (size_t)v[2] + k]) / 3;
    if (off)
        *off = cf_distance_estimate(c, p, g, &fv);
    else
        ism_eval_gradient(c->f, c->ws, p[0], p[1], p[2], g);
    return against >= 2 || ism_dot3(n, g) < 0;
}

/* Turned triangles round vertex v; *worst: the farthest of their centroids from f = 0. */
static size_t turned_round(cf_ctx *c, uint32_t v, double *worst, const centroids *cm)
{
    cf_inc it;
    uint32_t t;
    size_t n = 0;
    *worst = 0;
    cf_inc_begin(c, v, &it);
    while (cf_inc_next(c, &it, &t)) {
        double o;
        n += turned(c, t, &o, cm);
        *worst = fmax(*worst, o);
    }
    return n;
}

/* Moves vertex v to the mean of its neighbours projected onto f = 0, kept when no more
 * triangles round it face against ∇f (and some did before) and no centroid round it ends
 * farther from f = 0 than it was or than reach. True when it moved. */
static bool relax(cf_ctx *c, uint32_t v, double reach, centroids *cm)
{
    double *p = c->m->pos + 3 * (size_t)v, mean[3] = {0, 0, 0}, old[3] = {p[0], p[1], p[2]};
    double spread = 0;
    size_t n = 0;
    cf_inc it;
    uint32_t t;
    cf_inc_begin(c, v, &it);
    while (cf_inc_next(c, &it, &t))
        for (int k = 0; k < 3; k++) {
            uint32_t w = c->m->tri[3 * (size_t)t + k];
            if (w == v)
                continue;
            const double *q = c->m->pos + 3 * (size_t)w;
            for (int j = 0; j < 3; j++)
                mean[j] += q[j];
            spread += ism_dist3(q, old);
            n++;
        }
    if (n == 0)
        return false;
    for (int j = 0; j < 3; j++)
        mean[j] /= (double)n;
    double worst0, worst1 = INFINITY;
    size_t before = turned_round(c, v, &worst0, cm);
    double g[3], fv, off0 = cf_distance_estimate(c, old, g, &fv);
    cf_inc_begin(c, v, &it); /* its triangles' kept centroids no longer hold */
    while (cf_inc_next(c, &it, &t))
        if (t >= cm->nt0 && t - cm->nt0 < cm->cap_has)
            cm->has[t - cm->nt0] = 0;
    for (int j = 0; j < 3; j++)
        p[j] = mean[j];
    /* back onto f = 0, by at most half the neighbours' mean distance: never onto another
     * sheet; a move Newton cannot bring as near f = 0 as the vertex was is refused (beside a
     * fold the mean can lie where no foot is near) */
    double off = cf_project(c, p, 0.5 * spread / (double)n);
    size_t after = off <= fmax(off0, RELAX_ON_SURFACE * c->cell)
                       ? turned_round(c, v, &worst1, cm)
                       : SIZE_MAX;
    bool fewer = after < before || (after == before && before > 0);
    if (fewer && worst1 <= fmax(worst0, reach)) {
        cf_set_normal(c, v);
        return true;
    }
    for (int j = 0; j < 3; j++)
        p[j] = old[j];
    return false;
}

/* Not on the locus nor pinned (cf_pin_vertex), and inside the mesh: its triangles close a
 * fan round it (as many as its neighbours; one more neighbour on a boundary — a box face —
 * where it must stay). */
static bool movable(cf_ctx *c, uint32_t v)
{
    if (c->singular[v])
        return false;
    uint32_t nb[2 * MOVE_FAN_MAX], t;
    size_t ntri = 0, nnb = 0;
    cf_inc it;
    cf_inc_begin(c, v, &it);
    while (cf_inc_next(c, &it, &t)) {
        if (++ntri > MOVE_FAN_MAX)
            return false;
        for (int k = 0; k < 3; k++) {
            uint32_t w = c->m->tri[3 * (size_t)t + k];
            size_t j = 0;
            while (j < nnb && nb[j] != w)
                j++;
            if (w != v && j == nnb)
                nb[nnb++] = w;
        }
    }
    return ntri > 0 && nnb == ntri;
}

/* The polygoniser's live triangles (before nt0) within PINCH_FOLD_CELLS of one of the pinch
 * points of l turned over, into polys: the ones of its triangles the untangling
 * looks at again, with those round each vertex it moves (a move is kept where no more
 * triangles round it turn: a fold may pass to a neighbour). False when out of memory. */
static bool list_polygoniser_turned(cf_ctx *c, size_t nt0, const ism_locus *l, cf_tris *polys)
{
    double r = PINCH_FOLD_CELLS * c->cell;
    cf_tris cand = {0};
    bool ok = true;
    polys->n = 0;
    cf_tgrid_begin(&c->grid);
    for (size_t i = 0; ok && i < l->npoints; i++) {
        if (l->points[i].type != ISM_SING_PINCH)
            continue;
        double lo[3], hi[3];
        cf_query_box(l->points[i].p, l->points[i].p, r, lo, hi);
        ok = cf_tgrid_gather(&c->grid, c->m, lo, hi, c->dead, &cand);
    }
    for (size_t i = 0; ok && i < cand.n && !cf_poll(c, 1); i++) {
        uint32_t t = cand.t[i];
        if (t >= nt0)
            continue;
        const uint32_t *v = c->m->tri + 3 * (size_t)t;
        bool near = false;
        for (size_t j = 0; j < l->npoints && !near; j++)
            near = l->points[j].type == ISM_SING_PINCH &&
                   cf_point_triangle_d2(l->points[j].p, c->m->pos + 3 * (size_t)v[0],
                                        c->m->pos + 3 * (size_t)v[1],
                                        c->m->pos + 3 * (size_t)v[2]) < r * r;
        if (near && turned(c, t, NULL, NULL))
            ok = cf_tris_push(polys, t);
    }
    free(cand.t);
    return ok;
}

/* The movable vertices of the turned live triangles among polys and from nt0 on, each once
 * (memo stamp). */
static bool collect_turned(cf_ctx *c, size_t nt0, const cf_tris *polys, cf_tris *out,
                           size_t *nturned, const centroids *cm)
{
    out->n = 0;
    *nturned = 0;
    if (!cf_memo_reset(c))
        return false;
    for (size_t i = 0; i < polys->n + c->m->ntris - nt0 && !cf_poll(c, 1); i++) {
        size_t t = i < polys->n ? polys->t[i] : nt0 + (i - polys->n);
        if (c->dead[t] || !turned(c, (uint32_t)t, NULL, cm))
            continue;
        ++*nturned;
        for (int k = 0; k < 3; k++) {
            uint32_t v = c->m->tri[3 * t + k];
            if (c->memo_gen[v] == c->gen)
                continue;
            c->memo_gen[v] = c->gen;
            if (!movable(c, v))
                continue;
            if (!cf_tris_push(out, v))
                return false;
        }
    }
    return true;
}

static bool untangle(cf_ctx *c, size_t nt0, const ism_locus *l, double reach, centroids *cm)
{
    cf_tris vs = {0}, polys = {0};
    bool ok = list_polygoniser_turned(c, nt0, l, &polys);
    for (int round = 0; ok && round < UNTANGLE_ROUNDS && !c->stopped; round++) {
        size_t nturned;
        ok = collect_turned(c, nt0, &polys, &vs, &nturned, cm);
        if (round == 0)
            c->st->refill_turned = nturned;
        if (!ok || vs.n == 0)
            break;
        size_t moved = 0;
        for (size_t i = 0; ok && i < vs.n; i++) {
            if (!relax(c, vs.t[i], reach, cm))
                continue;
            moved++;
            cf_inc it;
            uint32_t t;
            cf_inc_begin(c, vs.t[i], &it);
            while (ok && cf_inc_next(c, &it, &t))
                ok = t >= nt0 || cf_tris_push(&polys, t);
        }
        c->st->refill_untangled += moved;
        if (moved == 0)
            break;
    }
    free(vs.t);
    free(polys.t);
    return ok;
}

/* An upper bound of p's distance to f = 0 when it may exceed E (Newton's foot), else the
 * first-order estimate; fv and g0: f and ∇f at p (ism_eval_gradient's bits). cm (when not
 * NULL): p is triangle t's centroid, its ∇f and f kept there. */
static double measure_from(cf_ctx *c, const double p[3], double E, centroids *cm, uint32_t t,
                           double fv, const double g0[3])
{
    double g[3] = {g0[0], g0[1], g0[2]}, x[3] = {p[0], p[1], p[2]}, gg = ism_dot3(g, g);
    if (cm) /* p is triangle t's centroid */
        centroids_keep(cm, t, g, fv);
    if (fv == 0)
        return 0;
    if (gg > 0 && fabs(fv) / sqrt(gg) < ESTIMATE_SHARE * E)
        return fabs(fv) / sqrt(gg);
    for (int it = 0; it < MEASURE_STEPS && fv != 0; it++) {
        if (!(gg > 0) || !isfinite(fv))
            return INFINITY;
        for (int k = 0; k < 3; k++)
            x[k] -= fv * g[k] / gg;
        fv = ism_eval_gradient(c->f, c->ws, x[0], x[1], x[2], g);
        gg = ism_dot3(g, g);
    }
    /* not converged: the residual's first-order step added (an estimate, not a bound) */
    double rest = fv == 0 ? 0 : gg > 0 ? fabs(fv) / sqrt(gg) : INFINITY;
    return ism_dist3(x, p) + rest;
}

/* measure_from with p's first evaluation taken here. */
static double measure(cf_ctx *c, const double p[3], double E, centroids *cm, uint32_t t)
{
    double g[3], fv = ism_eval_gradient(c->f, c->ws, p[0], p[1], p[2], g);
    return measure_from(c, p, E, cm, t, fv, g);
}

/* The edge of triangle t to split: its longest edge of two triangles whose length is at
 * least 2 min_edge (k: the edge from corner k to k + 1), or -1. */
static int edge_to_split(const cf_ctx *c, uint32_t t, double min_edge)
{
    const uint32_t *v = c->m->tri + 3 * (size_t)t;
    int best = -1;
    double bl = 2 * min_edge;
    for (int k = 0; k < 3; k++) {
        uint32_t a = v[k], b = v[(k + 1) % 3], tt[3];
        double len = ism_dist3(c->m->pos + 3 * (size_t)a, c->m->pos + 3 * (size_t)b);
        if (len >= bl && cf_live_on_edge(c, a, b, tt, 3) == 2) {
            bl = len;
            best = k;
        }
    }
    return best;
}

/* The two triangles that would replace triangle t when its edge (a, b) is halved at m: their
 * corners in t's winding (false when t does not hold the edge that way round). */
static bool halves(const cf_ctx *c, uint32_t t, uint32_t a, uint32_t b, uint32_t m,
                   uint32_t out[2][3])
{
    const uint32_t *v = c->m->tri + 3 * (size_t)t;
    for (int k = 0; k < 3; k++) {
        uint32_t s = v[k], e = v[(k + 1) % 3], o = v[(k + 2) % 3];
        if ((s == a && e == b) || (s == b && e == a)) {
            out[0][0] = s, out[0][1] = m, out[0][2] = o;
            out[1][0] = m, out[1][1] = e, out[1][2] = o;
            return true;
        }
    }
    return false;
}

/* Splits edge (a, b) (two live triangles) at its midpoint moved onto f = 0 along ∇f, unless the
 * midpoint finds no foot within half the edge or a half would face against ∇f where its
 * triangle did not (across a fold tighter than the edge: the split would turn it over). True
 * when split (*ok false only when out of memory). */
static bool split_edge(cf_ctx *c, uint32_t a, uint32_t b, cf_tris *removed, bool *ok,
                       const centroids *cm)
{
    uint32_t tt[3];
    *ok = true;
    if (cf_live_on_edge(c, a, b, tt, 3) != 2)
        return false; /* an earlier split this round changed it */
    const double *pa = c->m->pos + 3 * (size_t)a, *pb = c->m->pos + 3 * (size_t)b;
    double mid[3] = {(pa[0] + pb[0]) / 2, (pa[1] + pb[1]) / 2, (pa[2] + pb[2]) / 2};
    double len = ism_dist3(pa, pb);
    cf_grad kept;
    if (!(cf_project_keep(c, mid, 0.5 * len, &kept) <= RELAX_ON_SURFACE * c->cell))
        return false;
    size_t nt = c->m->ntris, nv = c->m->nverts;
    uint32_t m = cf_add_vertex_kept(c, mid, false, &kept), h[2][2][3];
    if (m == CF_NONE || !halves(c, tt[0], a, b, m, h[0]) || !halves(c, tt[1], a, b, m, h[1])) {
        *ok = m != CF_NONE;
        if (m != CF_NONE)
            cf_truncate(c, nt, nv);
        return false;
    }
    bool was[2] = {turned(c, tt[0], NULL, cm), turned(c, tt[1], NULL, cm)};
    for (int i = 0; i < 2; i++)
        for (int j = 0; j < 2; j++)
            *ok = *ok && cf_add_triangle(c, h[i][j][0], h[i][j][1], h[i][j][2]);
    bool worse = false;
    for (size_t t = nt; *ok && t < c->m->ntris; t++)
        worse |= turned(c, (uint32_t)t, NULL, cm) && !was[(t - nt) / 2];
    if (!*ok || worse || c->m->ntris != nt + 4) {
        cf_truncate(c, nt, nv);
        return false;
    }
    c->dead[tt[0]] = c->dead[tt[1]] = 1;
    *ok = cf_tris_push(removed, tt[0]) && cf_tris_push(removed, tt[1]);
    c->st->vertices_added++;
    c->st->refill_splits++;
    return true;
}

/* The midpoints measured in one round of split_over, by edge: the two triangles on an edge
 * measure the same point ((a + b) / 2 is (b + a) / 2 to the bit), and no vertex moves while a
 * round measures, so the second asks the memo (crossing-spheres: 63k gradient evaluations in
 * the refill, most of them midpoints met twice). */
typedef struct edge_memo {
    cf_edge_table tab; /* the round's edges → their entries' index */
    double *d;         /* by index */
    double (*pre)[4];  /* by index: f and ∇f at the midpoint, taken ahead (prefetch) */
    uint8_t *state;    /* by index: MID_*, set when the index is added */
    size_t cap_d, cap_pre, cap_state;
} edge_memo;

/* An edge's midpoint in a round: its first evaluation taken ahead, or measured (d). An index
 * is read only in the round that added it (the table starts again each round), and its state
 * is set when it is added. */
enum { MID_PREFETCHED = 1, MID_MEASURED = 2 };

/* Slots of the smallest table (a power of two: 2^6). */
#define EDGE_SLOTS_MIN 64

/* Room for at most ISM_KEY_NONE edges, so no number (0 .. ISM_KEY_NONE − 1) reads as an empty
 * slot (a round's 3 ntri edges pass it only beyond 1.4e9 triangles). Slots at least twice the
 * room: half of them stay empty however full the table, and cf_edge_table_add's probe, which
 * stops only at an empty slot (the room is checked after it), relies on slots > max to end. */
bool cf_edge_table_start(cf_edge_table *t, size_t max)
{
    if (max > ISM_KEY_NONE)
        max = ISM_KEY_NONE;
    size_t slots = EDGE_SLOTS_MIN;
    int shift = 64 - 6;
    for (; slots < 2 * max; slots *= 2)
        shift--;
    assert(slots > max);
    t->n = t->max = 0;
    if (!ism_grow((void **)&t->slot, &t->cap_slot, slots, sizeof *t->slot, slots))
        return false;
    for (size_t i = 0; i < slots; i++)
        t->slot[i].index = ISM_KEY_NONE;
    t->shift = shift;
    t->max = max;
    return true;
}

void cf_edge_table_free(cf_edge_table *t)
{
    free(t->slot);
    t->slot = NULL;
    t->n = t->max = t->cap_slot = 0;
}

/* The memo emptied for a round over ntri triangles, with room for their 3 ntri edges: the
 * entries are sized once per round, the table twice that (a round's edges are known ahead,
 * so nothing grows or rehashes while it runs; the general hash map, key_map.c, grown from
 * its first size each round, cost the Klein bottle at E 0.00327 17M instructions). Not
 * zeroed (ism_grow): every entry is written when its index is added, before it is read.
 * Out of memory: room for none (every edge measured as it comes, *ok false: edge_measure). */
static void edge_memo_start(edge_memo *m, size_t ntri)
{
    size_t max = 3 * ntri;
    if (!cf_edge_table_start(&m->tab, max) ||
        !ism_grow((void **)&m->d, &m->cap_d, max, sizeof *m->d, max) ||
        !ism_grow((void **)&m->pre, &m->cap_pre, max, sizeof *m->pre, max) ||
        !ism_grow((void **)&m->state, &m->cap_state, max, sizeof *m->state, max))
        m->tab.max = 0;
}

static void edge_memo_free(edge_memo *m)
{
    cf_edge_table_free(&m->tab);
    free(m->d);
    free(m->pre);
    free(m->state);
}

/* edge_measure of the midpoint q of an edge the memo holds at index i (added by prefetch or
 * by edge_measure). */
static double known_measure(cf_ctx *c, edge_memo *m, uint32_t i, const double q[3], double E)
{
    if (m->state[i] == MID_MEASURED)
        return m->d[i];
    m->state[i] = MID_MEASURED;
    return m->d[i] = measure_from(c, q, E, NULL, 0, m->pre[i][0], m->pre[i] + 1);
}

/* measure() of the midpoint q of the edge (a, b), once per round; *ok false when out of
 * memory (then the value is measured but not kept). */
static double edge_measure(cf_ctx *c, edge_memo *m, uint32_t a, uint32_t b, const double q[3],
                           double E, bool *ok)
{
    bool added;
    uint32_t i = cf_edge_table_add(&m->tab, a, b, &added);
    if (i == ISM_KEY_NONE) {
        *ok = false;
        return measure(c, q, E, NULL, 0);
    }
    if (!added)
        return known_measure(c, m, i, q, E);
    m->state[i] = MID_MEASURED;
    return m->d[i] = measure(c, q, E, NULL, 0);
}

/* Triangles whose points (centroid, new edge midpoints) split_over evaluates ahead in one
 * gradient batch: up to 4 points each, ISM_GRAD_BATCH lanes a pass. 16 measured fewest:
 * cf_refine_refill on the Klein bottle at E 0.00327 took 68.8M instructions with 8, 66.1M
 * with 16, 66.5M with 32 (callgrind --toggle-collect=cf_refine_refill, isomesh --threads 1;
 * the same mesh: the batch gives each lane ism_eval_gradient's bits). */
#define PREFETCH_TRIS 16

/* What prefetch took ahead for triangles [a, a + n) of a round (has: live): f and ∇f at
 * their centroids, and the edge memo's indices of their edges' midpoints. */
typedef struct tris_pre {
    size_t a, n;
    bool has[PREFETCH_TRIS];
    double fg[PREFETCH_TRIS][4];
    uint32_t edge[PREFETCH_TRIS][3]; /* the edges' memo indices (ISM_KEY_NONE: not added) */
} tris_pre;

/* The corners' points of a live triangle t, its centroid q[0] and edge midpoints q[1 + j]
 * (edge v[j] → v[j + 1]), as split_over measures them. */
static void tri_points(const cf_ctx *c, size_t t, double q[4][3])
{
    const uint32_t *v = c->m->tri + 3 * t;
    const double *p[3] = {c->m->pos + 3 * (size_t)v[0], c->m->pos + 3 * (size_t)v[1],
                          c->m->pos + 3 * (size_t)v[2]};
    for (int k = 0; k < 3; k++) {
        q[0][k] = (p[0][k] + p[1][k] + p[2][k]) / 3;
        for (int j = 0; j < 3; j++)
            q[1 + j][k] = (p[j][k] + p[(j + 1) % 3][k]) / 2;
    }
}

/* The first evaluation of every point split_over's round measures on the live triangles
 * [a, b) (b − a <= PREFETCH_TRIS), in one ism_eval_gradient_batch: lane by lane
 * ism_eval_gradient's bits, so each measure answers as it did one by one. A centroid's goes to
 * cp, a midpoint's to the edge memo, once per edge and round (an edge known already, or one
 * the memo has no room for, is left: edge_measure evaluates it as before). A triangle found
 * over E at its centroid leaves its midpoints unasked: their lanes are wasted, nothing more
 * (Klein bottle at E 0.00327: 82,200 measures, none beyond its first evaluation). */
static void prefetch(cf_ctx *c, edge_memo *m, size_t a, size_t b, tris_pre *cp)
{
    double x[4 * PREFETCH_TRIS], y[4 * PREFETCH_TRIS], z[4 * PREFETCH_TRIS];
    double f[4 * PREFETCH_TRIS], g[4 * PREFETCH_TRIS][3];
    uint32_t edge[4 * PREFETCH_TRIS]; /* per lane: the memo index, or CF_NONE (a centroid) */
    size_t n = 0;
    cp->a = a;
    cp->n = b - a;
    for (size_t t = a; t < b; t++) {
        cp->has[t - a] = !c->dead[t];
        if (c->dead[t])
            continue;
        const uint32_t *v = c->m->tri + 3 * t;
        double q[4][3];
        tri_points(c, t, q);
        for (int j = 0; j < 4; j++) {
            if (j) {
                bool added;
                uint32_t i = cf_edge_table_add(&m->tab, v[j - 1], v[j % 3], &added);
                cp->edge[t - a][j - 1] = i;
                if (i == ISM_KEY_NONE || !added)
                    continue;
                m->state[i] = MID_PREFETCHED;
                edge[n] = i;
            } else {
                edge[n] = CF_NONE;
            }
            x[n] = q[j][0];
            y[n] = q[j][1];
            z[n] = q[j][2];
            n++;
        }
    }
    ism_eval_gradient_batch(c->f, c->ws, x, y, z, f, g, n);
    size_t lane = 0;
    for (size_t t = a; t < b; t++) {
        if (!cp->has[t - a])
            continue;
        double *fg = cp->fg[t - a];
        fg[0] = f[lane];
        fg[1] = g[lane][0], fg[2] = g[lane][1], fg[3] = g[lane][2];
        for (lane++; lane < n && edge[lane] != CF_NONE; lane++) {
            double *e = m->pre[edge[lane]];
            e[0] = f[lane];
            e[1] = g[lane][0], e[2] = g[lane][1], e[3] = g[lane][2];
        }
    }
}

static bool split_over(cf_ctx *c, size_t nt0, double E, double min_edge, cf_tris *removed,
                       centroids *cm)
{
    cf_tris edges = {0}, overs = {0}; /* edges as pairs a, b; the triangles over E */
    edge_memo memo = {0};
    bool ok = true;
    size_t lo = nt0, stuck = 0; /* triangles from lo on not measured yet; over E, unsplit */
    for (int round = 0; ok && round < SPLIT_ROUNDS && !c->stopped; round++) {
        edges.n = overs.n = 0;
        size_t split = 0, hi = c->m->ntris;
        edge_memo_start(&memo, hi - lo);
        centroids_room(cm, hi);
        /* a triangle measured within E stays so (a split only replaces the two triangles
         * on its edge, by halves appended): each round measures the halves of the last */
        tris_pre cp = {.a = lo, .n = 0};
        for (size_t t = lo; ok && t < hi && !cf_poll(c, 4); t++) {
            if (t == cp.a + cp.n) /* the next triangles' points, ahead */
                prefetch(c, &memo, t, hi - t < PREFETCH_TRIS ? hi : t + PREFETCH_TRIS, &cp);
            if (c->dead[t])
                continue;
            const uint32_t *v = c->m->tri + 3 * t;
            double q[4][3];
            tri_points(c, t, q);
            const double *fg = cp.fg[t - cp.a];
            bool far = measure_from(c, q[0], E, cm, (uint32_t)t, fg[0], fg + 1) > E;
            for (int j = 1; j < 4 && !far && ok; j++) {
                uint32_t i = cp.edge[t - cp.a][j - 1];
                far = (i == ISM_KEY_NONE ? edge_measure(c, &memo, v[j - 1], v[j % 3], q[j], E, &ok)
                                         : known_measure(c, &memo, i, q[j], E)) > E;
            }
            if (!far)
                continue;
            int k = edge_to_split(c, (uint32_t)t, min_edge);
            ok = cf_tris_push(&overs, (uint32_t)t) &&
                 (k < 0 || (cf_tris_push(&edges, v[k]) && cf_tris_push(&edges, v[(k + 1) % 3])));
        }
        for (size_t i = 0; ok && i + 1 < edges.n; i += 2)
            split += split_edge(c, edges.t[i], edges.t[i + 1], removed, &ok, cm);
        /* over this round and not halved (one halved by a neighbour's split is measured
         * again as halves) */
        for (size_t i = 0; i < overs.n; i++)
            stuck += !c->dead[overs.t[i]];
        lo = hi;
        if (split == 0)
            break;
    }
    /* the last round's halves not measured when the rounds ran out: not counted */
    c->st->refill_over_error = stuck;
    free(edges.t);
    free(overs.t);
    edge_memo_free(&memo);
    return ok;
}

bool cf_refine_refill(cf_ctx *c, size_t nt0, double max_error, double min_edge,
                      const ism_locus *l)
{
    if (c->m->ntris == nt0 || !c->indexed)
        return true;
    double reach = RELAX_CENTROID_CELLS * c->cell;
    if (max_error > 0)
        reach = fmin(reach, max_error);
    size_t w0 = c->st->work, nt1 = c->m->ntris;
    cf_tris removed = {0};
    bool bounded = max_error > 0;
    centroids cm = {.nt0 = nt0};
    bool ok = split_over(c, nt0, bounded ? max_error : UNBOUNDED_ERROR_CELLS * c->cell,
                         bounded ? min_edge : UNBOUNDED_MIN_EDGE_CELLS * c->cell, &removed, &cm);
    /* a polygoniser's triangle halved counts as removed by the pass, a refill triangle halved
     * as never added; the halves as added */
    size_t refill_halved = 0;
    for (size_t i = 0; i < removed.n; i++) {
        c->st->triangles_removed += removed.t[i] < nt0;
        refill_halved += removed.t[i] >= nt0;
    }
    c->st->triangles_added += c->m->ntris - nt1 - refill_halved;
    free(removed.t);
    ok = ok && untangle(c, nt0, l, reach, &cm);
    centroids_free(&cm);
    c->st->refill_work = c->st->work - w0;
    return ok;
}
