/* rm_locks.c — what the quality pass must not touch. An edge is free when it is an oriented
 * manifold edge (two triangles running opposite ways), its triangles carry one label, it is
 * not in the caller's locked list and it is no crease; a vertex is free when every edge at it
 * is free, its triangles form one closed fan, ∇f does not vanish there, it ends no segment of
 * the mesh (a one-dimensional part) and it is not at a given point. Everything else keeps its
 * place and its edges, except that a locked vertex crowding a neighbour along a crease or a
 * curve of zeros of ∇f may merge into it (rm_collapse.c, crease_merge_find). */
#include "core/remesh/rm_pass.h"
#include "core/util/vec3.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

/* Boundary vertices with more triangles than this are not slid (the fan walk keeps its
 * neighbours on the stack; the polygoniser's vertices have about 6). */
#define ISM_RM_SLIDE_MAX_DEGREE 32

static int cmp_u64(const void *a, const void *b)
{
    uint64_t x = *(const uint64_t *)a, y = *(const uint64_t *)b;
    return x < y ? -1 : x > y;
}

/* Normals n1 and n2 face opposite ways across ∇f at v; where ∇f vanishes (a singular
 * point: the conformance's fan around it, whose rim may fold back on itself) v has no say
 * and the edge's other end decides. */
static bool turned_at(const rm_pass *p, uint32_t v, const double *n1, const double *n2)
{
    if (rm_normal_zero(p, v))
        return true;
    const double *g = p->normal + 3 * v;
    return (ism_dot3(n1, g) > 0) != (ism_dot3(n2, g) > 0);
}

/* Edge {a, b} of triangles t1, t2 bends by more than the crease angle, and is no fold: a
 * fold (one triangle turned over against its neighbours, a polygoniser artefact) has its two
 * triangles facing opposite ways across ∇f at the edge's ends, a crease has both facing
 * ∇f's side. Where f's gradient cannot jump (may_crease false) there is no crease to keep:
 * a bend is curvature, and the curvature test read at the edge's ends can miss a ridge
 * narrower than the triangles (pretzel-genus2 under its default bound, its tube's end at
 * x = 0 bending 42°-54° per edge: 13-20 vertices locked on a smooth surface, 11.3° and 7.3°
 * left in the shifted boxes). */
static bool is_crease(const rm_pass *p, uint32_t a, uint32_t b, uint32_t t1, uint32_t t2,
                      rm_curvature_memo *memo)
{
    if (!p->may_crease)
        return false;
    const ism_mesh *m = p->r.m;
    double n1[3], n2[3];
    const double *P = m->pos;
    const uint32_t *u = m->tri + 3 * t1, *w = m->tri + 3 * t2;
    double l1 = rm_cross(P + 3 * u[0], P + 3 * u[1], P + 3 * u[2], n1);
    double l2 = rm_cross(P + 3 * w[0], P + 3 * w[1], P + 3 * w[2], n2);
    double cosine = ism_dot3(n1, n2) / (l1 * l2);
    if (!(cosine < rm_crease_cos()) ||
        rm_is_cap(P + 3 * u[0], P + 3 * u[1], P + 3 * u[2]) ||
        rm_is_cap(P + 3 * w[0], P + 3 * w[1], P + 3 * w[2]))
        return false; /* a cap's normal says nothing of a bend */
    if (turned_at(p, a, n1, n2) && turned_at(p, b, n1, n2))
        return false; /* a fold */
    double ab = rm_dist(P + 3 * a, P + 3 * b);
    return !(ab > 0 && rm_bend_is_curvature(p, a, b, acos(fmax(-1, cosine)), (l1 + l2) / ab,
                                            memo));
}

/* rm_edge_free for the oriented manifold edge {a, b} of triangles t[0], t[1]. */
static bool manifold_edge_free(const rm_pass *p, uint32_t a, uint32_t b, const uint32_t t[2],
                               rm_curvature_memo *memo)
{
    const rm_mesh *r = &p->r;
    if (rm_label(r, t[0]) != rm_label(r, t[1]))
        return false;
    return !rm_edge_locked(r, a, b) && !is_crease(p, a, b, t[0], t[1], memo);
}

bool rm_edge_free(const rm_pass *p, uint32_t a, uint32_t b)
{
    uint32_t t[2];
    int n;
    return rm_edge_triangles(&p->r, a, b, t, &n) && manifold_edge_free(p, a, b, t, NULL);
}

/* What one protection pass has found of each edge, by triangle side (side j of triangle t
 * runs from its corner j to corner j + 1): whether it is free and the triangle across it.
 * Both ends' fans walk every edge, and an edge's verdict is the same from either end (the
 * two normals, the ends and the direction across swap: every test is symmetric in them,
 * bit for bit); each is asked once. */
typedef struct edge_memo {
    uint8_t *state;   /* 3 per triangle: 0 not asked, 1 free, 2 not */
    uint32_t *across; /* 3 per triangle: the triangle across a free side */
} edge_memo;

enum { EDGE_UNASKED, EDGE_FREE, EDGE_HELD };

/* Every edge at v free, and the triangles one closed fan (walked across those edges). */
static bool fan_free(const rm_pass *p, uint32_t v, rm_curvature_memo *memo, edge_memo *em)
{
    const rm_mesh *r = &p->r;
    const uint32_t *tri = r->m->tri;
    uint32_t n = r->count[v];
    if (n < 3)
        return false;
    uint32_t t0 = r->vt[r->start[v]], t = t0, steps = 0;
    do {
        int k = rm_corner(r->m, t, v);
        uint32_t ab[2], prev = tri[3 * t + (k + 2) % 3];
        size_t side = 3 * (size_t)t + (size_t)(k + 2) % 3; /* prev -> v */
        int c;
        if (tri[3 * t + (k + 1) % 3] == v || prev == v)
            return false;
        if (em->state && em->state[side] != EDGE_UNASKED) {
            if (em->state[side] != EDGE_FREE)
                return false;
            t = em->across[side];
            continue;
        }
        bool manifold = rm_edge_triangles(r, v, prev, ab, &c);
        bool free = manifold && manifold_edge_free(p, v, prev, ab, memo);
        if (em->state) {
            em->state[side] = free ? EDGE_FREE : EDGE_HELD;
            if (manifold) { /* ab[0] runs v -> prev: its side from v's corner */
                size_t other = 3 * (size_t)ab[0] + (size_t)rm_corner(r->m, ab[0], v);
                em->state[other] = em->state[side];
                em->across[side] = ab[0];
                em->across[other] = t;
            }
        }
        if (!free)
            return false;
        t = ab[0];
    } while (t != t0 && ++steps <= n);
    return t == t0 && steps + 1 == n;
}

uint32_t rm_point_vertex(const rm_mesh *r, const double *x)
{
    uint32_t best = UINT32_MAX;
    double bd = INFINITY;
    for (size_t v = 0; v < r->m->nverts; v++) {
        double d = rm_dist(r->m->pos + 3 * v, x);
        if (r->count[v] && d < bd) {
            bd = d;
            best = (uint32_t)v;
        }
    }
    return best;
}

static bool copy_locked_edges(rm_mesh *r, const ism_remesh_options *o)
{
    r->locked_edges = malloc((o->nlocked_edges ? o->nlocked_edges : 1) * sizeof *r->locked_edges);
    if (!r->locked_edges)
        return false;
    for (size_t i = 0; i < o->nlocked_edges; i++)
        r->locked_edges[i] = rm_edge_key(o->locked_edges[2 * i], o->locked_edges[2 * i + 1]);
    r->nlocked_edges = o->nlocked_edges;
    qsort(r->locked_edges, r->nlocked_edges, sizeof *r->locked_edges, cmp_u64);
    return true;
}

/* Vertex v lies on the mesh's boundary in one open fan whose inner edges are all free, its
 * two boundary edges are not locked, and its boundary neighbours share one coordinate with it
 * exactly (a box face cut the surface there): the boundary curve is f = 0 in that plane, and
 * v may slide along it (rm_slide.c). */
static bool box_slidable(const rm_pass *p, uint32_t v)
{
    const rm_mesh *r = &p->r;
    const uint32_t *tri = r->m->tri;
    uint32_t nb[2 * ISM_RM_SLIDE_MAX_DEGREE], nnb = 0, ends[2], nend = 0;
    if (r->count[v] > ISM_RM_SLIDE_MAX_DEGREE)
        return false;
    for (uint32_t i = 0; i < r->count[v]; i++) { /* v's distinct neighbours */
        const uint32_t *t = tri + 3 * r->vt[r->start[v] + i];
        for (int k = 0; k < 3; k++) {
            uint32_t j = 0;
            while (j < nnb && nb[j] != t[k])
                j++;
            if (t[k] != v && j == nnb)
                nb[nnb++] = t[k];
        }
    }
    if (nnb != r->count[v] + 1) /* one open fan: one neighbour more than triangles */
        return false;
    for (uint32_t j = 0; j < nnb; j++) {
        uint32_t two[2];
        int n;
        bool manifold = rm_edge_triangles(r, v, nb[j], two, &n);
        if (n == 1 && nend < 2 && !rm_edge_locked(r, v, nb[j]))
            ends[nend++] = nb[j];
        else if (!manifold || !rm_edge_free(p, v, nb[j]))
            return false;
    }
    if (nend != 2)
        return false;
    const double *P = r->m->pos;
    for (int k = 0; k < 3; k++)
        if (P[3 * v + k] == P[3 * ends[0] + k] && P[3 * v + k] == P[3 * ends[1] + k])
            return true;
    return false;
}

void rm_lock_vertices(rm_pass *p, const ism_remesh_options *o, const uint8_t *only)
{
    rm_mesh *r = &p->r;
    rm_curvature_memo memo;
    rm_curvature_memo_open(&memo, r->m->nverts); /* without room: each bend evaluates */
    size_t sides = 3 * (r->m->ntris ? r->m->ntris : 1);
    edge_memo em = {calloc(sides, 1), malloc(sides * sizeof *em.across)};
    if (!em.state || !em.across) { /* without room: each edge is asked from both ends */
        free(em.state);
        em.state = NULL;
    }
    for (size_t v = 0; v < r->m->nverts; v++) {
        if (only && !only[v])
            continue; /* its fan and normal as they were: its protection too */
        bool vanishes = rm_normal_zero(p, (uint32_t)v);
        r->locked[v] = vanishes || !fan_free(p, (uint32_t)v, &memo, &em);
        p->slide[v] = !vanishes && r->locked[v] && r->count[v] && box_slidable(p, (uint32_t)v);
    }
    free(em.state);
    free(em.across);
    rm_curvature_memo_close(&memo);
    for (size_t s = 0; s < 2 * r->m->nsegs; s++)
        r->locked[r->m->seg[s]] = RM_PINNED, p->slide[r->m->seg[s]] = 0;
    for (size_t i = 0; i < o->nlocked_points; i++) {
        uint32_t v = rm_point_vertex(r, o->locked_points + 3 * i);
        if (v != UINT32_MAX)
            r->locked[v] = RM_PINNED, p->slide[v] = 0;
    }
}

bool rm_lock_features(rm_pass *p, const ism_remesh_options *o)
{
    if (!copy_locked_edges(&p->r, o))
        return false;
    rm_lock_vertices(p, o, NULL);
    return true;
}
