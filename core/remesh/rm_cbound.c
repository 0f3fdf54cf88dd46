/* rm_cbound.c — per-triangle centroid measures kept between steps (rm_cbound.h). */
#include "core/remesh/rm_cbound.h"

#include "core/remesh/rm_bound.h"
#include "core/util/vec3.h"

#include <stdlib.h>
#include <string.h>


bool rm_cbound_open(rm_pass *p)
{
    size_t n = p->r.cap_tris ? p->r.cap_tris : 1;
    p->cen_ref = malloc(RM_CBOUND_REC * n * sizeof *p->cen_ref);
    p->cen_keep_v = UINT32_MAX;
    p->cen_gradient_min = ISM_RM_CBOUND_GRADIENT_SHARE * p->gthresh / ISM_RM_SINGULAR_REL;
    if (!p->cen_ref)
        return false;
    for (size_t t = 0; t < n; t++) {
        double *e = p->cen_ref + RM_CBOUND_REC * t;
        e[0] = e[1] = e[2] = e[4] = 0;
        e[3] = INFINITY;
    }
    return true;
}

double rm_cbound_distance(rm_pass *p, const double x[3], double *gn)
{
    double g[3], fv = ism_eval_gradient(p->f, p->ws, x[0], x[1], x[2], g);
    return rm_unbounded_distance(p, fv, g, gn); /* as rm_distance, bit for bit */
}

double *rm_cbound_fan(rm_pass *p, uint32_t v, const double x[3])
{
    uint32_t n = p->r.count[v];
    if (!p->cen_ref)
        return NULL;
    if (n > p->cen_keep_cap) {
        double *k = realloc(p->cen_keep, 2 * RM_CBOUND_REC * (size_t)n * sizeof *k);
        if (!k) {
            rm_cbound_drop(p);
            return NULL;
        }
        p->cen_keep = k;
        p->cen_keep_cap = 2 * n;
    }
    for (uint32_t i = 0; i < n; i++)
        p->cen_keep[RM_CBOUND_REC * i + 3] = NAN;
    p->cen_keep_v = v;
    memcpy(p->cen_keep_x, x, sizeof p->cen_keep_x);
    return p->cen_keep;
}

void rm_cbound_moved(rm_pass *p, uint32_t v, const double x[3])
{
    const rm_mesh *r = &p->r;
    if (!p->cen_ref || p->cen_keep_v != v || memcmp(p->cen_keep_x, x, sizeof p->cen_keep_x))
        return;
    for (uint32_t i = 0; i < r->count[v]; i++) {
        const double *k = p->cen_keep + RM_CBOUND_REC * i;
        if (!isnan(k[3]))
            rm_cbound_set(p, r->vt[r->start[v] + i], k, k[3], k[4]);
    }
    rm_cbound_drop(p);
}
