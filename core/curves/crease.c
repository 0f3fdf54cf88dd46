/* crease.c — cutting the mesh along the creases of a CSG function f. Each vertex is labelled
 * with f's branch there (branches.h); a mesh edge whose ends take branches A and B holds a
 * crease point, put on f_A = 0 and f_B = 0 by Newton from the crossing of f_A − f_B on the
 * edge (shared by both triangles of the edge). A triangle with two branches is split like a
 * sign change (cut.c); one with three holds a triple point f_A = f_B = f_C = 0 (a corner of
 * the CSG solid, Newton on the 3 × 3 system from its centroid) and is fanned from it:
 *
 *            A                the three crease points on its edges joined to the triple
 *           / \               point T: six triangles, three crease edges, each triangle
 *        pab---pca            on one branch
 *         / \ / \
 *        /   T   \
 *       B----pbc--C
 *
 * Every crease vertex lies on both branches' zero sets, so the mesh conforms: no edge
 * crosses the crease, and each crease edge records its two branches (the normals of its
 * sides, the later curves' Newton on it).
 *
 * A vertex where f ties (no branch: the polygoniser put it on the crease, as its sharp-
 * feature vertices are) is a crease point already: its edges are never split; a triangle
 * (T, A, B) is split from T to the crease point of A-B, and an edge between two such vertices
 * is a crease edge when the triangles on its two sides take different branches. (Kept whole,
 * such triangles left T-junctions against their split neighbours: the crack that sent
 * three balls to the fallback cut, 420 triangles at the default depth.) */
#include "core/curves/branches.h"
#include "core/curves/crease_label.h"
#include "core/curves/crease_micro.h"
#include "core/curves/crease_snap.h"
#include "core/curves/crease_weld.h"
#include "core/curves/cut_internal.h"
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include "core/util/grow.h"
#include "core/util/vec3.h"

#define NONE CUT_NONE
/* Newton may move a crease point at most this many lengths of its edge (the polygoniser's
 * vertices near a crease may lie that far off the surface). */
#define CREASE_MAX_MOVE_EDGES 2.0
/* Passes of putting crease points back in order along their chain (each pass fixes the
 * points whose neighbours lie on one side of them; one or two suffice). */
#define CREASE_ORDER_PASSES 3
/* Triple points of the same branches closer than this × the Newton tolerance are one. */
#define CREASE_SAME_TRIPLE 1e3

typedef struct triple {
    double p[3];
    uint32_t set[3]; /* its branches, sorted */
    uint32_t v;
} triple;

typedef struct crease_state {
    cut_state *s;
    ism_branches *b;
    uint32_t k;
    uint32_t *label;  /* per vertex of the mesh before the cut */
    triple *tp;
    size_t ntp, cap_tp;
    ism_key_map tie_edge; /* an edge between two tie vertices -> index into tie_side */
    uint32_t *tie_side;   /* the branch of the first triangle seen on that edge */
    size_t cap_tie;
} crease_state;

/* f_A − f_B at p. */
static double branch_gap(crease_state *cs, uint32_t A, uint32_t B, const double p[3])
{
    double g[3];
    return ism_branches_gradient(cs->b, A, p, g) - ism_branches_gradient(cs->b, B, p, g);
}

typedef struct gap_of {
    crease_state *cs;
    uint32_t A, B;
} gap_of;

static double gap_at(void *ctx, const double p[3])
{
    gap_of *g = ctx;
    return branch_gap(g->cs, g->A, g->B, p);
}

/* A new crease vertex at p (normal ∇f as it points there). NONE when out of memory. */
static uint32_t new_vertex(crease_state *cs, const double p[3])
{
    cut_state *s = cs->s;
    float nrm[3];
    cut_normal_at(s, p, NULL, nrm);
    uint32_t v = ism_mesh_add_vertex(s->m, p, nrm);
    return v != NONE && cut_set_vcurve(s, v, cs->k) ? v : NONE;
}

/* The crease point on edge u-w (branches label[u] ≠ label[w]), made once per edge. */
static uint32_t crease_vertex(crease_state *cs, uint32_t u, uint32_t w)
{
    cut_state *s = cs->s;
    uint32_t i, had;
    if (!cut_split_slot(s, u, w, &i, &had))
        return NONE;
    if (had != NONE)
        return had;
    uint32_t A = cs->label[u], B = cs->label[w];
    const double *a = s->m->pos + 3 * (size_t)u, *b = s->m->pos + 3 * (size_t)w;
    double ga = branch_gap(cs, A, B, a), gb = branch_gap(cs, A, B, b);
    double t = (ga < 0) != (gb < 0) ? ga / (ga - gb) : 0.5, p[3];
    for (int c = 0; c < 3; c++)
        p[c] = a[c] + t * (b[c] - a[c]);
    double len = fmax(sqrt(ism_sqdist3(a, b)), fmax(s->reach[u], s->reach[w]));
    size_t ks[1] = {B};
    double max_move = CREASE_MAX_MOVE_EDGES * len, plane[4];
    double n[3];
    for (int c = 0; c < 3; c++)
        n[c] = (double)s->m->normal[3 * (size_t)u + c] + s->m->normal[3 * (size_t)w + c];
    bool across = ism_cut_plane_along(a, b, n, p, plane);
    if (!ism_branches_refine(cs->b, A, ks, 1, across ? plane : NULL, s->tol, max_move, p)) {
        bool again = (ga < 0) != (gb < 0);
        if (again)
            cut_bisect(gap_at, &(gap_of){cs, A, B}, a, b, ga, p);
        if (!again ||
            !ism_branches_refine(cs->b, A, ks, 1, across ? plane : NULL, s->tol, max_move, p))
            s->c->unrefined++;
    }
    uint32_t v = new_vertex(cs, p);
    if (v != NONE)
        s->split_v[i] = v;
    return v;
}

static void sort3(uint32_t x[3])
{
    for (int i = 0; i < 3; i++)
        for (int j = i + 1; j < 3; j++)
            if (x[j] < x[i]) {
                uint32_t t = x[i];
                x[i] = x[j];
                x[j] = t;
            }
}

/* The triple point of the branches of triangle t (one vertex per point). */
static uint32_t triple_vertex(crease_state *cs, const uint32_t t[3])
{
    cut_state *s = cs->s;
    double p[3] = {0, 0, 0}, reach = 0;
    for (int i = 0; i < 3; i++) {
        for (int c = 0; c < 3; c++)
            p[c] += s->m->pos[3 * (size_t)t[i] + c] / 3;
        reach = fmax(reach, s->reach[t[i]]);
    }
    uint32_t set[3] = {cs->label[t[0]], cs->label[t[1]], cs->label[t[2]]};
    size_t ks[2] = {set[1], set[2]};
    if (!ism_branches_refine(cs->b, set[0], ks, 2, NULL, s->tol, CREASE_MAX_MOVE_EDGES * reach,
                             p))
        s->c->unrefined++;
    sort3(set);
    double same = CREASE_SAME_TRIPLE * s->tol;
    for (size_t i = 0; i < cs->ntp; i++)
        if (!memcmp(cs->tp[i].set, set, sizeof set) && ism_sqdist3(cs->tp[i].p, p) <= same * same)
            return cs->tp[i].v;
    if (!ism_grow((void **)&cs->tp, &cs->cap_tp, cs->ntp + 1, sizeof *cs->tp, CUT_FIRST))
        return NONE;
    uint32_t v = new_vertex(cs, p);
    cs->tp[cs->ntp++] = (triple){{p[0], p[1], p[2]}, {set[0], set[1], set[2]}, v};
    return v;
}

/* Records crease edge a-b between branches A and B (its ends noted on the crease: a tie
 * vertex was not yet). */
static bool crease_edge(crease_state *cs, uint32_t a, uint32_t b, uint32_t A, uint32_t B)
{
    uint32_t br[2] = {A, B};
    return cut_set_vcurve(cs->s, a, cs->k) && cut_set_vcurve(cs->s, b, cs->k) &&
           cut_add_cut_edge(cs->s, a, b, cs->k) && cut_set_branches(cs->s, a, b, br);
}

/* A triangle of three branches fanned from its triple point. */
static bool split_three(crease_state *cs, const uint32_t t[3])
{
    uint32_t T = triple_vertex(cs, t), e[3];
    if (T == NONE)
        return false;
    for (int i = 0; i < 3; i++) {
        uint32_t a = t[i], b = t[(i + 1) % 3];
        if ((e[i] = crease_vertex(cs, a, b)) == NONE ||
            !crease_edge(cs, T, e[i], cs->label[a], cs->label[b]))
            return false;
    }
    for (int i = 0; i < 3; i++)
        if (!cut_add_triangle(cs->s, t[i], e[i], T) ||
            !cut_add_triangle(cs->s, e[i], t[(i + 1) % 3], T))
            return false;
    return true;
}

/* Edge a-b between two tie vertices, seen from a triangle on branch A: a crease edge once
 * the other side is seen on another branch. */
static bool tie_edge_side(crease_state *cs, uint32_t a, uint32_t b, uint32_t A)
{
    bool added;
    uint32_t i = cut_edge_slot(&cs->tie_edge, a, b, (void **)&cs->tie_side, &cs->cap_tie,
                               sizeof *cs->tie_side, &added);
    if (i == CUT_NONE)
        return false;
    if (added) {
        cs->tie_side[i] = A;
        return true;
    }
    return cs->tie_side[i] == A || crease_edge(cs, a, b, cs->tie_side[i], A);
}

/* The branch at triangle t's centroid (ISM_BRANCH_NONE where f ties there too). */
static bool centroid_branch(crease_state *cs, const uint32_t t[3], uint32_t *A)
{
    double c[3] = {0, 0, 0};
    for (int i = 0; i < 3; i++)
        for (int k = 0; k < 3; k++)
            c[k] += cs->s->m->pos[3 * (size_t)t[i] + k] / 3;
    return ism_branches_at(cs->b, c, A);
}

/* A triangle with one or more tie vertices (l[i] ISM_BRANCH_NONE). */
static bool split_tie_triangle(crease_state *cs, const uint32_t t[3], const uint32_t l[3])
{
    int ties = 0, at = 0;
    for (int i = 0; i < 3; i++)
        if (l[i] == ISM_BRANCH_NONE) {
            ties++;
            at = i;
        }
    if (ties == 2) { /* the edge opposite the one labelled corner */
        int x = l[0] != ISM_BRANCH_NONE ? 0 : l[1] != ISM_BRANCH_NONE ? 1 : 2;
        if (!tie_edge_side(cs, t[(x + 1) % 3], t[(x + 2) % 3], l[x]))
            return false;
    }
    if (ties == 3) { /* three corners on the crease: its side is its middle's */
        uint32_t A;
        if (!centroid_branch(cs, t, &A))
            return false;
        for (int i = 0; A != ISM_BRANCH_NONE && i < 3; i++)
            if (!tie_edge_side(cs, t[i], t[(i + 1) % 3], A))
                return false;
    }
    uint32_t T = t[at], u = t[(at + 1) % 3], w = t[(at + 2) % 3];
    uint32_t A = cs->label[u], B = cs->label[w];
    if (ties != 1 || A == B)
        return cut_add_triangle(cs->s, t[0], t[1], t[2]);
    uint32_t p = crease_vertex(cs, u, w);
    return p != NONE && crease_edge(cs, T, p, A, B) && cut_add_triangle(cs->s, T, u, p) &&
           cut_add_triangle(cs->s, T, p, w);
}

static bool split_crease_triangle(crease_state *cs, const uint32_t t[3])
{
    uint32_t l[3] = {cs->label[t[0]], cs->label[t[1]], cs->label[t[2]]};
    if (l[0] == ISM_BRANCH_NONE || l[1] == ISM_BRANCH_NONE || l[2] == ISM_BRANCH_NONE)
        return split_tie_triangle(cs, t, l);
    if (l[0] == l[1] && l[1] == l[2])
        return cut_add_triangle(cs->s, t[0], t[1], t[2]);
    if (l[0] != l[1] && l[1] != l[2] && l[2] != l[0])
        return split_three(cs, t);
    for (int i = 0; i < 3; i++) /* the lone corner on its branch */
        if (l[i] != l[(i + 1) % 3] && l[i] != l[(i + 2) % 3]) {
            uint32_t c = t[i], u = t[(i + 1) % 3], w = t[(i + 2) % 3];
            uint32_t p = crease_vertex(cs, c, u), q = crease_vertex(cs, c, w);
            return p != NONE && q != NONE && crease_edge(cs, p, q, l[i], cs->label[u]) &&
                   cut_emit_lone(cs->s, c, u, w, p, q);
        }
    return false;
}

/* Whether v lies strictly between a and b along a-b. */
static bool between(const double *a, const double *v, const double *b)
{
    double x = 0, y = 0;
    for (int c = 0; c < 3; c++) {
        x += (v[c] - a[c]) * (b[c] - a[c]);
        y += (b[c] - v[c]) * (b[c] - a[c]);
    }
    return x > 0 && y > 0;
}

/* One pass over the crease chains: a crease point not between its two chain neighbours
 * (the label boundary zigzags across the crease, and a point of one edge lands past the next
 * one's) is moved onto the crease between them (Newton on f_A = f_B = 0 in the plane through
 * their midpoint across the chain). Returns the points moved; -1 when out of memory. */
static long order_pass(crease_state *cs)
{
    cut_state *s = cs->s;
    const ism_cut *c = s->c;
    size_t nv = s->m->nverts;
    uint32_t *nb = malloc(2 * (nv + 1) * sizeof *nb), *edge = malloc((nv + 1) * sizeof *edge);
    uint8_t *deg = calloc(nv + 1, 1);
    long moved = -1;
    if (nb && edge && deg) {
        moved = 0;
        for (size_t i = 0; i < c->nedges; i++) {
            const ism_cut_edge *e = &c->edges[i];
            if (e->fn != cs->k)
                continue;
            for (int end = 0; end < 2; end++) {
                uint32_t v = end ? e->b : e->a;
                if (deg[v] < 2)
                    nb[2 * (size_t)v + deg[v]] = end ? e->a : e->b;
                edge[v] = (uint32_t)i;
                deg[v] = deg[v] < UINT8_MAX ? deg[v] + 1 : deg[v];
            }
        }
        for (size_t v = 0; v < nv; v++) {
            if (deg[v] != 2)
                continue;
            double *p = s->m->pos + 3 * v, *a = s->m->pos + 3 * (size_t)nb[2 * v],
                   *b = s->m->pos + 3 * (size_t)nb[2 * v + 1];
            if (between(a, p, b))
                continue;
            double q[3], plane[4] = {0, 0, 0, 0}, l = 0;
            for (int k = 0; k < 3; k++) {
                q[k] = 0.5 * (a[k] + b[k]);
                plane[k] = b[k] - a[k];
                l += plane[k] * plane[k];
            }
            l = sqrt(l);
            for (int k = 0; k < 3; k++) {
                plane[k] /= l;
                plane[3] += plane[k] * q[k];
            }
            const uint32_t *br = c->edges[edge[v]].branch;
            size_t ks[1] = {br[1]};
            if (ism_branches_refine(cs->b, br[0], ks, 1, plane, s->tol, l, q)) {
                memcpy(p, q, sizeof q);
                moved++;
            }
        }
    }
    free(nb);
    free(edge);
    free(deg);
    return moved;
}

/* Adds branch x to a tie vertex's set (n of at most TIE_BRANCHES kept; n past it: more). */
#define TIE_BRANCHES 3
static void tie_add(uint32_t *set, uint8_t *n, uint32_t x)
{
    for (int i = 0; i < *n && i < TIE_BRANCHES; i++)
        if (set[i] == x)
            return;
    if (*n < TIE_BRANCHES)
        set[*n] = x;
    if (*n <= TIE_BRANCHES)
        (*n)++;
}

/* The tie vertices (the first nv, no branch) on the crease put on it by Newton: onto
 * f_A = f_B = 0 for the two branches of their crease edges, onto the triple point
 * f_A = f_B = f_C = 0 for three (the polygoniser put them where f ties to rounding, which is
 * on the crease only to its own precision). False when out of memory. */
static bool refine_ties(crease_state *cs, size_t nv)
{
    cut_state *s = cs->s;
    uint32_t *set = malloc((nv ? nv : 1) * TIE_BRANCHES * sizeof *set);
    uint8_t *n = calloc(nv ? nv : 1, 1);
    if (!set || !n) {
        free(set);
        free(n);
        return false;
    }
    for (size_t i = 0; i < s->c->nedges; i++) {
        const ism_cut_edge *e = &s->c->edges[i];
        for (int end = 0; e->fn == cs->k && end < 2; end++) {
            uint32_t v = end ? e->b : e->a;
            if (v < nv && cs->label[v] == ISM_BRANCH_NONE)
                for (int j = 0; j < 2; j++)
                    tie_add(set + TIE_BRANCHES * (size_t)v, &n[v], e->branch[j]);
        }
    }
    for (size_t v = 0; v < nv; v++) {
        if (n[v] < 2 || n[v] > TIE_BRANCHES)
            continue;
        const uint32_t *b = set + TIE_BRANCHES * v;
        size_t ks[2] = {b[1], n[v] == 3 ? b[2] : 0};
        double p[3];
        memcpy(p, s->m->pos + 3 * v, sizeof p);
        if (ism_branches_refine(cs->b, b[0], ks, n[v] - 1, NULL, s->tol,
                                CREASE_MAX_MOVE_EDGES * s->reach[v], p))
            memcpy(s->m->pos + 3 * v, p, sizeof p);
        else
            s->c->unrefined++;
    }
    free(set);
    free(n);
    return true;
}

/* The branch of f at every vertex. */
static bool label_vertices(crease_state *cs)
{
    const ism_mesh *m = cs->s->m;
    cs->label = malloc((m->nverts + 1) * sizeof *cs->label);
    return cs->label && cut_crease_label(cs->b, m, cs->label);
}

bool cut_crease(cut_state *s, size_t k)
{
    ism_cut_eval *ev = s->ev;
    if (!s->branches) {
        s->branches = malloc(sizeof *s->branches);
        if (!s->branches || !ism_branches_init(s->branches, ev->f)) {
            free(s->branches);
            s->branches = NULL;
            return false;
        }
    }
    ev->branch_tape = s->branches->tape;
    ev->branch_ws = s->branches->ws;
    crease_state cs = {.s = s, .b = s->branches, .k = (uint32_t)k};
    ism_key_map_init(&cs.tie_edge);
    ism_mesh *m = s->m;
    size_t nv = m->nverts, welded, snapped;
    bool ok = cut_grow_vertex_arrays(s) && label_vertices(&cs) &&
              cut_crease_weld_micro(s, cs.label, &welded);
    size_t nt = m->ntris;
    uint32_t *old = malloc((nt ? nt : 1) * 3 * sizeof *old), *parent = cut_parents_copy(s, nt);
    ok = ok && old && parent && cut_crease_snap(s, cs.b, cs.label, &snapped);
    if (ok) {
        cut_longest_edges(m, s->reach);
        memcpy(old, m->tri, nt * 3 * sizeof *old);
        ok = ism_crease_weld_ties(m, cs.label, ISM_BRANCH_NONE, s->tol, old, nt) != SIZE_MAX;
        m->ntris = 0;
        ism_key_map_free(&s->split);
        ism_key_map_init(&s->split);
    }
    for (size_t t = 0; ok && t < nt; t++) {
        const uint32_t *v = old + 3 * t;
        s->from = parent[t];
        if (v[0] != v[1] && v[1] != v[2] && v[2] != v[0]) /* else a welded sliver: gone */
            ok = split_crease_triangle(&cs, v);
    }
    ok = ok && refine_ties(&cs, nv);
    for (int pass = 0; ok && pass < CREASE_ORDER_PASSES; pass++) {
        long moved = order_pass(&cs);
        ok = moved >= 0;
        if (moved <= 0)
            break;
    }
    free(old);
    free(parent);
    free(cs.label);
    free(cs.tp);
    ism_key_map_free(&cs.tie_edge);
    free(cs.tie_side);
    return ok;
}
