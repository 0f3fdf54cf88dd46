/* rm_cbound.c — per-triangle centroid measures kept between steps (rm_cbound.h). */
#include "core/remesh/rm_cbound.h"

#include <stdlib.h>
#include <string.h>

/* The pass's measure |f|/|∇f| (rm_distance) is taken to lie within this factor of the
 * distance to f = 0, either way, near the surface: then a point s from one measured d lies
 * at most R d + s from f = 0 (the distance to a set moves by at most s), and measures at
 * most R² d + R s. Where |∇f| changes slowly the factor is near 1 (|f|/|∇f| is the distance
 * to first order); where it jumps (gyroid-ball's crease, where f switches between the
 * gyroid's ∇f and the ball's) no factor holds everywhere, hence a margin of 2. A centroid
 * so bounded decides nothing unless it is within centroid_bound: a measured one beyond the
 * bound is the fan's farthest whatever the others measure (rm_centroids_stay, rm_flip.c).
 * Not exact in principle (nothing bounds ∇|∇f|); measured in core/README.md (the quality
 * pass): the meshes byte-identical on 33 preset boxes, the bound overrun by at most 1.11×
 * (cross-cap), never at centroid_bound. Taking d + 2 × the moves' lengths instead, 3 of the
 * gyroid-ball's 1.5 million centroids so taken measured beyond centroid_bound. */
#define ISM_RM_CBOUND_RATIO 2.0

bool rm_cbound_open(rm_pass *p)
{
    size_t n = p->r.cap_tris ? p->r.cap_tris : 1;
    p->cen_ref = malloc(4 * n * sizeof *p->cen_ref);
    p->cen_keep_v = UINT32_MAX;
    if (!p->cen_ref)
        return false;
    for (size_t t = 0; t < n; t++) {
        double *e = p->cen_ref + 4 * t;
        e[0] = e[1] = e[2] = 0;
        e[3] = INFINITY;
    }
    return true;
}

double rm_cbound_at(const rm_pass *p, uint32_t t, const double c[3])
{
    const double *e = p->cen_ref + 4 * (size_t)t, r = ISM_RM_CBOUND_RATIO;
    double s = sqrt((c[0] - e[0]) * (c[0] - e[0]) + (c[1] - e[1]) * (c[1] - e[1]) +
                    (c[2] - e[2]) * (c[2] - e[2]));
    return r * r * e[3] + r * s; /* INFINITY when nothing was measured */
}

double *rm_cbound_fan(rm_pass *p, uint32_t v, const double x[3])
{
    uint32_t n = p->r.count[v];
    if (!p->cen_ref)
        return NULL;
    if (n > p->cen_keep_cap) {
        double *k = realloc(p->cen_keep, 8 * (size_t)n * sizeof *k);
        if (!k) {
            rm_cbound_drop(p);
            return NULL;
        }
        p->cen_keep = k;
        p->cen_keep_cap = 2 * n;
    }
    for (uint32_t i = 0; i < n; i++)
        p->cen_keep[4 * i + 3] = NAN;
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
        const double *k = p->cen_keep + 4 * i;
        if (!isnan(k[3]))
            rm_cbound_set(p, r->vt[r->start[v] + i], k, k[3]);
    }
    rm_cbound_drop(p);
}
