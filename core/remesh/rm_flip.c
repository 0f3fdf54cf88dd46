/* rm_flip.c — Lawson flips toward Delaunay within manifold patches. The edge ab of triangles
 * (a, b, c) and (b, a, d) becomes cd when the angles at c and d sum above π (the Delaunay
 * test), and only when the flip keeps the mesh saying the same: both triangles carry one
 * label, ab is not locked, the quad is nearly flat (no crease folded), the new triangles face
 * the old way, cd is not already an edge, the smallest angle of the pair grows, and cd's
 * midpoint lies no farther from f = 0 than the bound (max_error, or ab's own distance). */
#include "core/remesh/rm_pass.h"

#include <math.h>

/* Largest bend between the two triangles of a flipped edge, before and after: a flip on a
 * quad bent more than this would move the surface the mesh describes (the polygoniser's
 * smooth parts bend a few degrees per edge; see ISM_RM_CREASE_DEG for creases). */
#define ISM_RM_FLIP_MAX_BEND_DEG 20.0
/* The Delaunay test asks for an angle sum this much above π (radians), so that the four
 * points of a circle (sum exactly π up to rounding) are never flipped back and forth. */
#define ISM_RM_FLIP_MARGIN 1e-9

typedef struct quad {
    uint32_t a, b, c, d, t1, t2;
} quad;

static const double *P(const rm_pass *p, uint32_t v) { return p->r.m->pos + 3 * v; }

static double dot3(const double *u, const double *v)
{
    return u[0] * v[0] + u[1] * v[1] + u[2] * v[2];
}

/* The quad around edge {a, b} when it is a free edge; false otherwise. */
static bool find_quad(const rm_pass *p, uint32_t a, uint32_t b, quad *q)
{
    const rm_mesh *r = &p->r;
    uint32_t t[2];
    int n;
    if (!rm_edge_triangles(r, a, b, t, &n))
        return false;
    if ((r->label && r->label[t[0]] != r->label[t[1]]) || rm_edge_locked(r, a, b))
        return false;
    const uint32_t *tri = r->m->tri;
    q->a = a;
    q->b = b;
    q->t1 = t[0];
    q->t2 = t[1];
    q->c = tri[3 * t[0] + (rm_corner(r->m, t[0], a) + 2) % 3];
    q->d = tri[3 * t[1] + (rm_corner(r->m, t[1], b) + 2) % 3];
    return q->c != q->d && q->c != a && q->c != b && q->d != a && q->d != b;
}

static bool edge_exists(const rm_mesh *r, uint32_t c, uint32_t d)
{
    for (uint32_t i = 0; i < r->count[c]; i++)
        if (rm_corner(r->m, r->vt[r->start[c] + i], d) >= 0)
            return true;
    return false;
}

/* A vertex keeps at least three triangles when free (two when locked: a boundary fan). */
static bool degree_allows(const rm_mesh *r, uint32_t v)
{
    return r->count[v] > (r->locked[v] ? 2u : 3u);
}

static bool bend_ok(const double *n1, double l1, const double *n2, double l2)
{
    return l1 > 0 && l2 > 0 && dot3(n1, n2) >= cos(ISM_RM_FLIP_MAX_BEND_DEG * M_PI / 180) * l1 * l2;
}

/* The geometric tests of a flip (the combinatorial ones passed). */
static bool flip_improves(rm_pass *p, const quad *q)
{
    const double *A = P(p, q->a), *B = P(p, q->b), *C = P(p, q->c), *D = P(p, q->d);
    if (rm_angle(C, A, B) + rm_angle(D, B, A) <= M_PI + ISM_RM_FLIP_MARGIN)
        return false;
    double n1[3], n2[3], m1[3], m2[3];
    double l1 = rm_cross(A, B, C, n1), l2 = rm_cross(B, A, D, n2);
    double k1 = rm_cross(A, D, C, m1), k2 = rm_cross(B, C, D, m2);
    double s[3] = {n1[0] + n2[0], n1[1] + n2[1], n1[2] + n2[2]};
    if (!bend_ok(n1, l1, n2, l2) || !bend_ok(m1, k1, m2, k2) || !(dot3(m1, s) > 0) ||
        !(dot3(m2, s) > 0))
        return false;
    double before = fmin(rm_min_angle(A, B, C), rm_min_angle(B, A, D));
    double after = fmin(rm_min_angle(A, D, C), rm_min_angle(B, C, D));
    if (!(after > before))
        return false;
    double mab[3], mcd[3];
    for (int k = 0; k < 3; k++) {
        mab[k] = 0.5 * (A[k] + B[k]);
        mcd[k] = 0.5 * (C[k] + D[k]);
    }
    return rm_distance(p, mcd) <= fmax(p->max_error, rm_distance(p, mab));
}

/* (a, b, c), (b, a, d) -> (a, d, c), (b, c, d): winding kept, incidence updated. */
static void do_flip(rm_pass *p, const quad *q)
{
    uint32_t *t1 = p->r.m->tri + 3 * q->t1, *t2 = p->r.m->tri + 3 * q->t2;
    t1[0] = q->a, t1[1] = q->d, t1[2] = q->c;
    t2[0] = q->b, t2[1] = q->c, t2[2] = q->d;
    rm_slot_remove(&p->r, q->a, q->t2);
    rm_slot_remove(&p->r, q->b, q->t1);
    rm_slot_add(&p->r, q->c, q->t2);
    rm_slot_add(&p->r, q->d, q->t1);
}

size_t rm_flip_sweep(rm_pass *p)
{
    const rm_mesh *r = &p->r;
    size_t flips = 0;
    for (size_t t = 0; t < r->m->ntris; t++)
        for (int k = 0; k < 3; k++) {
            uint32_t a = r->m->tri[3 * t + k], b = r->m->tri[3 * t + (k + 1) % 3];
            quad q;
            if (a > b || !find_quad(p, a, b, &q) || edge_exists(r, q.c, q.d) ||
                !rm_slot_room(r, q.c) || !rm_slot_room(r, q.d) || !degree_allows(r, a) ||
                !degree_allows(r, b) || !flip_improves(p, &q))
                continue;
            do_flip(p, &q);
            flips++;
            break; /* triangle t changed: its other edges are seen on the next sweep */
        }
    p->flips += flips;
    return flips;
}
