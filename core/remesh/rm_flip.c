/* rm_flip.c — Lawson flips toward Delaunay within manifold patches. The edge ab of triangles
 * (a, b, c) and (b, a, d) becomes cd when the angles at c and d sum above π (the Delaunay
 * test), and only when the flip keeps the mesh saying the same: both triangles carry one
 * label, ab is not locked, the quad is nearly flat (no crease folded), the new triangles face
 * the old way, cd is not already an edge, the smallest angle of the pair grows, cd's
 * midpoint lies no farther from f = 0 than the bound (max_error, or ab's own distance), and
 * the new centroids no farther than the old ones or the mesh's farthest before the pass. A
 * cap (an angle near 180°) has no normal to speak of: a bend too large is forgiven when one
 * of the old triangles is a cap (asked only then), and without max_error the bound is the
 * largest of the quad's five edges. */
#include "core/remesh/rm_bound.h"
#include "core/remesh/rm_cbound.h"
#include "core/remesh/rm_pass.h"
#include "core/util/u32_lists.h"
#include "core/util/vec3.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

/* Largest bend between the two triangles of a flipped edge, before and after: a flip on a
 * quad bent more than this would move the surface the mesh describes (the polygoniser's
 * smooth parts bend a few degrees per edge; see ISM_RM_CREASE_DEG for creases). */
#define ISM_RM_FLIP_MAX_BEND_DEG 20.0
/* The Delaunay test asks for sin(γ + δ) below minus this (γ + δ this far above π, in
 * radians), so that the four points of a circle (sum exactly π up to rounding) are never
 * flipped back and forth. */
#define ISM_RM_FLIP_MARGIN 1e-9

/* Flips one call may make, per triangle of the mesh: Lawson's procedure ends by itself in
 * the plane; on a curved mesh this bounds the work whatever the geometry does. */
#define ISM_RM_FLIPS_PER_TRIANGLE 4

typedef struct quad {
    uint32_t a, b, c, d, t1, t2;
    double cen[2][RM_CBOUND_REC]; /* what the test knew of (a, d, c) and (b, c, d)'s centroids
                         (rm_cbound.h: a point and the distance there), for the flip to keep */
} quad;

/* The quad around edge {a, b} when it is a free edge; false otherwise. */
static bool find_quad(const rm_pass *p, uint32_t a, uint32_t b, quad *q)
{
    const rm_mesh *r = &p->r;
    uint32_t t[2];
    int n;
    if (!rm_edge_triangles(r, a, b, t, &n))
        return false;
    if (rm_label(r, t[0]) != rm_label(r, t[1]) || rm_edge_locked(r, a, b))
        return false;
    const uint32_t *tri = r->m->tri;
    q->a = a;
    q->b = b;
    q->cen[0][3] = q->cen[1][3] = INFINITY;
    q->cen[0][4] = q->cen[1][4] = 0;
    q->t1 = t[0];
    q->t2 = t[1];
    /* the corner of each that is neither a nor b (the XOR of its three corners with a and b,
       whichever way round the triangle runs) */
    q->c = tri[3 * t[0]] ^ tri[3 * t[0] + 1] ^ tri[3 * t[0] + 2] ^ a ^ b;
    q->d = tri[3 * t[1]] ^ tri[3 * t[1] + 1] ^ tri[3 * t[1] + 2] ^ a ^ b;
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
    return l1 > 0 && l2 > 0 && ism_dot3(n1, n2) >= cos(ISM_RM_FLIP_MAX_BEND_DEG * M_PI / 180) * l1 * l2;
}

/* The dot product of the sides from C to A and to B: the cosine of the angle at C times
 * their lengths (the same bits with A and B swapped: each product commutes). */
static double corner_dot(const double *A, const double *B, const double *C)
{
    return ism_dot3((double[3]){A[0] - C[0], A[1] - C[1], A[2] - C[2]},
                    (double[3]){B[0] - C[0], B[1] - C[1], B[2] - C[2]});
}

/* The angles at c and d of the quad sum above π: sin(γ + δ) < 0 written with the sides'
 * cross and dot products (no arc tangents; both angles lie in [0, π]). */
static bool not_delaunay(const double *A, const double *B, const double *C, const double *D)
{
    double cc = corner_dot(A, B, C), cd = corner_dot(A, B, D);
    if (cc >= 0 && cd >= 0)
        return false; /* neither angle obtuse: the sum below is of non-negative products */
    double n[3], sc = rm_cross(C, A, B, n), sd = rm_cross(D, B, A, n);
    /* sin(γ + δ) |CA||CB||DA||DB| = sc cd + cc sd */
    double sum = sc * cd + cc * sd;
    if (!(sum < 0))
        return false; /* most edges: the margin's scale need not be known */
    double scale = sqrt((cc * cc + sc * sc) * (cd * cd + sd * sd));
    return sum < -ISM_RM_FLIP_MARGIN * scale;
}

/* The new triangles (A, D, C), (B, C, D) put no centroid farther from f = 0 than the mesh's
 * farthest before the pass or the old triangles' farthest. With q (the quad of a mesh
 * edge; NULL for one not made yet), a new centroid that what the old triangles know says
 * stays within centroid_bound is not measured (rm_cbound.h; as rm_centroids_stay: a
 * measured one beyond the bound decides alone); q keeps what is known of the new ones. */
static bool centroids_ok(rm_pass *p, const double *A, const double *B, const double *C,
                         const double *D, quad *q)
{
    const double *tri[2][3] = {{A, D, C}, {B, C, D}};
    double now = 0;
    for (int i = 0; i < 2; i++) {
        double m[3], *keep = q ? q->cen[i] : NULL;
        rm_centroid(tri[i][0], tri[i][1], tri[i][2], m);
        if (q && p->cen_ref) { /* the nearer bound of the two old triangles' */
            uint32_t from = rm_cbound_at(p, q->t1, m) <= rm_cbound_at(p, q->t2, m) ? q->t1 : q->t2;
            if (rm_cbound_within(p, from, m)) {
                memcpy(keep, p->cen_ref + RM_CBOUND_REC * (size_t)from, sizeof q->cen[i]);
                continue;
            }
        }
        double gn = 0, d = p->cen_ref ? rm_cbound_distance(p, m, &gn) : rm_distance(p, m);
        if (keep)
            memcpy(keep, m, sizeof m), keep[3] = d, keep[4] = gn;
        now = d > now ? d : now;
    }
    if (now <= p->centroid_bound)
        return true;
    double old[2], m[3];
    const double *was[2][3] = {{A, B, C}, {B, A, D}};
    for (int i = 0; i < 2; i++) {
        rm_centroid(was[i][0], was[i][1], was[i][2], m);
        old[i] = q ? rm_cbound_exact(p, i ? q->t2 : q->t1, m) : NAN;
        if (isnan(old[i]))
            old[i] = rm_distance(p, m);
    }
    return now <= fmax(old[0], old[1]);
}

/* The geometric tests of flipping AB to CD in (A, B, C), (B, A, D) (the combinatorial ones
 * and the Delaunay test passed); q as centroids_ok. */
static bool flip_improves_at(rm_pass *p, const double *A, const double *B, const double *C,
                             const double *D, quad *q)
{
    double n1[3], n2[3], m1[3], m2[3];
    double l1 = rm_cross(A, B, C, n1), l2 = rm_cross(B, A, D, n2);
    double k1 = rm_cross(A, D, C, m1), k2 = rm_cross(B, C, D, m2);
    double s[3] = {n1[0] + n2[0], n1[1] + n2[1], n1[2] + n2[2]};
    /* a cap is asked only where the bend fails, or for the bound without max_error */
    bool bent = !bend_ok(n1, l1, n2, l2);
    bool cap = (bent || !p->bounded) && (rm_is_cap(A, B, C) || rm_is_cap(B, A, D));
    if ((bent && !cap) || !bend_ok(m1, k1, m2, k2) || !(ism_dot3(m1, s) > 0) ||
        !(ism_dot3(m2, s) > 0))
        return false;
    double before = fmin(rm_min_sine(A, B, C), rm_min_sine(B, A, D));
    double after = fmin(rm_min_sine(A, D, C), rm_min_sine(B, C, D));
    if (!(after > before))
        return false;
    if (p->bounded) /* the simplification's rule: within max_error, measured */
        return rm_bound_edge(p, C, D) && rm_bound_triangle(p, A, D, C) &&
               rm_bound_triangle(p, B, C, D);
    double bound = fmax(p->max_error, rm_midpoint_distance(p, A, B));
    if (cap) /* ab is as good as c's detour: the quad's sides bound the new edge too */
        bound = fmax(fmax(bound, fmax(rm_midpoint_distance(p, A, C),
                                      rm_midpoint_distance(p, C, B))),
                     fmax(rm_midpoint_distance(p, B, D), rm_midpoint_distance(p, D, A)));
    return rm_midpoint_distance(p, C, D) <= bound && centroids_ok(p, A, B, C, D, q);
}

static bool flip_improves(rm_pass *p, quad *q)
{
    return flip_improves_at(p, rm_pos(p, q->a), rm_pos(p, q->b), rm_pos(p, q->c),
                            rm_pos(p, q->d), q);
}

bool rm_flip_would_pass(rm_pass *p, const double *A, const double *B, const double *C,
                        const double *D)
{
    return not_delaunay(A, B, C, D) && flip_improves_at(p, A, B, C, D, NULL);
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
    rm_shape_changed(p, q->t1);
    rm_shape_changed(p, q->t2);
    rm_cbound_set(p, q->t1, q->cen[0], q->cen[0][3], q->cen[0][4]);
    rm_cbound_set(p, q->t2, q->cen[1], q->cen[1][3], q->cen[1][4]);
    if (p->flipped)
        p->flipped[q->a] = p->flipped[q->b] = p->flipped[q->c] = p->flipped[q->d] = 1;
}

/* A stack of edges (vertex pairs) still to test. */
typedef struct edge_stack {
    uint32_t *e;
    size_t n, cap;
} edge_stack;

static bool push(edge_stack *s, uint32_t a, uint32_t b)
{
    if (s->n + 2 > s->cap) {
        size_t cap = s->cap ? 2 * s->cap : 1024;
        uint32_t *e = realloc(s->e, cap * sizeof *e);
        if (!e)
            return false;
        s->e = e;
        s->cap = cap;
    }
    s->e[s->n++] = a;
    s->e[s->n++] = b;
    return true;
}

/* Tests edge {a, b} and flips it when every test passes. A full slot at c or d is grown
 * (rm_slot_reserve) rather than taken as a reason not to flip: steiner-roman's 1e-3 box kept
 * 5 of its 11 needles beside the double lines only because a vertex there had used up its
 * slot's spare room. */
static bool try_flip(rm_pass *p, uint32_t a, uint32_t b, quad *q)
{
    rm_mesh *r = &p->r;
    if (!find_quad(p, a, b, q) || /* the Delaunay test first: most edges fail it, cheaply */
        !not_delaunay(rm_pos(p, q->a), rm_pos(p, q->b), rm_pos(p, q->c), rm_pos(p, q->d)) ||
        edge_exists(r, q->c, q->d) || !degree_allows(r, a) || !degree_allows(r, b) ||
        !flip_improves(p, q) || !rm_slot_reserve(r, q->c, 1) || !rm_slot_reserve(r, q->d, 1))
        return false; /* (out of memory growing a slot: that flip is not made) */
    do_flip(p, q);
    return true;
}

size_t rm_flip_active(rm_pass *p, bool *ok)
{
    return rm_flip_from(p, p->active, ok);
}

/* Triangle t's corners whose angle is not acute or right by corner_dot (obtuse, or NaN): bit
 * k for corner k, kept in rm_pass.obtuse while its shape holds (most triangles keep theirs
 * from one call of rm_flip_from to the next). */
static uint8_t obtuse_corners(const rm_pass *p, size_t t)
{
    if (p->obtuse && p->obtuse[t] != RM_OBTUSE_UNKNOWN)
        return p->obtuse[t];
    const uint32_t *v = p->r.m->tri + 3 * t;
    uint8_t bits = 0;
    for (int k = 0; k < 3; k++)
        if (!(corner_dot(rm_pos(p, v[k]), rm_pos(p, v[(k + 1) % 3]),
                         rm_pos(p, v[(k + 2) % 3])) >= 0))
            bits |= (uint8_t)(1u << k);
    if (p->obtuse)
        p->obtuse[t] = bits;
    return bits;
}

/* Edge {a, b} in set, the lists of ism_u32_lists keyed by the lower end (a handful of
 * entries a vertex at most), valued by the higher. */
static bool edge_add(ism_u32_lists *set, uint32_t a, uint32_t b)
{
    return ism_u32_lists_add(set, a < b ? a : b, a < b ? b : a);
}

/* The edges opposite a corner of a live triangle with a corner in near whose angle is not
 * acute or right (obtuse_corners) into set; false when out of memory or out of entry numbers
 * (set then freed). An edge whose angles opposite it, in both its triangles, are at most 90°
 * fails not_delaunay: sc cd + cc sd is a sum of products of non-negative numbers. On the
 * presets' meshes most are: the Delaunay test for an edge pushed first needs its quad found
 * (rm_edge_triangles).
 * (A sorted array and binary searches were 19% of the flips' instructions on the torus under
 * its default bound, the sort 6%; a hash set of edge keys, rebuilt each call, 13.1M of the
 * cube's 155M in its 0.37-cell box.) */
static bool obtuse_edges(const rm_pass *p, const uint8_t *near, ism_u32_lists *set)
{
    const ism_mesh *m = p->r.m;
    if (!ism_u32_lists_init(set, m->nverts))
        return false;
    for (size_t t = 0; t < m->ntris; t++) {
        const uint32_t *v = m->tri + 3 * t;
        if (!(near[v[0]] | near[v[1]] | near[v[2]]))
            continue;
        uint8_t bits = p->r.dead[t] ? 0 : obtuse_corners(p, t);
        for (int k = 0; bits && k < 3; k++)
            if ((bits >> k & 1) && !edge_add(set, v[k], v[(k + 1) % 3])) {
                ism_u32_lists_free(set);
                return false;
            }
    }
    return true;
}

/* The live triangles with a corner in seed, in order, into *list (how many: *n; NULL when
 * there are none), and the corners of those triangles into a new array: every triangle on an
 * edge of a seeded triangle has one of them. NULL when out of memory (*list then NULL too). */
static uint8_t *seeded_corners(const rm_pass *p, const uint8_t *seed, uint32_t **list,
                               size_t *n)
{
    const ism_mesh *m = p->r.m;
    uint8_t *near = calloc(m->nverts ? m->nverts : 1, 1);
    uint32_t *l = NULL;
    size_t cap = 0;
    *n = 0;
    for (size_t t = 0; near && t < m->ntris; t++) {
        const uint32_t *v = m->tri + 3 * t;
        if (p->r.dead[t] || !(seed[v[0]] | seed[v[1]] | seed[v[2]]))
            continue;
        near[v[0]] = near[v[1]] = near[v[2]] = 1;
        if (*n == cap) {
            cap = cap ? 2 * cap : 1024;
            uint32_t *grown = realloc(l, cap * sizeof *l);
            if (!grown) {
                free(near);
                near = NULL;
                break;
            }
            l = grown;
        }
        l[(*n)++] = (uint32_t)t;
    }
    if (!near)
        free(l), l = NULL;
    *list = l;
    return near;
}

/* Pushes the edges {v[k], v[k + 1]}, v[k] < v[k + 1], of triangle v, those in set only
 * when it is not NULL; false when out of memory. */
static bool push_edges(edge_stack *s, const uint32_t *v, const ism_u32_lists *set)
{
    static const int next[3] = {1, 2, 0};
    for (int k = 0; k < 3; k++) {
        uint32_t a = v[k], b = v[next[k]];
        if (a < b && (!set || ism_u32_lists_has(set, a, b)) && !push(s, a, b))
            return false;
    }
    return true;
}

size_t rm_flip_from(rm_pass *p, const uint8_t *seed, bool *ok)
{
    const ism_mesh *m = p->r.m;
    edge_stack s = {0};
    size_t flips = 0, limit = ISM_RM_FLIPS_PER_TRIANGLE * m->ntris, nseeded;
    ism_u32_lists obtuse;
    uint32_t *seeded;
    /* only the edges of seeded triangles are asked of the set, and both triangles on such an
       edge have a seeded triangle's corner (NULL, out of memory: every edge pushed) */
    uint8_t *near = seeded_corners(p, seed, &seeded, &nseeded);
    bool listed = near != NULL, known = listed && nseeded && obtuse_edges(p, near, &obtuse);
    free(near);
    *ok = true;
    if (listed) { /* (none seeded: nothing to push) */
        for (size_t i = 0; i < nseeded && *ok; i++)
            *ok = push_edges(&s, m->tri + 3 * (size_t)seeded[i], known ? &obtuse : NULL);
    } else {
        for (size_t t = 0; t < m->ntris && *ok; t++) {
            const uint32_t *v = m->tri + 3 * t;
            if (!p->r.dead[t] && (seed[v[0]] || seed[v[1]] || seed[v[2]]))
                *ok = push_edges(&s, v, NULL);
        }
    }
    free(seeded);
    if (known)
        ism_u32_lists_free(&obtuse);
    while (*ok && s.n && flips < limit) {
        uint32_t b = s.e[--s.n], a = s.e[--s.n];
        quad q;
        if (!try_flip(p, a, b, &q))
            continue;
        flips++;
        /* the quad's sides may now fail the test */
        *ok = push(&s, q.a, q.c) && push(&s, q.c, q.b) && push(&s, q.b, q.d) &&
              push(&s, q.d, q.a);
    }
    free(s.e);
    p->flips += flips;
    return flips;
}
