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

/* Triangle t's centroid c measured d from f = 0 (rm_distance). */
static inline void rm_cbound_set(rm_pass *p, uint32_t t, const double c[3], double d)
{
    if (p->cen_ref) {
        double *e = p->cen_ref + 4 * (size_t)t;
        e[0] = c[0], e[1] = c[1], e[2] = c[2], e[3] = d;
    }
}

/* Triangle to takes what from knows (a triangle split from it: its point is near). */
static inline void rm_cbound_copy(rm_pass *p, uint32_t to, uint32_t from)
{
    if (p->cen_ref)
        memcpy(p->cen_ref + 4 * (size_t)to, p->cen_ref + 4 * (size_t)from, 4 * sizeof(double));
}

/* The bound rm_cbound.c takes on the distance at c from what triangle t knows (INFINITY
 * when nothing). */
double rm_cbound_at(const rm_pass *p, uint32_t t, const double c[3]);

/* True when triangle t's centroid at c is surely within centroid_bound. */
static inline bool rm_cbound_within(const rm_pass *p, uint32_t t, const double c[3])
{
    return p->cen_ref && rm_cbound_at(p, t, c) <= p->centroid_bound;
}

/* The distance measured at c, when t's point is c bit for bit; NAN otherwise. */
static inline double rm_cbound_exact(const rm_pass *p, uint32_t t, const double c[3])
{
    const double *e = p->cen_ref ? p->cen_ref + 4 * (size_t)t : NULL;
    return e && e[0] == c[0] && e[1] == c[1] && e[2] == c[2] ? e[3] : NAN;
}

/* Room for the centroids and distances of v's fan with v at x (4 per triangle of the fan in
 * its slot order; distance NAN: not measured), for rm_centroids_stay to fill; kept until v
 * moves to x (rm_cbound_moved) or rm_cbound_drop. NULL when out of memory (nothing kept). */
double *rm_cbound_fan(rm_pass *p, uint32_t v, const double x[3]);
static inline void rm_cbound_drop(rm_pass *p) { p->cen_keep_v = UINT32_MAX; }

/* v moves to x: each triangle of its fan measured there (rm_cbound_fan) takes that measure. */
void rm_cbound_moved(rm_pass *p, uint32_t v, const double x[3]);

#endif
