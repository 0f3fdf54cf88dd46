/* rm_sheets.c — the sheets that ∇f's unit normals at a set of vertices fall into (rm_sheets:
 * a normal more than the crease angle from every group's first starts a new group; two on a
 * crease, three or more at a junction), where three sheets' tangent planes meet
 * (rm_sheets_meet), and whether a vertex is a junction's own vertex (rm_junction_vertex:
 * the sheets of the vertices up to two edges from it meet within its mean edge, nearer it
 * than any neighbour). rm_junction.c's clusters read the sheets of their rims; the crease
 * merges ask rm_junction_vertex on every candidate so as not to move a junction's vertex:
 * crease_merge_find (rm_collapse.c) and snap_merge (rm_crease_slide.c), the caller whose
 * merges moved it (2efee29's trace). Split from rm_junction.c, the cluster collapse (revE 3). */
#include "core/remesh/rm_merge.h"
#include "core/remesh/rm_pass.h"
#include "core/util/vec3.h"

#include <math.h>
#include <string.h>

/* The three sheets' unit normals must span space at least this much (their triple product)
 * for the tangent planes' meeting point to be a junction: two normals the crease angle apart
 * (ISM_RM_CREASE_DEG, 40°: they are in different groups) and a third the crease angle out of
 * their plane give sin² 40° = 0.41; under it the third sheet is one of the first two bent
 * (a curved sheet read as two groups beside a crease) and the planes meet far off or along a
 * line (a cube's corner: 1, three balls' triple points: 0.99). */
#define ISM_RM_JUNCTION_DET 0.41
/* A junction vertex's sheets are read off the vertices at most two edges from it, at most
 * this many (rm_junction_vertex): 8 + 8 x 8 = 72 for crease vertices of degree up to 8 (a
 * crowded crease vertex has 6 to 8), with room; where there are more the farthest are left
 * out. The walk itself is not capped: v of up to ISM_RM_MERGE_MAX_DEGREE (24) triangles has
 * up to 48 neighbours, each of whose triangles' corners is offered to the ring (an O(96)
 * check and insertion), some 48 x 24 x 3 x 96 = 330k compares at worst; only a vertex the
 * screen (third_sheet_possible) passes gets there, and crowded crease vertices have degree
 * 6 to 8 (rm_junction.c's ISM_RM_JUNCTION_STAR), a few thousand compares (revE 4). */
#define ISM_RM_JUNCTION_RING 96
/* Newton steps onto the junction of three smooth pieces at most (onto_pieces), and the step,
 * as a share of how far the planes were read from it, at which they have converged: they
 * converge quadratically from the planes' point (three-balls' spheres read 0.1 off put it
 * ~0.007 from the junction: three steps to 1e-10 of that, the next one to rounding); the
 * cube's planes are its pieces (one step of 0). */
#define ISM_RM_JUNCTION_NEWTON_STEPS 8
#define ISM_RM_JUNCTION_NEWTON_TOL 1e-10

void rm_sheets_add(const rm_pass *p, rm_sheets *s, uint32_t v)
{
    if (rm_normal_zero(p, v))
        return;
    const double *n = p->normal + 3 * (size_t)v;
    double near = rm_crease_cos();
    int h = 0;
    while (h < s->n && !(ism_dot3(s->normal[h], n) >= near))
        h++;
    if (h == s->n && s->n < ISM_RM_COLLAPSE_MAX_DEGREE) {
        s->d[s->n] = ism_dot3(n, rm_pos(p, v)), s->v[s->n] = v;
        s->normal[s->n++] = n;
    }
}

/* Where the planes g[i] · x = d[i] meet (x), when their normals span space at least det_min
 * (the triple product's size); false otherwise. */
static bool planes_meet(const double *const g[3], const double d[3], double det_min,
                        double x[3])
{
    double c12[3], c23[3], c31[3];
    ism_cross3(g[1], g[2], c23);
    ism_cross3(g[2], g[0], c31);
    ism_cross3(g[0], g[1], c12);
    double det = ism_dot3(g[0], c23);
    if (!(fabs(det) >= det_min))
        return false;
    for (int k = 0; k < 3; k++)
        x[k] = (d[0] * c23[k] + d[1] * c31[k] + d[2] * c12[k]) / det;
    return true;
}

/* x taken on to where the three pieces pc vanish: Newton steps, each to where the pieces'
 * tangent planes at the last point meet (planes_meet, the normals' rule), at most
 * ISM_RM_JUNCTION_NEWTON_STEPS; kept when a step falls under ISM_RM_JUNCTION_NEWTON_TOL × reach
 * within reach of where it started (reach: how far from x the planes were read, so farther
 * is another junction); x unchanged otherwise (a piece's gradient vanishing, the three
 * turning parallel, no convergence). A reach of 0 — every sheet's first vertex at the
 * planes' point — admits only a step of exactly 0: x then stays that point, which lies on
 * every sheet's vertex already. */
static void onto_pieces(const rm_pass *p, const ism_piece pc[3], double reach, double x[3])
{
    double y[3] = {x[0], x[1], x[2]};
    for (int step = 0; step < ISM_RM_JUNCTION_NEWTON_STEPS; step++) {
        double grad[3][3], d[3], z[3];
        const double *g[3] = {grad[0], grad[1], grad[2]};
        for (int h = 0; h < 3; h++) {
            double val = ism_eval_piece_gradient(p->f, p->ws, pc[h], y[0], y[1], y[2], grad[h]);
            double len = ism_normalise3(grad[h]);
            if (!isfinite(val) || !(len > 0) || !isfinite(len))
                return;
            d[h] = ism_dot3(grad[h], y) - val / len;
        }
        if (!planes_meet(g, d, ISM_RM_JUNCTION_DET, z))
            return;
        double moved = rm_dist(y, z);
        memcpy(y, z, sizeof y);
        if (!(rm_dist(x, y) <= reach))
            return;
        if (moved <= ISM_RM_JUNCTION_NEWTON_TOL * reach) {
            memcpy(x, y, sizeof y);
            return;
        }
    }
}

bool rm_sheets_meet(const rm_pass *p, const rm_sheets *s, double x[3])
{
    if (s->n < 3 || !planes_meet(s->normal, s->d, ISM_RM_JUNCTION_DET, x))
        return false;
    ism_piece pc[3];
    double reach = 0;
    for (int h = 0; h < 3; h++) {
        const double *q = rm_pos(p, s->v[h]);
        if ((pc[h] = ism_eval_piece(p->f, p->ws, q[0], q[1], q[2])) == ISM_PIECE_NONE)
            return true; /* more kinks than a piece names: the planes' point */
        reach = fmax(reach, rm_dist(q, x));
    }
    onto_pieces(p, pc, reach, x);
    return true;
}

/* Adds x (not v) to ring[0..*n) unless there, nearest v first (dist[]: the distances); past
 * ISM_RM_JUNCTION_RING the farthest go. */
static void ring_add(const rm_pass *p, uint32_t v, uint32_t x, uint32_t *ring, double *dist,
                     int *n)
{
    double d = rm_dist(rm_pos(p, v), rm_pos(p, x));
    for (int k = 0; k < *n; k++)
        if (ring[k] == x)
            return;
    if (x == v || (*n == ISM_RM_JUNCTION_RING && !(d < dist[*n - 1])))
        return;
    int i = *n < ISM_RM_JUNCTION_RING ? (*n)++ : *n - 1;
    for (; i > 0 && dist[i - 1] > d; i--)
        ring[i] = ring[i - 1], dist[i] = dist[i - 1];
    ring[i] = x, dist[i] = d;
}

/* False only when the normals at v and the vertices up to two edges from it (nb: v's n
 * neighbours) cannot fall into three sheets: those more than the crease angle from v's own
 * (the second sheet's and any third's) all lie within a hair under half of it of the first
 * of them, so no two of them are the crease angle apart, and rm_junction_vertex's grouping
 * (nearest first, of at most ISM_RM_JUNCTION_RING of them) finds two sheets or fewer. Dot
 * products only, for the crease vertices rm_crease_slide.c asks about (cube, irrational box:
 * 2,344 asks were 23.6M instructions of the pass without it). */
static bool third_sheet_possible(const rm_pass *p, uint32_t v, const uint32_t *nb, int n)
{
    const rm_mesh *r = &p->r;
    if (rm_normal_zero(p, v))
        return true;
    const double *nv = p->normal + 3 * (size_t)v, *first = NULL;
    double crease = rm_crease_cos();
    double half = cos(0.49 * ISM_RM_CREASE_DEG * M_PI / 180); /* under half: past rounding */
    for (int i = 0; i < n; i++)
        for (uint32_t s = 0; s < r->count[nb[i]]; s++) {
            const uint32_t *c = r->m->tri + 3 * (size_t)rm_slot(r, nb[i], s);
            for (int k = 0; k < 3; k++) {
                if (c[k] == v || rm_normal_zero(p, c[k]))
                    continue;
                const double *nx = p->normal + 3 * (size_t)c[k];
                if (ism_dot3(nv, nx) >= crease)
                    continue; /* v's own sheet */
                if (!first)
                    first = nx;
                else if (!(ism_dot3(first, nx) >= half))
                    return true;
            }
        }
    return false;
}

/* rm_junction_vertex past its screen: v's n neighbours nb, the ring's sheets; *off gets v's
 * distance from the point as a share of its mean edge. */
static bool sheets_meet_at(const rm_pass *p, uint32_t v, const uint32_t *nb, int n, double *off)
{
    const rm_mesh *r = &p->r;
    uint32_t ring[ISM_RM_JUNCTION_RING];
    double dist[ISM_RM_JUNCTION_RING];
    int nr = 0;
    for (int i = 0; i < n; i++)
        for (uint32_t s = 0; s < r->count[nb[i]]; s++) {
            const uint32_t *c = r->m->tri + 3 * (size_t)rm_slot(r, nb[i], s);
            for (int k = 0; k < 3; k++)
                ring_add(p, v, c[k], ring, dist, &nr);
        }
    rm_sheets s = {.n = 0};
    double x[3], sum = 0;
    rm_sheets_add(p, &s, v);
    for (int i = 0; i < nr; i++)
        rm_sheets_add(p, &s, ring[i]);
    if (!rm_sheets_meet(p, &s, x))
        return false;
    double d = rm_dist(rm_pos(p, v), x);
    for (int i = 0; i < n; i++) {
        double e = rm_dist(rm_pos(p, nb[i]), x);
        if (!(d < e))
            return false; /* a neighbour is nearer the junction */
        sum += rm_dist(rm_pos(p, v), rm_pos(p, nb[i]));
    }
    *off = d / (sum / n);
    return d <= sum / n; /* the point within v's mean edge: the sheets meet at v */
}

/* v's neighbours into nb (how many: *n); false when v has too many triangles to ask. */
static bool neighbours(const rm_pass *p, uint32_t v, uint32_t *nb, int *n)
{
    if (p->r.count[v] > ISM_RM_MERGE_MAX_DEGREE)
        return false;
    *n = rm_merge_neighbours(&p->r, v, nb);
    return true;
}

/* Whether the sheets round v meet at v, with how far off (*off, of v's mean edge): the
 * neighbours, the third-sheet screen when asked, the sheets' meeting point. */
static bool junction_off(const rm_pass *p, uint32_t v, bool screened, double *off)
{
    uint32_t nb[2 * ISM_RM_MERGE_MAX_DEGREE];
    int n;
    return neighbours(p, v, nb, &n) && (!screened || third_sheet_possible(p, v, nb, n)) &&
           sheets_meet_at(p, v, nb, n, off);
}

bool rm_junction_vertex(const rm_pass *p, uint32_t v)
{
    double off;
    return junction_off(p, v, true, &off);
}

bool rm_junction_vertex_on(const rm_pass *p, uint32_t v)
{
    double off;
    return junction_off(p, v, true, &off) && off <= ISM_RM_JUNCTION_AT;
}

bool rm_junction_vertex_unscreened(const rm_pass *p, uint32_t v)
{
    double off;
    return junction_off(p, v, false, &off);
}
