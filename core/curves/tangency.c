/* tangency.c — tangency points made mesh vertices before g_k cuts the mesh, so the cut meets
 * there whatever the mesh: seeds from the mesh, points from the equations.
 *
 * Seeds: a vertex where g_k has a discrete saddle (the values of its link go up and down
 * round it at least twice) near g_k = 0, and a vertex of an earlier curve's chain where g_k
 * has a discrete extremum along the chain near 0. From each seed Newton on the Lagrange
 * system (critical.c) finds the critical point of g_k on the surface, or on the earlier
 * curve; where g_k is 0 there (within the curve precision) it is a tangency and becomes a
 * vertex on which g_k is taken as exactly 0:
 *   - on the surface (a node of the curve), the vertex of the seed's star nearest the point
 *     is moved onto it, the nearest whose triangles keep their orientation and whose link's
 *     signs of g_k change at least four times (both branches of the node leave it), else
 *     the nearest that can move, its branches then followed out of its star (node.c);
 *   - on an earlier curve, the chain edge it lies on is split at it (or the chain vertex
 *     moved onto it when it is that close), a crossing of the two curves. */
#include "core/curves/critical.h"
#include "core/curves/cut_internal.h"
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include "core/util/grow.h"
#include "core/util/vec3.h"

#define NONE CUT_NONE
/* A seed's |g_k| may be at most this many times the largest difference of g_k to its
 * neighbours: a critical value of 0 lies within about a ring of a vertex whose value is
 * that small (at a quadratic critical point the nearest vertex holds at most a quarter of
 * the neighbours' differences). */
#define TANG_SEED_SPAN 4.0
/* Newton may move a seed at most this many of its longest edges. */
#define TANG_MAX_MOVE_EDGES 2.0
/* s->tol is a thousandth of the curve precision (curves.c); a critical point whose g_k
 * lies within the precision is a tangency. */
#define TANG_ACCEPT_TOLS 1e3
/* At most this many tangencies per function: each costs passes over the triangles; beyond
 * it g_k touches the surface along whole curves (degenerate), and the cut goes on without. */
#define TANG_MAX_PER_FN 64
/* A moved vertex's triangles must keep their normals within 60° of where they were. */
#define TANG_MIN_COS 0.5
/* A tangency this close (in edge fractions) to a chain vertex moves that vertex onto it
 * rather than splitting the edge into a sliver. */
#define TANG_CHAIN_SNAP 0.1
/* Seeds tried per function (Newton from each): bounds the cost on a mesh full of noise. */
#define TANG_MAX_SEEDS 4096

typedef struct tangent {
    double p[3];
    uint32_t seed; /* mesh vertex */
    uint32_t j;    /* the earlier curve, NONE on the surface */
} tangent;

typedef struct tang_state {
    cut_state *s;
    size_t k;
    tangent t[TANG_MAX_PER_FN];
    size_t n;
    size_t seeds;
} tang_state;

/* Whether w's value is above v's (ties broken by index: a symbolic perturbation). */
static bool above(const double *g, uint32_t v, uint32_t w)
{
    return g[w] > g[v] || (g[w] == g[v] && w > v);
}

/* Newton from the seed vertex v (on curve j or on the surface); the point kept when it is a
 * new tangency. */
static void try_seed(tang_state *ts, uint32_t v, uint32_t j)
{
    cut_state *s = ts->s;
    if (ts->n == TANG_MAX_PER_FN || ts->seeds++ == TANG_MAX_SEEDS)
        return;
    double p[3], dist, r = s->reach[v];
    memcpy(p, s->m->pos + 3 * (size_t)v, sizeof p);
    size_t jj = j == NONE ? ISM_CUT_NO_CURVE : j;
    if (!ism_cut_critical(s->ev, ts->k, jj, s->tol, TANG_MAX_MOVE_EDGES * r,
                          CUT_FD_STEP_REL * r, p, &dist) ||
        !(dist <= TANG_ACCEPT_TOLS * s->tol))
        return;
    double same = TANG_ACCEPT_TOLS * s->tol;
    for (size_t i = 0; i < ts->n; i++)
        if (ism_sqdist3(ts->t[i].p, p) <= same * same)
            return;
    ts->t[ts->n++] = (tangent){{p[0], p[1], p[2]}, v, j};
}

bool cut_on_no_other(const cut_state *s, uint32_t v, size_t k)
{
    uint32_t c = cut_vcurve_of(s, v);
    return c == NONE || c == (uint32_t)k;
}

/* Discrete saddles of g_k near 0 among the corners of the triangles the curve crosses or
 * touches (near 1: a node's nearest vertex is one), on no other curve. */
static void surface_seeds(tang_state *ts)
{
    cut_state *s = ts->s;
    const double *g = s->gv;
    cut_vscratch *vs = s->vs;
    for (size_t i0 = 0; i0 < s->nstars; i0++) { /* the stars of the curve's corners */
        const uint32_t *tv = s->m->tri + 3 * (size_t)s->stars[i0];
        for (int i = 0; i < 3; i++) {
            uint32_t v = tv[i], u = tv[(i + 1) % 3], w = tv[(i + 2) % 3];
            if (s->near[v] != 1)
                continue;
            if (above(g, v, u) != above(g, v, w) && vs[v].changes < UINT8_MAX)
                vs[v].changes++;
            vs[v].spread = fmax(vs[v].spread, fmax(fabs(g[u] - g[v]), fabs(g[w] - g[v])));
        }
    }
    for (size_t i = 0; i < s->n_near; i++) {
        uint32_t v = s->near_list[i];
        if (s->near[v] == 1 && vs[v].changes >= 4 && fabs(g[v]) <= TANG_SEED_SPAN * vs[v].spread &&
            cut_on_no_other(s, v, ts->k))
            try_seed(ts, v, NONE);
    }
}

/* Discrete extrema of g_k near 0 along the chains of earlier curves: corners of the
 * triangles the curve crosses or touches with two cut edges, both of one function, both
 * neighbours above (or both below). */
static void chain_seeds(tang_state *ts)
{
    cut_state *s = ts->s;
    const ism_cut *c = s->c;
    const double *g = s->gv;
    cut_vscratch *vs = s->vs;
    for (size_t i = 0; i < s->n_near; i++) /* the seeds' spread counts along chains only */
        vs[s->near_list[i]].spread = 0;
    for (size_t i = 0; i < s->n_near; i++) { /* the cut edges at the curve's corners */
        uint32_t v = s->near_list[i];
        if (s->near[v] != 1 || v >= s->cap_ehead)
            continue;
        for (uint32_t end = s->ehead[v]; end != NONE; end = s->enext[end]) {
            const ism_cut_edge *e = &c->edges[end / 2];
            if (e->fn == NONE || s->ev->fns[e->fn].kind == ISM_CUT_CREASE)
                continue; /* a crease's g depends on the edge: not seeded */
            uint32_t w = end & 1 ? e->a : e->b;
            cut_sign_of(s, w); /* its g (w may lie outside the listed triangles) */
            if (vs[v].fn && vs[v].fn != e->fn + 1)
                vs[v].deg = UINT8_MAX; /* two curves meet here: not a seed */
            vs[v].fn = e->fn + 1;
            if (vs[v].deg < 2)
                vs[v].nbr[vs[v].deg] = w;
            if (vs[v].deg < UINT8_MAX)
                vs[v].deg++;
            vs[v].up += above(g, v, w);
            vs[v].spread = fmax(vs[v].spread, fabs(g[w] - g[v]));
        }
    }
    for (size_t i = 0; i < s->n_near; i++) {
        uint32_t v = s->near_list[i];
        if (vs[v].deg == 2 && vs[v].up != 1 && fabs(g[v]) <= TANG_SEED_SPAN * vs[v].spread)
            try_seed(ts, v, vs[v].fn - 1);
    }
}

bool cut_ring_triangles(const ism_mesh *m, uint32_t v, uint32_t **out, size_t *n)
{
    uint8_t *mark = calloc(m->nverts + 1, 1);
    if (!mark)
        return false;
    mark[v] = 1;
    for (size_t t = 0; t < m->ntris; t++) {
        const uint32_t *tv = m->tri + 3 * t;
        if (tv[0] == v || tv[1] == v || tv[2] == v)
            mark[tv[0]] = mark[tv[1]] = mark[tv[2]] = 2;
    }
    size_t cap = 0;
    *n = 0;
    bool ok = true;
    for (size_t t = 0; ok && t < m->ntris; t++) {
        const uint32_t *tv = m->tri + 3 * t;
        if (!mark[tv[0]] && !mark[tv[1]] && !mark[tv[2]])
            continue;
        ok = ism_grow((void **)out, &cap, *n + 1, sizeof **out, CUT_FIRST);
        if (ok)
            (*out)[(*n)++] = (uint32_t)t;
    }
    free(mark);
    return ok;
}

void cut_tri_normal(const ism_mesh *m, const uint32_t *tv, uint32_t moved, const double *p,
                    double n[3])
{
    const double *q[3];
    for (int i = 0; i < 3; i++)
        q[i] = tv[i] == moved ? p : m->pos + 3 * (size_t)tv[i];
    ism_tri_cross3(q[0], q[1], q[2], n);
}

bool cut_can_move(cut_state *s, const uint32_t *tris, size_t nt, uint32_t u,
                  const double p[3], bool need_node, uint32_t skip)
{
    const ism_mesh *m = s->m;
    int changes = 0;
    for (size_t i = 0; i < nt; i++) {
        const uint32_t *tv = m->tri + 3 * (size_t)tris[i];
        int at = tv[0] == u ? 0 : tv[1] == u ? 1 : tv[2] == u ? 2 : -1;
        if (at < 0 || tv[0] == skip || tv[1] == skip || tv[2] == skip)
            continue;
        double a[3], b[3];
        cut_tri_normal(m, tv, NONE, NULL, a);
        cut_tri_normal(m, tv, u, p, b);
        double ab = a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
        if (!(ab > TANG_MIN_COS * sqrt(ism_sqdist3(a, (double[3]){0, 0, 0}) *
                                       ism_sqdist3(b, (double[3]){0, 0, 0}))))
            return false;
        changes += cut_sign_of(s, tv[(at + 1) % 3]) * cut_sign_of(s, tv[(at + 2) % 3]) < 0;
    }
    return !need_node || changes >= 4;
}

bool cut_move_vertex(cut_state *s, size_t k, uint32_t u, const double p[3],
                     const uint32_t *tris, size_t nt)
{
    float nrm[3];
    cut_normal_at(s, p, s->m->normal + 3 * (size_t)u, nrm);
    memcpy(s->m->pos + 3 * (size_t)u, p, 3 * sizeof *p);
    memcpy(s->m->normal + 3 * (size_t)u, nrm, sizeof nrm);
    cut_on_curve_now(s, u);
    for (size_t i = 0; i < nt; i++) {
        const uint32_t *tv = s->m->tri + 3 * (size_t)tris[i];
        if (tv[0] == u || tv[1] == u || tv[2] == u)
            cut_cells_grow(s, tris[i]);
    }
    s->edits++;
    return cut_set_vcurve(s, u, (uint32_t)k);
}

typedef struct candidate {
    double d2;
    uint32_t v;
} candidate;

static int cmp_candidate(const void *x, const void *y)
{
    const candidate *a = x, *b = y;
    if (a->d2 != b->d2)
        return a->d2 < b->d2 ? -1 : 1;
    return (a->v > b->v) - (a->v < b->v);
}

/* A node on the surface: the nearest vertex of the seed's star whose link already shows
 * both branches (its signs change four times) is moved onto it; failing that the nearest
 * that can move, and its star split where the branches leave it. */
static bool place_on_surface(cut_state *s, size_t k, const tangent *t)
{
    uint32_t *tris = NULL;
    size_t nt = 0, nc = 0;
    if (!cut_ring_triangles(s->m, t->seed, &tris, &nt))
        return false;
    candidate *cand = malloc((3 * nt + 1) * sizeof *cand);
    bool ok = cand != NULL;
    for (size_t i = 0; ok && i < nt; i++) {
        const uint32_t *tv = s->m->tri + 3 * (size_t)tris[i];
        if (tv[0] != t->seed && tv[1] != t->seed && tv[2] != t->seed)
            continue;
        for (int c = 0; c < 3; c++)
            cand[nc++] = (candidate){ism_sqdist3(s->m->pos + 3 * (size_t)tv[c], t->p), tv[c]};
    }
    if (ok)
        qsort(cand, nc, sizeof *cand, cmp_candidate);
    uint32_t chosen = NONE;
    for (int node = 1; ok && node >= 0 && chosen == NONE; node--)
        for (size_t i = 0; i < nc && chosen == NONE; i++) {
            if ((i && cand[i].v == cand[i - 1].v) || !cut_on_no_other(s, cand[i].v, k))
                continue;
            if (cut_can_move(s, tris, nt, cand[i].v, t->p, node, NONE))
                chosen = cand[i].v;
        }
    bool node = chosen != NONE && cut_can_move(s, tris, nt, chosen, t->p, true, NONE);
    free(cand);
    ok = ok && (chosen == NONE || cut_move_vertex(s, k, chosen, t->p, tris, nt));
    free(tris);
    if (!ok || chosen == NONE)
        return ok; /* no vertex can take it: the cut goes on as the mesh allows */
    return node || cut_node_branches(s, k, chosen, s->reach[t->seed]);
}

bool cut_split_triangles_at(cut_state *s, uint32_t a, uint32_t b, uint32_t x)
{
    ism_mesh *m = s->m;
    size_t nt = m->ntris;
    for (size_t t = 0; t < nt; t++) {
        uint32_t *tv = m->tri + 3 * t;
        for (int i = 0; i < 3; i++) {
            uint32_t u = tv[i], w = tv[(i + 1) % 3], o = tv[(i + 2) % 3];
            if (!((u == a && w == b) || (u == b && w == a)))
                continue;
            tv[(i + 1) % 3] = x; /* (u, x, o) in place, (x, w, o) appended */
            cut_cells_grow(s, t);
            s->from = s->parent[t];
            if (!cut_add_triangle(s, x, w, o))
                return false;
            tv = m->tri + 3 * t; /* the array may have moved */
            break;
        }
    }
    s->edits++;
    return true;
}

/* A touching crossing with the earlier curve j: its chain edge from the seed split at the
 * point, or a chain vertex moved onto it when it lies that close. */
static bool place_on_curve(tang_state *ts, const tangent *t)
{
    cut_state *s = ts->s;
    ism_mesh *m = s->m;
    uint32_t v = t->seed, w = NONE;
    double best = -INFINITY, tw = 0;
    for (int i = 0; i < 2; i++) { /* the neighbour on whose side the point lies */
        uint32_t u = s->vs[v].nbr[i];
        const double *a = m->pos + 3 * (size_t)v, *b = m->pos + 3 * (size_t)u;
        double d[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]}, q = 0, l2 = 0;
        for (int c = 0; c < 3; c++) {
            q += (t->p[c] - a[c]) * d[c];
            l2 += d[c] * d[c];
        }
        double par = l2 > 0 ? q / l2 : 0;
        if (par > best) {
            best = par;
            w = u;
            tw = par;
        }
    }
    uint32_t snap = tw <= TANG_CHAIN_SNAP ? v : tw >= 1 - TANG_CHAIN_SNAP ? w : NONE;
    if (snap != NONE) {
        if (cut_vcurve_of(s, snap) != t->j)
            return true;
        uint32_t *tris = NULL;
        size_t nt = 0;
        if (!cut_ring_triangles(m, snap, &tris, &nt))
            return false;
        bool ok = !cut_can_move(s, tris, nt, snap, t->p, false, NONE) ||
                  cut_move_vertex(s, ts->k, snap, t->p, tris, nt);
        free(tris);
        return ok;
    }
    float nrm[3];
    cut_normal_at(s, t->p, m->normal + 3 * (size_t)v, nrm);
    uint32_t x = ism_mesh_add_vertex(m, t->p, nrm);
    if (x == NONE || !cut_grow_vertex_arrays(s))
        return false;
    cut_on_curve_now(s, x);
    s->reach[x] = s->reach[v];
    return cut_set_vcurve(s, x, t->j) && cut_split_cut_edge(s, v, w, x, t->j) &&
           cut_split_triangles_at(s, v, w, x);
}

bool cut_tangencies(cut_state *s, size_t k)
{
    tang_state ts = {.s = s, .k = k};
    surface_seeds(&ts);
    chain_seeds(&ts);
    bool ok = true;
    for (size_t i = 0; ok && i < ts.n; i++)
        ok = ts.t[i].j == NONE ? place_on_surface(s, k, &ts.t[i]) : place_on_curve(&ts, &ts.t[i]);
    return ok;
}
