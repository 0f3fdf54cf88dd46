/* rm_brec.c — per-triangle bounds on the distance of the centroid and edge midpoints, and
 * per-vertex offsets, kept between steps of the quality pass under an error bound
 * (rm_brec.h). */
#include "core/remesh/rm_brec.h"
#include "core/remesh/rm_bound.h"
#include "core/remesh/rm_cbound.h"
#include "core/eval/interval_jet.h"
#include "core/util/vec3.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

/* A point's record: its place, the bound u on its distance, the unit normal n of f's level
 * set taken for it (∇f's direction where it was measured; 0: none) and how far n may have
 * turned since (radians: 0 where measured). */
#define SLOT 8
#define SLOT_U 3
#define SLOT_N 4
#define SLOT_TURN 7

/* What the fan's check found, per triangle of the fan in slot order: the new centroid's
 * record, then the new midpoint's of the edge from v to the next corner. */
#define KEEP_REC (2 * SLOT)

/* Points per triangle: the centroid (slot 0), then the midpoint of the edge from corner j to
 * corner j + 1 (slot 1 + j). */
#define RM_BREC_POINTS 4
#define RM_BREC_REC (SLOT * RM_BREC_POINTS)

/* Slot s of triangle t. */
static inline double *slot_of(const rm_pass *p, uint32_t t, int s)
{
    return p->brec + RM_BREC_REC * (size_t)t + SLOT * s;
}

/* Whether record e carries a normal. */
static inline bool has_normal(const double *e)
{
    return e[SLOT_N] != 0 || e[SLOT_N + 1] != 0 || e[SLOT_N + 2] != 0;
}

/* The record e moved to y (into w, when not NULL): a bound on y's distance from f = 0 where
 * f's unit normal ∇f/|∇f| turns by at most kappa (radians per unit length) in a box holding
 * e's place, y and everything within max_error of the segment between them (fan_bend). The
 * distance to a set moves by at most as far as the point does (u + |δ|, δ = y − e's place,
 * always); where e has a normal n, turned by at most a since its point was measured, the
 * surface's nearest point q to e's lies within u along the normal there (e − q is normal to
 * the surface at q), which is within a + κu of n; the surface through q leaves its tangent
 * plane by at most a circle's sagitta of curvature κ over the tangential part of δ (its
 * normal turning by at most κ along it: a circle bends the most), r = |δ| at most, so y lies
 * within u + |n·δ| + (a + κu)|δ| + r κr / (1 + √(1 − κ²r²)) (κr ≤ 1: the circle's reach) of
 * it, the smaller of the two. A relaxation moves a fan's points along the surface (n·δ about
 * 0), where the first bound grows by all of |δ| and this one by its square. Whatever the
 * bent bound, only a point it puts within max_error / ISM_RM_CBOUND_RATIO is not measured
 * (bound_of): q and the surface's points used then lie within max_error of the segment. */
static double moved_bound(const double *e, const double y[3], double kappa, double *w,
                          double *plain)
{
    double dx[3] = {y[0] - e[0], y[1] - e[1], y[2] - e[2]};
    double len = ism_norm3(dx), u = e[SLOT_U] + len;
    *plain = u;
    double turn = e[SLOT_TURN] + kappa * len; /* n's turn at y */
    double along = fabs(ism_dot3(e + SLOT_N, dx)), reach = kappa * len;
    double sagitta = reach <= 1 ? len * reach / (1 + sqrt(1 - reach * reach)) : INFINITY;
    double bent = e[SLOT_U] + along + (e[SLOT_TURN] + kappa * e[SLOT_U]) * len + sagitta;
    bool use = has_normal(e) && bent < u; /* NaN (κ infinite, no move): not used */
    if (w) { /* kept at y: the bent bound while n may have turned by at most
                RM_BREC_TURN_MAX, else the one that holds whatever f's bend (no normal) */
        bool keep = use && turn <= RM_BREC_TURN_MAX;
        memcpy(w, y, 3 * sizeof *w);
        w[SLOT_U] = keep ? bent : u;
        for (int k = 0; k < 3; k++)
            w[SLOT_N + k] = keep ? e[SLOT_N + k] : 0;
        w[SLOT_TURN] = keep ? turn : 0;
    }
    return use ? bent : u;
}

/* Slot s of triangle t takes the record w. */
static void rm_brec_set(rm_pass *p, uint32_t t, int s, const double *w)
{
    memcpy(slot_of(p, t, s), w, SLOT * sizeof *w);
}

bool rm_brec_open(rm_pass *p)
{
    size_t n = p->r.cap_tris ? p->r.cap_tris : 1;
    p->brec = malloc(RM_BREC_REC * n * sizeof *p->brec);
    size_t nv = p->r.cap_verts ? p->r.cap_verts : 1;
    p->bend = malloc(RM_BREC_BEND_REC * nv * sizeof *p->bend);
    p->jws = ism_ivjet_ws_new(p->f);
    p->cen_keep_v = UINT32_MAX;
    if (!p->brec || !p->bend || !p->jws || !(p->offset || rm_offset_open(p)))
        return false;
    /* no point (NaN matches no place): measured when asked */
    for (size_t i = 0; i < RM_BREC_REC * n; i++)
        p->brec[i] = NAN;
    for (size_t i = 0; i < RM_BREC_BEND_REC * nv; i++) /* no box: NaN holds nothing */
        p->bend[i] = NAN;
    return true;
}

/* Room for what v's fan check finds (KEEP_REC per triangle, in cen_keep: a pass under a bound
 * has no rm_cbound records), kept for v at x; NULL when out of memory (nothing is kept then:
 * the records stay as they were). */
static double *keep_for(rm_pass *p, uint32_t v, const double x[3])
{
    uint32_t n = p->r.count[v];
    rm_brec_drop(p);
    if (n > p->cen_keep_cap) { /* room counted in triangles, as rm_cbound_fan's */
        double *k = realloc(p->cen_keep, 2 * KEEP_REC * (size_t)n * sizeof *k);
        if (!k)
            return NULL;
        p->cen_keep = k;
        p->cen_keep_cap = 2 * n;
    }
    p->cen_keep_v = v;
    memcpy(p->cen_keep_x, x, sizeof p->cen_keep_x);
    return p->cen_keep;
}

static double fan_bend(rm_pass *p, uint32_t v, const double x[3]);

/* The bound at y, which lies where slot s of triangle t's point was before the move (at
 * y0), with its record into w: that slot's moved to y (moved_bound, f's normal turning by at
 * most *kappa) when ISM_RM_CBOUND_RATIO times it is within max_error; else measured (with
 * ∇f's direction there, from the pass's memo: no evaluation more). *kappa is fan_bend's for
 * v moving to x, NAN until a record asks for it: one whose bent bound could spare its point
 * where the plain one cannot (with no turn at all, κ = 0, the bent bound is at its least).
 * Elsewhere the point is measured, or spared by the plain bound, whatever κ (the record then
 * keeps no normal): on gyroid-ball's default bound 35,000 fans asked -> 23,000. */
static double bound_of(rm_pass *p, uint32_t t, int s, const double y0[3], const double y[3],
                       uint32_t v, const double x[3], double *kappa, double *w)
{
    const double *e = slot_of(p, t, s);
    if (e[0] == y0[0] && e[1] == y0[1] && e[2] == y0[2]) {
        if (isnan(*kappa) && !p->bend_stopped && has_normal(e)) {
            double plain0, least = moved_bound(e, y, 0, NULL, &plain0);
            if (ISM_RM_CBOUND_RATIO * least <= p->max_error &&
                !(ISM_RM_CBOUND_RATIO * plain0 <= p->max_error))
                *kappa = fan_bend(p, v, x);
        }
        double plain, u = moved_bound(e, y, isnan(*kappa) ? INFINITY : *kappa, w, &plain);
        p->brec_known++;
        bool plain_ok = ISM_RM_CBOUND_RATIO * plain <= p->max_error;
        p->brec_skipped += plain_ok; /* rm_brec_pays */
        if (ISM_RM_CBOUND_RATIO * u <= p->max_error) {
            p->bend_spared += !plain_ok; /* fan_bend */
            return u;
        }
    }
    double u = rm_bound_upper(p, y), g[3] = {0, 0, 0};
    memcpy(w, y, 3 * sizeof *w);
    w[SLOT_U] = u;
    w[SLOT_N] = w[SLOT_N + 1] = w[SLOT_N + 2] = w[SLOT_TURN] = 0;
    /* the normal serves the bent bound only: none once no box is asked (fan_bend) */
    if (p->memo && !p->bend_stopped && isfinite(u) && rm_bound_gradient(p, y, g)) {
        /* a lookup: just measured */
        double l = ism_norm3(g);
        for (int k = 0; k < 3; k++)
            w[SLOT_N + k] = g[k] / l;
    }
    return u;
}

/* The smallest |∇f| the enclosures d allow: the norm of their smallest magnitudes. */
static double least_norm(const ism_interval d[3])
{
    double g2 = 0;
    for (int k = 0; k < 3; k++) {
        double least = d[k].lo > 0 ? d[k].lo : d[k].hi < 0 ? -d[k].hi : 0;
        g2 += least * least;
    }
    return sqrt(g2);
}

/* A bound on how fast f's unit normal ∇f/|∇f| turns (radians per unit length, in any
 * direction) over the box lo..hi, from f's interval jet there (interval_jet.h): its
 * derivative along a unit d is (I − n nᵀ) H d / |∇f|, at most |H|_F / |∇f|, with the
 * Hessian's entries at most their enclosures' magnitudes and |∇f| at least the norm of the
 * gradient enclosures' smallest magnitudes. INFINITY where ∇f may vanish in the box (a
 * singular point, or a min/max whose branches may cross there: a crease, its derivatives the
 * whole line) or the jet is not bounded. */
static double box_bend(rm_pass *p, const double *lo, const double *hi)
{
    ism_interval b[3] = {{lo[0], hi[0]}, {lo[1], hi[1]}, {lo[2], hi[2]}};
    /* ∇f's enclosures first, without the Hessian's (half the work): where ∇f may vanish, or a
       min/max may switch branches in the box (gyroid-ball: 8 boxes in 10, beside its crease)
       the Hessian is not needed */
    ism_ivgrad d;
    if (ism_eval_interval_grad_kept(p->f, p->jws, b, &d) != 0 || !(least_norm(d.d) > 0))
        return INFINITY;
    ism_ivjet j;
    if (ism_eval_interval_jet(p->f, p->jws, b, NULL, NULL, &j) == (size_t)-1)
        return INFINITY;
    double gn = least_norm(j.d), h2 = 0;
    for (int k = 0; k < 6; k++) { /* xx xy xz yy yz zz: the mixed ones twice in |H|_F */
        double most = fmax(fabs(j.h[k].lo), fabs(j.h[k].hi));
        h2 += (k == 1 || k == 2 || k == 4 ? 2 : 1) * most * most;
    }
    /* the few roundings of the sums and the root: far under the margin's relative 2^-40 */
    double kappa = sqrt(h2) / gn * (1 + 0x1p-40);
    return kappa >= 0 ? kappa : INFINITY; /* 0/0, ∞/∞: NaN */
}

/* How fast f's unit normal may turn where moved_bound uses it for v's fan with v at x: the
 * box round v's place, x and the fan's corners, grown by max_error (the points the bent bound
 * relies on, moved_bound), bounded by box_bend over a box that holds it: the one kept for v
 * (bend) when it does, else that box grown by RM_BREC_BOX_GROW of its largest side each way,
 * bounded and kept (a relaxation moves v and its neighbours by fractions of an edge: later
 * checks find their boxes inside). INFINITY where a corner is protected (rm_locks.c: a
 * crease's vertices; beside them the fan's points may lie where the other branch of f's
 * min/max rules, and the measure there is not a distance: on gyroid-ball's 1e-3 box, without
 * this, points taken from records measured up to 0.0057 against E 0.0052). */
static double fan_bend(rm_pass *p, uint32_t v, const double x[3])
{
    const rm_mesh *r = &p->r;
    double lo[3], hi[3], side = 0;
    for (int k = 0; k < 3; k++)
        lo[k] = hi[k] = x[k];
    for (uint32_t i = 0; i < r->count[v]; i++) {
        const uint32_t *c = r->m->tri + 3 * (size_t)r->vt[r->start[v] + i];
        for (int j = 0; j < 3; j++) {
            if (r->locked[c[j]])
                return INFINITY;
            const double *q = r->m->pos + 3 * (size_t)c[j];
            for (int k = 0; k < 3; k++) {
                lo[k] = q[k] < lo[k] ? q[k] : lo[k];
                hi[k] = q[k] > hi[k] ? q[k] : hi[k];
            }
        }
    }
    double *kept = p->bend + RM_BREC_BEND_REC * (size_t)v;
    bool inside = true;
    for (int k = 0; k < 3; k++) {
        lo[k] -= p->max_error, hi[k] += p->max_error;
        inside = inside && kept[k] <= lo[k] && hi[k] <= kept[3 + k]; /* NaN: no box */
        side = fmax(side, hi[k] - lo[k]);
    }
    if (!inside) {
        /* bound_of asks no bend once stopped: the flag is only ever set here */
        if (p->bend_boxes == RM_BREC_BEND_TRIAL &&
            (double)p->bend_spared < RM_BREC_BEND_MIN_SPARED * RM_BREC_BEND_TRIAL) {
            p->bend_stopped = true; /* the boxes have not paid (rm_brec.h) */
            return INFINITY;        /* the plain bound alone */
        }
        for (int k = 0; k < 3; k++) {
            kept[k] = lo[k] - RM_BREC_BOX_GROW * side;
            kept[3 + k] = hi[k] + RM_BREC_BOX_GROW * side;
        }
        kept[6] = box_bend(p, kept, kept + 3);
        p->bend_boxes++;
    }
    return kept[6];
}

bool rm_brec_fan_within(rm_pass *p, uint32_t v, const double x[3])
{
    const double *pos = p->r.m->pos + 3 * (size_t)v;
    double e = p->max_error, *keep = keep_for(p, v, x), kappa = NAN; /* not asked yet */
    if (!(rm_bound_upper(p, x) <= e))
        return rm_brec_drop(p), false;
    for (uint32_t i = 0; i < p->r.count[v]; i++) {
        uint32_t t;
        int k;
        double g0[3], g[3], m0[3], m[3], scratch[KEEP_REC];
        double *w = keep ? keep + KEEP_REC * i : scratch;
        rm_fan_point(p, v, i, pos, &t, &k, g0, m0);
        rm_fan_point(p, v, i, x, &t, &k, g, m);
        if (!(bound_of(p, t, 0, g0, g, v, x, &kappa, w) <= e) ||
            !(bound_of(p, t, 1 + k, m0, m, v, x, &kappa, w + SLOT) <= e))
            return rm_brec_drop(p), false;
    }
    return true;
}

bool rm_brec_pays(rm_pass *p)
{
    if (p->brec && p->brec_known >= RM_BREC_TRIAL &&
        (double)p->brec_skipped < RM_BREC_MIN_SHARE * (double)p->brec_known) {
        free(p->brec);
        p->brec = NULL;
    }
    return p->brec != NULL;
}

double rm_brec_fan_known(const rm_pass *p, uint32_t v)
{
    const double *pos = p->r.m->pos + 3 * (size_t)v;
    double worst = 0;
    for (uint32_t i = 0; i < p->r.count[v] && worst <= p->max_error; i++) {
        uint32_t t;
        int k;
        double g[3], m[3];
        rm_fan_point(p, v, i, pos, &t, &k, g, m);
        const double *eg = slot_of(p, t, 0), *em = slot_of(p, t, 1 + k);
        bool known = eg[0] == g[0] && eg[1] == g[1] && eg[2] == g[2] && em[0] == m[0] &&
                     em[1] == m[1] && em[2] == m[2];
        worst = known ? fmax(worst, fmax(eg[SLOT_U], em[SLOT_U])) : INFINITY;
    }
    return worst;
}

void rm_brec_moved(rm_pass *p, uint32_t v, const double x[3])
{
    const rm_mesh *r = &p->r;
    if (!p->brec || p->cen_keep_v != v || memcmp(p->cen_keep_x, x, sizeof p->cen_keep_x))
        return;
    uint32_t n = r->count[v];
    for (uint32_t i = 0; i < n; i++) {
        uint32_t t;
        int k = rm_fan_corner(p, v, i, &t);
        const uint32_t *c = r->m->tri + 3 * (size_t)t;
        const double *w = p->cen_keep + KEEP_REC * i;
        rm_brec_set(p, t, 0, w);
        rm_brec_set(p, t, 1 + k, w + SLOT);
        /* the edge from the corner before v: the next edge of the fan's triangle whose next
           corner that is (the midpoint's place and bound the same, bit for bit) */
        uint32_t prev = c[(k + 2) % 3];
        for (uint32_t j = 0; j < n; j++) {
            uint32_t u;
            int l = rm_fan_corner(p, v, j, &u);
            if (r->m->tri[3 * (size_t)u + (l + 1) % 3] == prev) {
                const double *z = p->cen_keep + KEEP_REC * j;
                rm_brec_set(p, t, 1 + (k + 2) % 3, z + SLOT);
                break;
            }
        }
    }
    rm_brec_drop(p);
}

double rm_brec_offset(rm_pass *p, uint32_t v)
{
    const double *x = p->r.m->pos + 3 * (size_t)v;
    const double *o = p->offset ? p->offset + 4 * (size_t)v : NULL;
    if (o && o[0] == x[0] && o[1] == x[1] && o[2] == x[2])
        return o[3];
    return rm_bound_signed(p, x);
}

void rm_brec_offset_set(rm_pass *p, uint32_t v, const double x[3])
{
    if (p->offset) {
        double *o = p->offset + 4 * (size_t)v;
        o[0] = x[0], o[1] = x[1], o[2] = x[2], o[3] = rm_bound_signed(p, x);
    }
}

/* Each point is measured against the bound it must meet (a point beyond it fails either
 * way, rm_bound_distance), and the first to fail ends the measure. */
bool rm_bound_fan(rm_pass *p, uint32_t v, const double *x)
{
    double e = p->max_error;
    if (rm_brec_pays(p) ? rm_brec_fan_within(p, v, x) : rm_bound_fan_worst(p, v, x, e, e) <= e)
        return true;
    if (p->brec && ISM_RM_CBOUND_RATIO * rm_brec_fan_known(p, v) <= e)
        return false; /* the fan lies within the bound now: no farther than it is no gain */
    double before = rm_bound_fan_worst(p, v, p->r.m->pos + 3 * (size_t)v, INFINITY, INFINITY);
    return rm_bound_fan_worst(p, v, x, before, before) <= before;
}
