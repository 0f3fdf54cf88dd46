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

void rm_sheets_add(const rm_pass *p, rm_sheets *s, uint32_t v)
{
    if (rm_normal_zero(p, v))
        return;
    const double *n = p->normal + 3 * (size_t)v;
    double near = rm_crease_cos();
    int h = 0;
    while (h < s->n && !(ism_dot3(s->normal[h], n) >= near))
        h++;
    if (h == s->n && s->n < ISM_RM_COLLAPSE_MAX_DEGREE)
        s->d[s->n] = ism_dot3(n, rm_pos(p, v)), s->normal[s->n++] = n;
}

bool rm_sheets_meet(const rm_sheets *s, double x[3])
{
    const double *const *g = s->normal;
    if (s->n < 3)
        return false;
    double c12[3], c23[3], c31[3];
    ism_cross3(g[1], g[2], c23);
    ism_cross3(g[2], g[0], c31);
    ism_cross3(g[0], g[1], c12);
    double det = ism_dot3(g[0], c23);
    if (!(fabs(det) >= ISM_RM_JUNCTION_DET))
        return false;
    for (int k = 0; k < 3; k++)
        x[k] = (s->d[0] * c23[k] + s->d[1] * c31[k] + s->d[2] * c12[k]) / det;
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

/* rm_junction_vertex past its screen: v's n neighbours nb, the ring's sheets. */
static bool sheets_meet_at(const rm_pass *p, uint32_t v, const uint32_t *nb, int n)
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
    if (!rm_sheets_meet(&s, x))
        return false;
    double d = rm_dist(rm_pos(p, v), x);
    for (int i = 0; i < n; i++) {
        double e = rm_dist(rm_pos(p, nb[i]), x);
        if (!(d < e))
            return false; /* a neighbour is nearer the junction */
        sum += rm_dist(rm_pos(p, v), rm_pos(p, nb[i]));
    }
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

bool rm_junction_vertex(const rm_pass *p, uint32_t v)
{
    uint32_t nb[2 * ISM_RM_MERGE_MAX_DEGREE];
    int n;
    return neighbours(p, v, nb, &n) && third_sheet_possible(p, v, nb, n) &&
           sheets_meet_at(p, v, nb, n);
}

bool rm_junction_vertex_unscreened(const rm_pass *p, uint32_t v)
{
    uint32_t nb[2 * ISM_RM_MERGE_MAX_DEGREE];
    int n;
    return neighbours(p, v, nb, &n) && sheets_meet_at(p, v, nb, n);
}
