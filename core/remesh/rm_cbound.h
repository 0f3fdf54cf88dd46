/* rm_cbound.h — what the quality pass knows of each triangle's centroid distance from f = 0
 * without measuring it again (rm_cbound.c). Without an error bound a move, a flip or a collapse
 * is refused when it puts a centroid farther from f = 0 than the mesh's farthest before the
 * pass (centroid_bound) and than the centroids it replaces; measuring every centroid of a
 * fan for every relaxation move was 884M of the gyroid-ball pass's 2,953M instructions
 * (callgrind). Each triangle keeps the last point near it that was measured (its centroid
 * then) and the distance there; a centroid close enough to that point, for the distance
 * measured there, cannot be beyond centroid_bound and is not measured. Only for the pass
 * without an error bound (the bounded rule, rm_bound.h, measures midpoints too and keeps its
 * own memo). */
#ifndef ISM_RM_CBOUND_H
#define ISM_RM_CBOUND_H

#include "core/remesh/rm_pass.h"

#include <string.h>

/* Room for every triangle the pass may hold (r.cap_tris), nothing known yet. False when out
 * of memory. rm_pass_close frees it. */
bool rm_cbound_open(rm_pass *p);

/* A record: the point measured, the distance there (rm_distance) and |∇f| there. */
#define RM_CBOUND_REC 5

/* rm_distance at x (without an error bound), and |∇f| there into *gn. */
double rm_cbound_distance(rm_pass *p, const double x[3], double *gn);

/* Triangle t's centroid c measured d from f = 0 with |∇f| gn there. */
static inline void rm_cbound_set(rm_pass *p, uint32_t t, const double c[3], double d, double gn)
{
    if (p->cen_ref) {
        double *e = p->cen_ref + RM_CBOUND_REC * (size_t)t;
        e[0] = c[0], e[1] = c[1], e[2] = c[2], e[3] = d, e[4] = gn;
    }
}

/* Triangle to takes what from knows (a triangle split from it: its point is near). */
static inline void rm_cbound_copy(rm_pass *p, uint32_t to, uint32_t from)
{
    if (p->cen_ref)
        memcpy(p->cen_ref + RM_CBOUND_REC * (size_t)to, p->cen_ref + RM_CBOUND_REC * (size_t)from,
               RM_CBOUND_REC * sizeof(double));
}

/* The pass's measure |f|/|∇f| (rm_distance) is taken to lie within this factor of the
 * distance to f = 0, either way, near the surface: then a point s from one measured d lies
 * at most R d + s from f = 0 (the distance to a set moves by at most s), and measures at
 * most R² d + R s. Where |∇f| changes slowly the factor is near 1 (|f|/|∇f| is the distance
 * to first order); where it jumps (gyroid-ball's crease, where f switches between the
 * gyroid's ∇f and the ball's) no factor holds everywhere, hence a margin of 2. A centroid
 * so bounded decides nothing unless it is within centroid_bound: a measured one beyond the
 * bound is the fan's farthest whatever the others measure (rm_centroids_stay, rm_flip.c).
 * Not exact in principle (nothing bounds ∇|∇f|); measured in core/README.md (the quality
 * pass): the meshes byte-identical on 33 preset boxes, the bound overrun by at most 1.04×
 * (gyroid-ball's crease), a centroid so taken never beyond 0.76 of centroid_bound. Taking
 * d + 2 × the moves' lengths instead, 3 of the gyroid-ball's 1.5 million centroids so
 * taken measured beyond centroid_bound. */
#define ISM_RM_CBOUND_RATIO 2.0

/* Where |∇f| at the point measured is under this share of its median over the vertices no
 * bound is taken from it: |f|/|∇f| changes fastest where |∇f| is small, and it vanishes at
 * singular points (cross-cap's: without it the bound above was overrun 1.11× beside them, a
 * centroid so taken measuring 0.92 of centroid_bound; with it 0.49× and 0.21 at most). */
#define ISM_RM_CBOUND_GRADIENT_SHARE 0.25

/* The bound taken on the distance at c from what triangle t knows (INFINITY when nothing). */
static inline double rm_cbound_at(const rm_pass *p, uint32_t t, const double c[3])
{
    const double *e = p->cen_ref + RM_CBOUND_REC * (size_t)t, r = ISM_RM_CBOUND_RATIO;
    if (!(e[4] >= p->cen_gradient_min))
        return INFINITY;
    double s = sqrt((c[0] - e[0]) * (c[0] - e[0]) + (c[1] - e[1]) * (c[1] - e[1]) +
                    (c[2] - e[2]) * (c[2] - e[2]));
    return r * r * e[3] + r * s;
}

/* True when triangle t's centroid at c (to rounding: the bound has room) is surely within
 * centroid_bound. */
static inline bool rm_cbound_within(const rm_pass *p, uint32_t t, const double c[3])
{
    return p->cen_ref && rm_cbound_at(p, t, c) <= p->centroid_bound;
}

/* The distance measured at c, when t's point is c bit for bit; NAN otherwise. */
static inline double rm_cbound_exact(const rm_pass *p, uint32_t t, const double c[3])
{
    const double *e = p->cen_ref ? p->cen_ref + RM_CBOUND_REC * (size_t)t : NULL;
    return e && e[0] == c[0] && e[1] == c[1] && e[2] == c[2] ? e[3] : NAN;
}

/* Room for the records of v's fan with v at x (RM_CBOUND_REC per triangle of the fan in its
 * slot order; distance NAN: not measured), for rm_centroids_stay to fill; kept until v
 * moves to x (rm_cbound_moved) or rm_cbound_drop. NULL when out of memory (nothing kept). */
double *rm_cbound_fan(rm_pass *p, uint32_t v, const double x[3]);
static inline void rm_cbound_drop(rm_pass *p) { p->cen_keep_v = UINT32_MAX; }

/* v moves to x: each triangle of its fan measured there (rm_cbound_fan) takes that measure. */
void rm_cbound_moved(rm_pass *p, uint32_t v, const double x[3]);

#endif
