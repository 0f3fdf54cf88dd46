/* rm_slide.c — box-boundary vertices slide along the boundary curve. Where a face of the
 * search box cuts the surface, the polygoniser leaves boundary edges as short as the cut
 * happens to make them (kummer-16-nodes: 0.0008 beside 0.09), and every triangle on such an
 * edge is a needle that no flip or interior move can mend. A vertex on that curve (its two
 * boundary neighbours in the same box plane, rm_locks.c) moves toward the middle of its
 * neighbours within the plane and back onto f = 0 by Newton in the plane, so it stays on the
 * box face and on the surface, and the boundary loop keeps its vertices, edges and order. */
#include "core/remesh/rm_bound.h"
#include "core/remesh/rm_brec.h"
#include "core/remesh/rm_pass.h"

#include <math.h>
#include <string.h>

/* A slide may leave the boundary edges' midpoints and the vertex this × the fan's mean edge
 * from f = 0 whatever they were: rounding. Where a box face cuts the surface in straight
 * lines (whitney-umbrella's top face z = 1: x = ±y) every boundary point measures rounding
 * (1e-17) and any slide another, so each was refused by chance; 1e-12 of an edge lies far
 * above that and far below the polygoniser's own vertex error (~1e-8). Whitney in the 1e-3
 * / 0.37-cell boxes: needles under 10° at the boundary 10 / 5 -> 3 / 2 (those left have a
 * corner where the surface crosses an edge of the box: no plane to slide in). */
#define ISM_RM_SLIDE_ROUNDING 1e-12

/* The two boundary neighbours of v (one triangle on the edge) and the axis of the box plane
 * the three share; false when they are not found. */
static bool boundary_neighbours(const rm_pass *p, uint32_t v, uint32_t nb[2], int *axis)
{
    const rm_mesh *r = &p->r;
    int n = 0;
    for (uint32_t i = 0; i < r->count[v] && n <= 2; i++) {
        uint32_t t = r->vt[r->start[v] + i], two[2];
        int k = rm_corner(r->m, t, v), c;
        for (int s = 1; s <= 2; s++) {
            uint32_t w = r->m->tri[3 * t + (k + s) % 3];
            rm_edge_triangles(r, v, w, two, &c);
            if (c == 1 && n < 2)
                nb[n++] = w;
        }
    }
    const double *P = r->m->pos;
    for (int k = 0; n == 2 && k < 3; k++)
        if (P[3 * v + k] == P[3 * nb[0] + k] && P[3 * v + k] == P[3 * nb[1] + k]) {
            *axis = k;
            return true;
        }
    return false;
}

/* The farther of the distances from f = 0 at the midpoints of x's two boundary edges. */
static double boundary_error(rm_pass *p, const double *x, const double *a, const double *b)
{
    double ma[3], mb[3];
    for (int k = 0; k < 3; k++) {
        ma[k] = 0.5 * (x[k] + a[k]);
        mb[k] = 0.5 * (x[k] + b[k]);
    }
    return fmax(rm_distance(p, ma), rm_distance(p, mb));
}

bool rm_in_order(const double *x, const double *a, const double *b)
{
    double ab[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]}, l2 = 0, t = 0;
    for (int k = 0; k < 3; k++) {
        l2 += ab[k] * ab[k];
        t += (x[k] - a[k]) * ab[k];
    }
    t /= l2 > 0 ? l2 : 1;
    return t > ISM_RM_SLIDE_KEEP_ORDER && t < 1 - ISM_RM_SLIDE_KEEP_ORDER;
}

/* ∇f at x into g, the vertex's normal should it move there. Under a bound through the
 * pass's memo (rm_bound_gradient: the same evaluation, bit for bit), so that the distance
 * at x measured next (rm_distance) is a lookup rather than a second evaluation of f and ∇f
 * at the same point. Where the memo's step fails (∇f vanishes, f not finite) or there is no
 * memo (no bound), evaluated as before. With slide_vertex's cheap checks first: catenoid's
 * own box (callgrind --toggle-collect=ism_quality_pass, --quality good --threads 1)
 * rm_slide_sweep 9.05M -> 7.38M instructions, the same mesh. */
static void full_gradient(rm_pass *p, const double x[3], double g[3])
{
    if (!(p->memo && rm_bound_gradient(p, x, g)))
        ism_eval_gradient(p->f, p->ws, x[0], x[1], x[2], g);
}

/* Tries to slide v; true when it moved. */
static bool slide_vertex(rm_pass *p, uint32_t v)
{
    uint32_t nb[2];
    int axis;
    if (!boundary_neighbours(p, v, nb, &axis))
        return false;
    const double *pos = p->r.m->pos + 3 * v;
    const double *a = p->r.m->pos + 3 * nb[0], *b = p->r.m->pos + 3 * nb[1];
    rm_fan f;
    rm_fan_measure(p, v, &f);
    double bound = NAN; /* measured once a try passes the shape checks */
    for (double step = 1; step >= 0.5; step *= 0.5) {
        double x[3], g[3];
        for (int k = 0; k < 3; k++)
            x[k] = pos[k] + step * (0.5 * (a[k] + b[k]) - pos[k]);
        x[axis] = pos[axis];
        double start[3] = {x[0], x[1], x[2]};
        if (!rm_project(p, x, f.mean_edge, axis, g))
            continue;
        x[axis] = pos[axis]; /* exactly on the box face */
        /* the checks that cost no evaluation first: the measures are pure (f is), so the
           order decides nothing; rm_bound_fan, which keeps records, stays last */
        if (!(rm_dist(x, start) <= 0.5 * f.mean_edge) || !rm_in_order(x, a, b) ||
            !rm_fan_accepts(p, v, x, &f))
            continue;
        if (isnan(bound))
            bound = fmax(fmax(p->max_error, boundary_error(p, pos, a, b)),
                         ISM_RM_SLIDE_ROUNDING * f.mean_edge);
        full_gradient(p, x, g);
        if (!(boundary_error(p, x, a, b) <= bound) || !(rm_distance(p, x) <= bound) ||
            (p->bounded && !rm_bound_fan(p, v, x)))
            continue;
        rm_commit_move(p, v, x, g);
        return true;
    }
    return false;
}

size_t rm_slide_sweep(rm_pass *p)
{
    size_t moves = 0;
    for (size_t v = 0; v < p->r.m->nverts; v++)
        if (p->active[v] && p->slide[v] && slide_vertex(p, (uint32_t)v))
            moves++;
    p->moves += moves;
    return moves;
}
