/* rm_brec.c — per-triangle bounds on the distance of the centroid and edge midpoints, and
 * per-vertex offsets, kept between steps of the quality pass under an error bound
 * (rm_brec.h). */
#include "core/remesh/rm_brec.h"
#include "core/remesh/rm_bound.h"
#include "core/remesh/rm_cbound.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

/* What the fan's check found, per triangle of the fan in slot order: the new centroid and
 * its bound, the new midpoint of the edge from v to the next corner and its bound. */
#define KEEP_REC 8

/* Points per triangle: the centroid (slot 0), then the midpoint of the edge from corner j to
 * corner j + 1 (slot 1 + j); each a place and a bound. */
#define RM_BREC_POINTS 4
#define RM_BREC_REC (4 * RM_BREC_POINTS)

/* The bound slot s of triangle t gives at x: its bound plus x's distance from its point
 * (INFINITY when nothing is kept there). */
static double rm_brec_at(const rm_pass *p, uint32_t t, int s, const double x[3])
{
    const double *e = p->brec + RM_BREC_REC * (size_t)t + 4 * s;
    double d = sqrt((x[0] - e[0]) * (x[0] - e[0]) + (x[1] - e[1]) * (x[1] - e[1]) +
                    (x[2] - e[2]) * (x[2] - e[2]));
    return e[3] + d;
}

/* Slot s of triangle t: x lies within u of f = 0. */
static void rm_brec_set(rm_pass *p, uint32_t t, int s, const double x[3], double u)
{
    double *e = p->brec + RM_BREC_REC * (size_t)t + 4 * s;
    e[0] = x[0], e[1] = x[1], e[2] = x[2], e[3] = u;
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
 * y0): that slot's, moved by |y - y0| (rm_brec_at), when ISM_RM_CBOUND_RATIO times it is
 * within max_error; else measured. */
static double bound_of(rm_pass *p, uint32_t t, int s, const double y0[3], const double y[3])
{
    const double *e = p->brec + RM_BREC_REC * (size_t)t + 4 * s;
    if (e[0] == y0[0] && e[1] == y0[1] && e[2] == y0[2]) {
        double u = rm_brec_at(p, t, s, y);
        p->brec_known++;
        if (ISM_RM_CBOUND_RATIO * u <= p->max_error)
            return p->brec_skipped++, u;
    }
    return rm_bound_upper(p, y);
}

bool rm_brec_fan_within(rm_pass *p, uint32_t v, const double x[3])
{
    const double *pos = p->r.m->pos + 3 * (size_t)v;
    double e = p->max_error, *keep = keep_for(p, v, x);
    if (!(rm_bound_upper(p, x) <= e))
        return rm_brec_drop(p), false;
    for (uint32_t i = 0; i < p->r.count[v]; i++) {
        uint32_t t;
        int k;
        double g0[3], g[3], m0[3], m[3];
        rm_fan_point(p, v, i, pos, &t, &k, g0, m0);
        rm_fan_point(p, v, i, x, &t, &k, g, m);
        double bg = bound_of(p, t, 0, g0, g);
        if (!(bg <= e))
            return rm_brec_drop(p), false;
        double bm = bound_of(p, t, 1 + k, m0, m);
        if (!(bm <= e))
            return rm_brec_drop(p), false;
        if (keep) {
            double *w = keep + KEEP_REC * i;
            memcpy(w, g, sizeof g), w[3] = bg;
            memcpy(w + 4, m, sizeof m), w[7] = bm;
        }
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
        const double *eg = p->brec + RM_BREC_REC * (size_t)t, *em = eg + 4 * (1 + k);
        bool known = eg[0] == g[0] && eg[1] == g[1] && eg[2] == g[2] && em[0] == m[0] &&
                     em[1] == m[1] && em[2] == m[2];
        worst = known ? fmax(worst, fmax(eg[3], em[3])) : INFINITY;
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
        rm_brec_set(p, t, 0, w, w[3]);
        rm_brec_set(p, t, 1 + k, w + 4, w[7]);
        /* the edge from the corner before v: the next edge of the fan's triangle whose next
           corner that is (the midpoint's place and bound the same, bit for bit) */
        uint32_t prev = c[(k + 2) % 3];
        for (uint32_t j = 0; j < n; j++) {
            uint32_t u;
            int l = rm_fan_corner(p, v, j, &u);
            if (r->m->tri[3 * (size_t)u + (l + 1) % 3] == prev) {
                const double *z = p->cen_keep + KEEP_REC * j;
                rm_brec_set(p, t, 1 + (k + 2) % 3, z + 4, z[7]);
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
    if (p->brec && rm_brec_fan_known(p, v) <= e)
        return false; /* the fan lies within the bound now: no farther than it is no gain */
    double before = rm_bound_fan_worst(p, v, p->r.m->pos + 3 * (size_t)v, INFINITY, INFINITY);
    return rm_bound_fan_worst(p, v, x, before, before) <= before;
}
