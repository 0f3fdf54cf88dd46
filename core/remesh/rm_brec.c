/* rm_brec.c — per-triangle bounds on the distance of the centroid and edge midpoints, and
 * per-vertex offsets, kept between steps of the quality pass under an error bound
 * (rm_brec.h). */
#include "core/remesh/rm_brec.h"
#include "core/remesh/rm_bound.h"
#include "core/remesh/rm_cbound.h"
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

/* The record e moved to y (into w, when not NULL): a bound on y's distance from f = 0 where
 * f's level sets bend by at most kappa (radians per unit length) about the fan. The distance
 * to a set moves by at most as far as the point does (u + |δ|, δ = y − e's place, always);
 * where e has a normal n, turned by at most a since its point was measured, the surface's
 * nearest point to e's lies within u along a normal within a + κu of n, and the surface
 * leaves its tangent plane there by at most κ|δ|²/2 over |δ|: u + |n·δ| + (a + κu)|δ| +
 * κ|δ|²/2, the smaller of the two. A relaxation moves a fan's points along the surface
 * (n·δ about 0), where the first bound grows by all of |δ| and this one by its square. */
static double moved_bound(const double *e, const double y[3], double kappa, double *w,
                          double *plain)
{
    double dx[3] = {y[0] - e[0], y[1] - e[1], y[2] - e[2]};
    double len = ism_norm3(dx), u = e[SLOT_U] + len;
    *plain = u;
    double turn = e[SLOT_TURN] + kappa * len; /* n's turn at y */
    double along = fabs(ism_dot3(e + SLOT_N, dx));
    bool normal = e[SLOT_N] != 0 || e[SLOT_N + 1] != 0 || e[SLOT_N + 2] != 0;
    double bent = e[SLOT_U] + along + (e[SLOT_TURN] + kappa * e[SLOT_U]) * len +
                  0.5 * kappa * len * len;
    bool use = normal && bent < u; /* never NaN: kappa finite here */
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
    p->offset = malloc(4 * nv * sizeof *p->offset);
    p->cen_keep_v = UINT32_MAX;
    if (!p->brec || !p->offset)
        return false;
    /* no point (NaN matches no place): measured when asked */
    for (size_t i = 0; i < RM_BREC_REC * n; i++)
        p->brec[i] = NAN;
    for (size_t i = 0; i < 4 * nv; i++)
        p->offset[i] = NAN;
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

/* The bound at y, which lies where slot s of triangle t's point was before the move (at
 * y0), with its record into w: that slot's moved to y (moved_bound, level sets bending by at
 * most kappa) when ISM_RM_CBOUND_RATIO times it is within max_error; else measured (with
 * ∇f's direction there, from the pass's memo: no evaluation more). */
static double bound_of(rm_pass *p, uint32_t t, int s, const double y0[3], const double y[3],
                       double kappa, double *w)
{
    const double *e = slot_of(p, t, s);
    if (e[0] == y0[0] && e[1] == y0[1] && e[2] == y0[2]) {
        double plain, u = moved_bound(e, y, kappa, w, &plain);
        p->brec_known++;
        p->brec_skipped += ISM_RM_CBOUND_RATIO * plain <= p->max_error; /* rm_brec_pays */
        if (ISM_RM_CBOUND_RATIO * u <= p->max_error)
            return u;
    }
    double u = rm_bound_upper(p, y), g[3] = {0, 0, 0};
    memcpy(w, y, 3 * sizeof *w);
    w[SLOT_U] = u;
    w[SLOT_N] = w[SLOT_N + 1] = w[SLOT_N + 2] = w[SLOT_TURN] = 0;
    if (p->memo && isfinite(u) && rm_bound_gradient(p, y, g)) { /* a lookup: just measured */
        double l = ism_norm3(g);
        for (int k = 0; k < 3; k++)
            w[SLOT_N + k] = g[k] / l;
    }
    return u;
}

/* How fast f's level sets may turn about v's fan (radians per unit length), for moved_bound:
 * RM_BREC_BEND_MARGIN times the largest turn of ∇f's direction between v and a corner of its
 * fan over their distance (the pass's unit normals at the vertices: measured, kept as the
 * vertices move); INFINITY where one vanishes (beside a singular point), the normals part by
 * more than RM_BREC_BEND_MAX (a crease: ∇f jumps, no bend bounds it) or a corner is
 * protected (rm_locks.c: a crease's vertices; beside them the fan's points may lie where the
 * other branch of f's min/max rules: on gyroid-ball's 1e-3 box, without this, points taken
 * from records measured up to 0.0057 against E 0.0052). */
static double fan_bend(const rm_pass *p, uint32_t v)
{
    const rm_mesh *r = &p->r;
    const double *nv = p->normal + 3 * (size_t)v, *x = r->m->pos + 3 * (size_t)v;
    double worst = 0, apart = cos(RM_BREC_BEND_MAX);
    if (ism_dot3(nv, nv) == 0)
        return INFINITY;
    for (uint32_t i = 0; i < r->count[v]; i++) {
        const uint32_t *c = r->m->tri + 3 * (size_t)r->vt[r->start[v] + i];
        for (int k = 0; k < 3; k++) {
            if (r->locked[c[k]])
                return INFINITY;
            if (c[k] == v)
                continue;
            const double *nw = p->normal + 3 * (size_t)c[k];
            double cosine = ism_dot3(nv, nw);
            if (!(cosine >= apart))
                return INFINITY;
            double chord[3] = {nv[0] - nw[0], nv[1] - nw[1], nv[2] - nw[2]};
            /* the angle from its chord (2 asin(c/2) <= c × π/3 for angles up to π/3) */
            double turn = ism_norm3(chord) * (M_PI / 3) / rm_dist(x, r->m->pos + 3 * (size_t)c[k]);
            worst = turn > worst ? turn : worst;
        }
    }
    return RM_BREC_BEND_MARGIN * worst;
}

bool rm_brec_fan_within(rm_pass *p, uint32_t v, const double x[3])
{
    const double *pos = p->r.m->pos + 3 * (size_t)v;
    double e = p->max_error, *keep = keep_for(p, v, x), kappa = fan_bend(p, v);
    if (!(rm_bound_upper(p, x) <= e))
        return rm_brec_drop(p), false;
    for (uint32_t i = 0; i < p->r.count[v]; i++) {
        uint32_t t;
        int k;
        double g0[3], g[3], m0[3], m[3], scratch[KEEP_REC];
        double *w = keep ? keep + KEEP_REC * i : scratch;
        rm_fan_point(p, v, i, pos, &t, &k, g0, m0);
        rm_fan_point(p, v, i, x, &t, &k, g, m);
        if (!(bound_of(p, t, 0, g0, g, kappa, w) <= e) ||
            !(bound_of(p, t, 1 + k, m0, m, kappa, w + SLOT) <= e))
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
