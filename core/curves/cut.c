/* cut.c — splitting the mesh along g = 0, one function after another. A triangle whose
 * corners take both signs of g is split at its crossed edges (the split point of an edge is
 * shared by both its triangles through a map keyed by the edge, so the cut is crack-free);
 * the crossing is first interpolated linearly, then moved onto f = g = 0 by Newton. An edge
 * already lying on an earlier curve is split at the crossing of the two curves (Newton on
 * f, g₁, g₂), and its cut edge replaced by the two halves. */
#include "core/curves/arr_internal.h"
#include "core/curves/crease_refine.h"
#include "core/curves/cut_compact.h"
#include "core/curves/cut_internal.h"
#include <limits.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include "core/util/grow.h"
#include "core/util/vec3.h"

#define NONE CUT_NONE
/* Newton may move a split point at most this many lengths of its edge (further means it
 * ran to another part of the curve). */
#define CUT_MAX_MOVE_EDGES 2.0
/* Newton steps moving a triangle's centroid onto f = 0 (it lies within the triangle's
 * sagitta of the surface: quadratic convergence ends there in two or three). */
#define CUT_CENTROID_STEPS 4
/* Bisection steps for the fallback start on an edge (2^-40 of the edge). */
#define CUT_BISECT_STEPS 40

uint64_t cut_edge_key(uint32_t a, uint32_t b)
{
    return a < b ? ((uint64_t)a << 32) | b : ((uint64_t)b << 32) | a;
}

uint32_t cut_edge_slot(ism_key_map *map, uint32_t a, uint32_t b, void **arr, size_t *cap,
                       size_t elem, bool *added)
{
    uint32_t i = ism_key_map_add(map, cut_edge_key(a, b), added);
    if (i == ISM_KEY_NONE || !ism_grow(arr, cap, (size_t)i + 1, elem, CUT_FIRST))
        return CUT_NONE;
    return i;
}

void ism_cut_free(ism_cut *c)
{
    free(c->edges);
    free(c->tri_parent);
    memset(c, 0, sizeof *c);
}

bool cut_add_triangle(cut_state *s, uint32_t a, uint32_t b, uint32_t c)
{
    size_t t = s->m->ntris;
    if (!ism_grow((void **)&s->parent, &s->cap_parent, t + 1, sizeof *s->parent, CUT_FIRST) ||
        !ism_mesh_add_triangle(s->m, a, b, c))
        return false;
    s->parent[t] = s->from;
    return cut_cells_place(s, t);
}

uint32_t *cut_parents_copy(const cut_state *s, size_t nt)
{
    uint32_t *p = malloc((nt ? nt : 1) * sizeof *p);
    if (p && nt)
        memcpy(p, s->parent, nt * sizeof *p);
    return p;
}

/* Every triangle its own parent (before the first cut). */
static bool parents_init(cut_state *s)
{
    size_t nt = s->m->ntris;
    if (nt > UINT32_MAX ||
        !ism_grow((void **)&s->parent, &s->cap_parent, nt ? nt : 1, sizeof *s->parent, CUT_FIRST))
        return false;
    for (size_t t = 0; t < nt; t++)
        s->parent[t] = (uint32_t)t;
    return true;
}

bool cut_set_vcurve(cut_state *s, uint32_t v, uint32_t fn)
{
    size_t old = s->cap_vcurve;
    if (!ism_grow((void **)&s->vcurve, &s->cap_vcurve, (size_t)v + 1, sizeof *s->vcurve, CUT_FIRST))
        return false;
    for (size_t i = old; i < s->cap_vcurve; i++)
        s->vcurve[i] = NONE;
    if (s->vcurve[v] == NONE)
        s->vcurve[v] = fn;
    return true;
}

uint32_t cut_vcurve_of(const cut_state *s, uint32_t v)
{
    return v < s->cap_vcurve ? s->vcurve[v] : NONE;
}

/* Lists cut edge i at its ends a and b (ehead / enext). */
static bool link_edge_ends(cut_state *s, uint32_t i, uint32_t a, uint32_t b)
{
    size_t old = s->cap_ehead, top = (a > b ? a : b) + (size_t)1;
    if (!ism_grow((void **)&s->ehead, &s->cap_ehead, top, sizeof *s->ehead, CUT_FIRST) ||
        !ism_grow((void **)&s->enext, &s->cap_enext, 2 * (size_t)i + 2, sizeof *s->enext,
                  CUT_FIRST))
        return false;
    for (size_t v = old; v < s->cap_ehead; v++)
        s->ehead[v] = NONE;
    s->enext[2 * (size_t)i] = s->ehead[a];
    s->ehead[a] = 2 * i;
    s->enext[2 * (size_t)i + 1] = s->ehead[b];
    s->ehead[b] = 2 * i + 1;
    return true;
}

uint32_t cut_find_cut_edge(const cut_state *s, uint32_t a, uint32_t b)
{
    if (a >= s->cap_ehead)
        return NONE;
    for (uint32_t end = s->ehead[a]; end != NONE; end = s->enext[end]) {
        const ism_cut_edge *e = &s->c->edges[end / 2];
        if ((end % 2 ? e->a : e->b) == b)
            return end / 2;
    }
    return NONE;
}

bool cut_add_cut_edge(cut_state *s, uint32_t a, uint32_t b, uint32_t fn)
{
    if (cut_find_cut_edge(s, a, b) != NONE)
        return true;
    size_t i = s->c->nedges;
    if (i >= UINT32_MAX / 2 ||
        !ism_grow((void **)&s->c->edges, &s->cap_edges, i + 1, sizeof *s->c->edges, CUT_FIRST))
        return false;
    s->c->edges[i] = (ism_cut_edge){a, b, fn, {ISM_CUT_NO_BRANCH, ISM_CUT_NO_BRANCH}};
    s->c->nedges = i + 1;
    return link_edge_ends(s, (uint32_t)i, a, b);
}

bool cut_split_cut_edge(cut_state *s, uint32_t a, uint32_t b, uint32_t v, uint32_t fn)
{
    uint32_t e = cut_find_cut_edge(s, a, b);
    uint32_t br[2] = {ISM_CUT_NO_BRANCH, ISM_CUT_NO_BRANCH};
    if (e != NONE) {
        s->c->edges[e].fn = NONE;
        memcpy(br, s->c->edges[e].branch, sizeof br);
    }
    return cut_add_cut_edge(s, a, v, fn) && cut_add_cut_edge(s, v, b, fn) &&
           cut_set_branches(s, a, v, br) && cut_set_branches(s, v, b, br);
}

bool cut_set_branches(cut_state *s, uint32_t a, uint32_t b, const uint32_t br[2])
{
    uint32_t e = cut_find_cut_edge(s, a, b);
    if (e == NONE)
        return false;
    memcpy(s->c->edges[e].branch, br, sizeof s->c->edges[e].branch);
    return true;
}

void cut_normal_at(cut_state *s, const double p[3], const float ref[3], float out[3])
{
    double g[3];
    ism_cut_f_gradient(s->ev, p, g);
    double n = sqrt(g[0] * g[0] + g[1] * g[1] + g[2] * g[2]);
    double d = ref ? g[0] * ref[0] + g[1] * ref[1] + g[2] * ref[2] : 1;
    double k = n > 0 ? (d < 0 ? -1 / n : 1 / n) : 0;
    for (int i = 0; i < 3; i++)
        out[i] = (float)(g[i] * k);
}

/* Puts point p (on or near edge u-w of length len) on curve k, and on curve j too when it is
 * not NONE. False (p kept) when Newton fails. */
static bool try_refine(cut_state *s, uint32_t j, size_t k, double len, double p[3])
{
    size_t ks[2] = {k, j};
    int nk = 1;
    if (j != NONE && j != k) {
        ks[0] = j;
        ks[1] = k;
        nk = 2;
    }
    return ism_cut_refine(s->ev, ks, nk, s->tol, CUT_MAX_MOVE_EDGES * len, p);
}

static void refine_point(cut_state *s, uint32_t j, size_t k, double len, double p[3])
{
    if (!try_refine(s, j, k, len, p))
        s->c->unrefined++;
}

void cut_bisect(cut_sign_fn fn, void *ctx, const double a[3], const double b[3], double ga,
                double p[3])
{
    double lo = 0, hi = 1;
    for (int it = 0; it < CUT_BISECT_STEPS; it++) {
        double t = 0.5 * (lo + hi), q[3];
        for (int c = 0; c < 3; c++)
            q[c] = a[c] + t * (b[c] - a[c]);
        if ((fn(ctx, q) < 0) == (ga < 0))
            lo = t;
        else
            hi = t;
    }
    for (int c = 0; c < 3; c++)
        p[c] = a[c] + 0.5 * (lo + hi) * (b[c] - a[c]);
}

typedef struct g_of {
    cut_state *s;
    size_t k;
} g_of;

static double g_at(void *ctx, const double p[3])
{
    g_of *g = ctx;
    return ism_cut_g(g->s->ev, g->k, p, NULL);
}

bool cut_split_slot(cut_state *s, uint32_t u, uint32_t w, uint32_t *slot, uint32_t *v)
{
    bool added;
    uint32_t i = cut_edge_slot(&s->split, u, w, (void **)&s->split_v, &s->cap_split,
                               sizeof *s->split_v, &added);
    if (i == CUT_NONE)
        return false;
    *slot = i;
    *v = added ? NONE : s->split_v[i];
    return true;
}

/* A lattice plane's coordinate is computed from the box's corner and side (lo + i × side /
 * 2^depth), so the mesh's border on the far face can differ from the box's bound by a few
 * ulps of the side: within this × the side it is that face. */
#define BOX_FACE_REL 1e-12

/* The box face edge a-b lies in (plane: n, c), when the box is known: both ends on one
 * coordinate plane (bit for bit) at one of its faces — the mesh's border there. */
static bool box_face_of(const cut_state *s, const double *a, const double *b, double plane[4])
{
    const double *box = s->ev->box;
    for (int i = 0; box && i < 6; i++) {
        int c = i % 3;
        if (a[c] == b[c] && fabs(a[c] - box[i]) <= BOX_FACE_REL * (box[c + 3] - box[c])) {
            plane[0] = plane[1] = plane[2] = 0;
            plane[c] = 1;
            plane[3] = a[c];
            return true;
        }
    }
    return false;
}

/* Puts the point p where curve k leaves the mesh through a box face (an edge a-b in that
 * face) on the face as well, so the curve's end is the curve's exit from the box; p kept
 * (and false) when Newton fails there (the curve tangent to the face). */
static bool refine_on_face(cut_state *s, size_t k, const double *a, const double *b, double len,
                           double p[3])
{
    double plane[4];
    if (s->ev->fns[k].kind == ISM_CUT_CREASE || !box_face_of(s, a, b, plane))
        return false;
    double q[3] = {p[0], p[1], p[2]};
    if (!ism_cut_refine_on_plane(s->ev, k, plane, s->tol, CUT_MAX_MOVE_EDGES * len, q))
        return false;
    for (int c = 0; c < 3; c++) /* on the face exactly (Newton leaves it to rounding) */
        p[c] = plane[c] == 1 ? plane[3] : q[c];
    return true;
}

/* Puts p (on edge a-b of length len) on curve k in the plane across the edge (∇f at p and
 * the edge: ism_cut_plane_along). False (p kept) when Newton fails there (the curve runs along
 * the edge). */
static bool refine_across(cut_state *s, size_t k, const double *a, const double *b, double len,
                          double p[3])
{
    double d[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]}, q[3] = {p[0], p[1], p[2]};
    if (s->ev->fns[k].kind == ISM_CUT_CREASE ||
        !ism_cut_refine_across(s->ev, k, d, s->tol, CUT_MAX_MOVE_EDGES * len, q))
        return false;
    memcpy(p, q, sizeof q);
    return true;
}

/* The vertex where g_k = 0 splits edge u-w (made once per edge). NONE when out of memory. */
static uint32_t split_vertex(cut_state *s, size_t k, uint32_t u, uint32_t w)
{
    uint32_t i, had;
    if (!cut_split_slot(s, u, w, &i, &had))
        return NONE;
    if (had != NONE)
        return had;
    const double *a = s->m->pos + 3 * (size_t)u, *b = s->m->pos + 3 * (size_t)w;
    double t = s->gv[u] / (s->gv[u] - s->gv[w]), p[3], len2 = 0;
    for (int c = 0; c < 3; c++) {
        p[c] = a[c] + t * (b[c] - a[c]);
        len2 += (b[c] - a[c]) * (b[c] - a[c]);
    }
    uint32_t e = cut_vcurve_of(s, u) == NONE || cut_vcurve_of(s, w) == NONE
                     ? NONE
                     : cut_find_cut_edge(s, u, w);
    uint32_t j = e == NONE ? NONE : s->c->edges[e].fn;
    for (int c = 0; c < 2; c++) /* when u-w lies on a crease: its two branches */
        s->ev->pair[c] = e == NONE ? ISM_CUT_NO_BRANCH : s->c->edges[e].branch[c];
    double len = fmax(sqrt(len2), fmax(s->reach[u], s->reach[w]));
    if ((j != NONE || (!refine_on_face(s, k, a, b, len, p) &&
                       !refine_across(s, k, a, b, len, p))) &&
        !try_refine(s, j, k, len, p)) {
        cut_bisect(g_at, &(g_of){s, k}, a, b, s->gv[u], p); /* g bends: a start by bisection */
        refine_point(s, j, k, len, p);
    }
    float nrm[3];
    bool crease = s->ev->fns[k].kind == ISM_CUT_CREASE ||
                  (j != NONE && s->ev->fns[j].kind == ISM_CUT_CREASE);
    cut_normal_at(s, p, crease ? NULL : s->m->normal + 3 * (size_t)u, nrm);
    uint32_t v = ism_mesh_add_vertex(s->m, p, nrm);
    if (v == NONE || !cut_set_vcurve(s, v, (uint32_t)k) || !cut_note_residuals(s, v))
        return NONE;
    if (j != NONE && !cut_split_cut_edge(s, u, w, v, j)) /* the earlier curve's edge */
        return NONE;
    s->split_v[i] = v;
    return v;
}

static double dist2(const ism_mesh *m, uint32_t a, uint32_t b)
{
    return ism_sqdist3(m->pos + 3 * (size_t)a, m->pos + 3 * (size_t)b);
}

/* Emits a piece of the triangle being split: into its own slot first, then appended. */
static bool emit(cut_state *s, uint32_t a, uint32_t b, uint32_t c)
{
    if (s->slot == SIZE_MAX)
        return cut_add_triangle(s, a, b, c);
    uint32_t *t = s->m->tri + 3 * s->slot;
    t[0] = a;
    t[1] = b;
    t[2] = c;
    cut_cells_grow(s, s->slot);
    s->slot = SIZE_MAX;
    return true;
}

/* An edge whose ends both lie on the curve, seen from a triangle whose third corner has
 * sign sign (a triangle of zeros: g's sign inside it): it is a curve edge when g takes both
 * signs across it (or at the border of the mesh), not when both sides have one sign (it
 * crosses a sector of a node, or the curve only touches it). */
static bool note_zero_edge(cut_state *s, uint32_t a, uint32_t b, int sign)
{
    bool added;
    uint32_t i = cut_edge_slot(&s->zero, a, b, (void **)&s->zero_edge, &s->cap_zero,
                               sizeof *s->zero_edge, &added);
    if (i == CUT_NONE)
        return false;
    if (added)
        s->zero_edge[i] = (cut_zero_edge){a, b, 0, 0};
    s->zero_edge[i].mask |= sign > 0 ? 1 : sign < 0 ? 2 : 0;
    s->zero_edge[i].seen += s->zero_edge[i].seen < UINT8_MAX;
    return true;
}

/* The curve edges among the edges with both ends on the curve. */
static bool add_zero_edges(cut_state *s, size_t k)
{
    for (size_t i = 0; i < s->zero.n; i++) {
        const cut_zero_edge *z = &s->zero_edge[i];
        if ((z->mask == 3 || (z->seen == 1 && z->mask)) &&
            !cut_add_cut_edge(s, z->a, z->b, (uint32_t)k))
            return false;
    }
    ism_key_map_free(&s->zero);
    ism_key_map_init(&s->zero);
    return true;
}

/* The sign of g_k on the surface inside triangle t: at its centroid moved onto f = 0 by
 * Newton along ∇f. At the centroid itself g may vanish where the triangle lies in g's zero
 * set (a plane tangent to the surface: the Klein bottle's x = 0 at its nodes, through
 * vertices of the lattice) while the surface beyond it takes g's sign. */
static int centroid_sign(cut_state *s, size_t k, const uint32_t t[3])
{
    double c[3] = {0, 0, 0};
    for (int i = 0; i < 3; i++)
        for (int d = 0; d < 3; d++)
            c[d] += s->m->pos[3 * (size_t)t[i] + d] / 3;
    for (int it = 0; it < CUT_CENTROID_STEPS; it++) {
        double gf[3], f = ism_eval_gradient(s->ev->f, s->ev->fws, c[0], c[1], c[2], gf);
        double n2 = gf[0] * gf[0] + gf[1] * gf[1] + gf[2] * gf[2];
        if (!(n2 > 0) || f == 0)
            break;
        for (int d = 0; d < 3; d++)
            c[d] -= f * gf[d] / n2;
    }
    double g = ism_cut_g(s->ev, k, c, NULL);
    return (g > 0) - (g < 0);
}

/* Splits triangle t = (v0 v1 v2) by g_k, appending the pieces to the mesh. */
static bool split_triangle(cut_state *s, size_t k, const uint32_t t[3])
{
    const signed char sg[3] = {s->sg[t[0]], s->sg[t[1]], s->sg[t[2]]};
    int pos = (sg[0] > 0) + (sg[1] > 0) + (sg[2] > 0);
    int neg = (sg[0] < 0) + (sg[1] < 0) + (sg[2] < 0);
    uint32_t fn = (uint32_t)k;
    if (!pos || !neg) {
        int side = pos ? 1 : neg ? -1 : centroid_sign(s, k, t); /* all zero: g inside */
        for (int i = 0; i < 3; i++)
            if (sg[i] == 0 && sg[(i + 1) % 3] == 0 &&
                !note_zero_edge(s, t[i], t[(i + 1) % 3], side))
                return false;
        return emit(s, t[0], t[1], t[2]);
    }
    for (int i = 0; i < 3; i++) /* one corner on the curve, the other two apart */
        if (sg[i] == 0) {
            uint32_t z = t[i], u = t[(i + 1) % 3], w = t[(i + 2) % 3];
            uint32_t p = split_vertex(s, k, u, w);
            return p != NONE && cut_add_cut_edge(s, z, p, fn) && emit(s, z, u, p) &&
                   emit(s, z, p, w);
        }
    for (int i = 0; i < 3; i++) /* the lone corner on its side */
        if (sg[i] != sg[(i + 1) % 3] && sg[i] != sg[(i + 2) % 3]) {
            uint32_t l = t[i], u = t[(i + 1) % 3], w = t[(i + 2) % 3];
            uint32_t p = split_vertex(s, k, l, u), q = split_vertex(s, k, l, w);
            return p != NONE && q != NONE && cut_add_cut_edge(s, p, q, fn) &&
                   cut_emit_lone(s, l, u, w, p, q);
        }
    return false;
}

bool cut_emit_lone(cut_state *s, uint32_t l, uint32_t u, uint32_t w, uint32_t p, uint32_t q)
{
    if (!emit(s, l, p, q))
        return false;
    if (dist2(s->m, p, w) <= dist2(s->m, u, q)) /* the shorter diagonal */
        return emit(s, p, u, w) && emit(s, p, w, q);
    return emit(s, p, u, q) && emit(s, u, w, q);
}

/* Per vertex: its longest edge into len (0 for a vertex no triangle uses). */
void cut_longest_edges(const ism_mesh *m, double *len)
{
    memset(len, 0, m->nverts * sizeof *len);
    for (size_t t = 0; t < m->ntris; t++)
        for (int i = 0; i < 3; i++) {
            uint32_t a = m->tri[3 * t + i], b = m->tri[3 * t + (i + 1) % 3];
            double d = sqrt(dist2(m, a, b));
            len[a] = d > len[a] ? d : len[a];
            len[b] = d > len[b] ? d : len[b];
        }
}

bool cut_grow_vertex_arrays(cut_state *s)
{
    size_t need = s->m->nverts + 1, n = 2 * need;
    if (need <= s->cap_gv)
        return true;
    double *gv = realloc(s->gv, n * sizeof *gv);
    if (gv)
        s->gv = gv;
    double *reach = gv ? realloc(s->reach, n * sizeof *reach) : NULL;
    if (reach)
        s->reach = reach;
    signed char *sg = reach ? realloc(s->sg, n) : NULL;
    if (sg)
        s->sg = sg;
    cut_vscratch *vs = sg ? realloc(s->vs, n * sizeof *vs) : NULL;
    if (vs)
        s->vs = vs;
    uint8_t *near = vs ? realloc(s->near, n) : NULL;
    if (!near)
        return false;
    memset(vs + s->cap_gv, 0, (n - s->cap_gv) * sizeof *vs);
    memset(near + s->cap_gv, 0, n - s->cap_gv);
    s->near = near;
    s->cap_gv = n;
    return true;
}

static bool push_near(cut_state *s, uint32_t v, uint8_t level)
{
    if (s->near[v])
        return true;
    if (!ism_grow((void **)&s->near_list, &s->cap_near, s->n_near + 1, sizeof *s->near_list,
                  CUT_FIRST))
        return false;
    s->near[v] = level;
    s->reach[v] = 0;
    s->near_list[s->n_near++] = v;
    return true;
}

/* The triangles of list (n) with a corner of the curve's triangles: listed in stars, their
 * corners marked a ring further, and squared edge lengths into reach. */
static bool mark_stars(cut_state *s, const uint32_t *list, size_t n)
{
    const ism_mesh *m = s->m;
    for (size_t i = 0; i < n; i++) {
        const uint32_t *tv = m->tri + 3 * (size_t)list[i];
        if (s->near[tv[0]] != 1 && s->near[tv[1]] != 1 && s->near[tv[2]] != 1)
            continue;
        if (!ism_grow((void **)&s->stars, &s->cap_stars, s->nstars + 1, sizeof *s->stars,
                      CUT_FIRST))
            return false;
        s->stars[s->nstars++] = list[i];
        for (int c = 0; c < 3; c++) {
            uint32_t a = tv[c], b = tv[(c + 1) % 3];
            if (!push_near(s, a, 2))
                return false;
            double d = dist2(m, a, b);
            s->reach[a] = d > s->reach[a] ? d : s->reach[a];
            s->reach[b] = d > s->reach[b] ? d : s->reach[b];
        }
    }
    return true;
}

bool cut_mark_near(cut_state *s)
{
    const ism_mesh *m = s->m;
    const cut_cells *cl = &s->cells;
    s->nstars = 0;
    for (size_t i = 0; i < cl->ntris; i++) { /* the curve's triangles are in crossed cells */
        const uint32_t *tv = m->tri + 3 * (size_t)cl->tris[i];
        signed char a = s->sg[tv[0]];
        if (a != 0 && a == s->sg[tv[1]] && a == s->sg[tv[2]])
            continue;
        for (int c = 0; c < 3; c++)
            if (!push_near(s, tv[c], 1))
                return false;
    }
    if (!mark_stars(s, cl->tris, cl->ntris) || !mark_stars(s, cl->ring_tris, cl->nring))
        return false;
    for (size_t i = 0; i < s->n_near; i++)
        s->reach[s->near_list[i]] = sqrt(s->reach[s->near_list[i]]);
    return cut_cells_near_values(s);
}

void cut_clear_near(cut_state *s)
{
    for (size_t i = 0; i < s->n_near; i++) {
        s->vs[s->near_list[i]] = (cut_vscratch){0};
        s->near[s->near_list[i]] = 0;
    }
    s->n_near = 0;
}

/* Signs of g_k at the vertices near its curve (cut_cells_select); those on the curve are
 * put on it (and on an earlier curve they lie on). */
static bool classify(cut_state *s, size_t k)
{
    ism_mesh *m = s->m;
    s->fn = k;
    if (!cut_grow_vertex_arrays(s) || !cut_cells_ready(s) ||
        !cut_cells_select(s, k) || !cut_mark_near(s))
        return false;
    for (size_t i = 0; i < s->cells.nverts; i++) {
        uint32_t v = s->cells.verts[i];
        if (s->gv[v] != 0)
            continue;
        refine_point(s, cut_vcurve_of(s, v), k, s->reach[v], m->pos + 3 * (size_t)v);
        cut_cells_moved(s, m->pos + 3 * (size_t)v, s->reach[v]);
        if (!cut_set_vcurve(s, v, (uint32_t)k) || !cut_note_residuals(s, v))
            return false;
    }
    return true;
}

static bool cut_one(cut_state *s, size_t k)
{
    size_t edits = s->edits;
    if (!classify(s, k) || !cut_tangencies(s, k))
        return false;
    if (s->edits != edits && /* the tangencies changed the mesh: list its triangles again */
        ((!s->cells.valid && !cut_cells_build(s)) || !cut_cells_select(s, k)))
        return false;
    ism_mesh *m = s->m;
    ism_key_map_free(&s->split);
    ism_key_map_init(&s->split);
    bool ok = true;
    for (size_t i = 0; i < s->cells.ntris && ok; i++) { /* pieces: the first in t's slot,
                                                            others appended */
        size_t t = s->cells.tris[i];
        uint32_t tri[3] = {m->tri[3 * t], m->tri[3 * t + 1], m->tri[3 * t + 2]};
        signed char a = s->sg[tri[0]];
        if (a != 0 && a == s->sg[tri[1]] && a == s->sg[tri[2]])
            continue; /* on one side: kept as it is */
        s->slot = t;
        s->from = s->parent[t];
        ok = split_triangle(s, k, tri);
    }
    s->slot = SIZE_MAX;
    cut_clear_near(s);
    return ok && add_zero_edges(s, k);
}

/* Drops the replaced cut edges and measures how close the curve vertices are. */
static void finish(cut_state *s)
{
    ism_cut *c = s->c;
    size_t n = 0;
    for (size_t i = 0; i < c->nedges; i++)
        if (c->edges[i].fn != NONE)
            c->edges[n++] = c->edges[i];
    c->nedges = n;
    cut_measure_residuals(s);
}

/* V − E + T of the triangles (vertices and edges counted once, only those triangles use: the
 * crease cut leaves welded copies unused; edges filed under their lower vertex as the
 * arrangement does, not hashed: the hash was 5% of the gyroid ball's crease stage); LONG_MIN
 * when out of memory. */
static long mesh_euler(const ism_mesh *m)
{
    size_t ne = arr_mesh_edge_count(m);
    uint8_t *used = calloc(m->nverts + 1, 1);
    long chi = LONG_MIN;
    if (used && ne != SIZE_MAX) {
        size_t nv = 0;
        for (size_t i = 0; i < 3 * m->ntris; i++)
            if (!used[m->tri[i]]) {
                used[m->tri[i]] = 1;
                nv++;
            }
        chi = (long)nv - (long)ne + (long)m->ntris;
    }
    free(used);
    return chi;
}

/* The crease cut by branches, then refined beside it (crease_refine.h); where the cut leaves
 * a crack (the mesh's Euler characteristic changes: a vertex whose branch ties, a triple
 * junction it cannot resolve) the mesh is restored and cut by the sign of a − b of the top
 * min/max instead. */
static bool crease_or_top(cut_state *s, size_t k)
{
    ism_mesh *m = s->m;
    size_t nv = m->nverts, nt = m->ntris, ne = s->c->nedges;
    long before = mesh_euler(m);
    uint32_t *tri = malloc((nt ? nt : 1) * 3 * sizeof *tri), *parent = cut_parents_copy(s, nt);
    if (!tri || !parent || before == LONG_MIN) {
        free(tri);
        free(parent);
        return false;
    }
    memcpy(tri, m->tri, nt * 3 * sizeof *tri);
    s->cells.valid = false; /* the crease cut writes the triangles afresh */
    bool ok = cut_crease(s, k);
    if (ok && mesh_euler(m) != before) {
        memcpy(m->tri, tri, nt * 3 * sizeof *tri); /* its vertices stay, unused (the cut
                                                      edge map still names them) */
        m->ntris = nt;
        memcpy(s->parent, parent, nt * sizeof *parent);
        for (size_t v = nv; v < m->nverts && v < s->cap_vcurve; v++)
            s->vcurve[v] = NONE;
        for (size_t i = ne; i < s->c->nedges; i++)
            s->c->edges[i].fn = NONE;
        ok = cut_one(s, k);
    } else if (ok) {
        size_t added;
        ok = cut_crease_refine(s, k, &added);
    }
    free(tri);
    free(parent);
    return ok;
}

bool ism_cut_mesh(ism_cut_eval *ev, double tol, ism_mesh *m, ism_cut *c)
{
    cut_state s = {.ev = ev, .m = m, .c = c, .tol = tol, .slot = SIZE_MAX};
    ism_key_map_init(&s.split);
    ism_key_map_init(&s.zero);
    bool ok = parents_init(&s);
    for (size_t k = 0; k < ev->nfns && ok; k++)
        ok = ev->fns[k].kind == ISM_CUT_CREASE ? crease_or_top(&s, k) : cut_one(&s, k);
    if (ok) {
        finish(&s);
        ok = ism_cut_compact(m, c);
    }
    free(c->tri_parent);
    c->tri_parent = ok ? s.parent : NULL;
    if (!ok)
        free(s.parent);
    ism_key_map_free(&s.split);
    ism_key_map_free(&s.zero);
    free(s.zero_edge);
    free(s.split_v);
    free(s.vcurve);
    free(s.gv);
    free(s.sg);
    free(s.reach);
    free(s.vs);
    free(s.near);
    free(s.near_list);
    free(s.stars);
    cut_cells_free(&s.cells);
    free(s.ehead);
    free(s.enext);
    free(s.vres);
    if (s.branches) {
        ism_branches_free(s.branches);
        free(s.branches);
        ev->branch_tape = NULL;
        ev->branch_ws = NULL;
    }
    return ok;
}
