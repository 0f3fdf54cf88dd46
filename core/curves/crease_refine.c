/* crease_refine.c — red-green refinement along a crease (crease_refine.h). A triangle on
 * crease edge a-b (length L) with its third corner c a height h off it is flat across surface
 * that bends: its normal is off its branch's gradient at the edge's midpoint by about
 * |κ_across h/2 − κ_along L²/(8h)| (the chord a-b lies the sagitta below the surface), so
 * only a smaller triangle of the same shape has a smaller miss — a thinner one trades the
 * first term for the second (the gyroid ball at depth 7: 3–5° for 4–5% of the crease edges,
 * over the 2° of dihedral angle). A triangle that misses is split in four at its
 * edges' midpoints:
 *
 *          c              m on the crease (Newton on both branches in the plane across
 *         / \             a-b's midpoint: the cut edge a-b becomes a-m, m-b), p and q on
 *        p---q            the triangle's branch (Newton along its gradient); a neighbour
 *       / \ / \           with one split edge is split in two, with two in three (cut.c's
 *      a---m---b          lone corner), so the mesh stays conforming.
 *
 * A triangle whose crease point would turn a triangle beside the edge over (the crease
 * bulges past a near corner) is left whole, its sides too; before each pass the thin
 * triangles on the crease are fattened by moving their corner off it (crease_relax.h).
 * Passes repeat on the smaller triangles while one still misses. */
#include "core/curves/crease_refine.h"
#include "core/curves/crease_relax.h"
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include "core/util/grow.h"
#include "core/util/vec3.h"

#define NONE CUT_NONE
/* A triangle on a crease edge may have its flat normal this far off its branch's gradient at
 * the edge's midpoint (degrees): the dihedral angle across the edge is then off the
 * gradients' angle by at most twice this, within the 2°. */
#define CREASE_REFINE_DEG 0.8
/* Passes at most: each halves the misses of the triangles it splits (thin ones keep their
 * shape, and need more); the gyroid ball at depth 7 needs 7 in the lattice box and the one
 * moved by 1e-3 (the 7th asks nothing; four left 6 edges over 2°, beside triangles of
 * 3.7°), and in the irrational box still splits a few edges in the 12th (with the
 * relaxation before every pass: 6 passes left an edge 9.2° off the gradients' angle beside a
 * 6.5° triangle the 6th made, 8 three up to 2.2°, 10 none but 2 sliver sides, 12 none). */
#define CREASE_REFINE_PASSES 12
/* ... the first this many each after a relaxation (crease_relax.h), later ones measuring
 * only the triangles the last pass made (nothing else moved): past the 6th each splits few
 * triangles (71 down to 9 new vertices) while the relaxation still moved 280-450 vertices
 * and every crease triangle was measured again. ism_cut_mesh in the gyroid ball's test
 * (callgrind, lattice / irrational box): 6 passes 1,284M / 1,287M instructions; 12 with
 * the relaxation in each 1,456M / 1,832M; so 1,342M / 1,496M, no edge over 2° and no sliver
 * side in either. */
#define CREASE_RELAX_PASSES 6
/* Newton steps at most along the branch's gradient putting an edge's midpoint on its zero set
 * (it starts within the edge's sagitta of it: quadratic convergence ends in two or three). */
#define CREASE_REFINE_NEWTON 4
/* A half of a triangle beside a split crease edge must keep this cosine with the triangle's
 * normal (60°, as the snap's star: no half turned over or folded up). */
#define CREASE_REFINE_TURN_COS 0.5
/* A midpoint moved farther than this share of its edge's length ran away (to another sheet):
 * the chord's midpoint is kept instead. */
#define CREASE_REFINE_MOVE 0.5

typedef struct refine_split {
    uint32_t u, w;  /* the edge; u on the crease */
    uint32_t A;     /* the branch of the triangle that asked (an edge off the crease) */
    bool crease;    /* a cut edge of the crease */
    uint32_t by[2]; /* an edge off the crease: the crease edges' splits that asked it (NONE);
                       made only when one of them is (a triangle whose crease edge stays
                       whole is not split at its sides: that would halve its height alone) */
} refine_split;

typedef struct refine_state {
    cut_state *s;
    size_t k;
    uint8_t *on;        /* per vertex: an end of a cut edge of the crease */
    ism_key_map edge;   /* edge key -> index into split */
    refine_split *split;
    uint32_t *vert;     /* per split: its new vertex (NONE: left whole) */
    size_t cap_split, cap_vert;
    uint32_t *label;    /* per vertex: its branch once looked up (LABEL_UNKNOWN before; a
                           vertex keeps its branch: the relaxation moves none across) */
    size_t cap_label;
    ism_key_map side;   /* crease edge key -> index into sides */
    uint32_t (*sides)[2]; /* the triangles on a crease edge (NONE: none yet) */
    size_t cap_sides;
    cut_relax_memo relax; /* the relaxation's failed stars, kept from pass to pass */
    uint8_t *fresh;     /* per triangle: made by the last pass's splits */
    size_t cap_fresh;
    bool all;           /* measure every triangle (a relaxation moved vertices), not only
                           the fresh ones */
} refine_state;

/* The flat normal of triangle (a, b, c) against branch A's gradient at the midpoint of a-b,
 * in degrees (a triangle the mesh orients against ∇f, inside a thin piece, compared the
 * other way round). */
static double side_miss(ism_branches *br, uint32_t A, const double *a, const double *b,
                        const double *c)
{
    double mid[3], g[3], n[3];
    for (int i = 0; i < 3; i++)
        mid[i] = 0.5 * (a[i] + b[i]);
    ism_tri_cross3(a, b, c, n);
    ism_branches_gradient(br, A, mid, g);
    double nn = ism_norm3(n) * ism_norm3(g);
    if (!(nn > 0) || !isfinite(nn))
        return 0;
    return acos(fmin(1.0, fabs(ism_dot3(n, g)) / nn)) * (180 / M_PI);
}

/* A vertex whose branch is not looked up yet (branches are numbered below ISM_BRANCH_MAX). */
#define LABEL_UNKNOWN (ISM_BRANCH_NONE - 1)

/* The branch of vertex v (ISM_BRANCH_NONE: a tie), looked up once; false when out of
 * memory. */
static bool label_of(refine_state *st, uint32_t v, uint32_t *A)
{
    size_t old = st->cap_label;
    if (!ism_grow((void **)&st->label, &st->cap_label, (size_t)v + 1, sizeof *st->label,
                  CUT_FIRST))
        return false;
    for (size_t i = old; i < st->cap_label; i++)
        st->label[i] = LABEL_UNKNOWN;
    if (st->label[v] == LABEL_UNKNOWN &&
        !ism_branches_at(st->s->branches, st->s->m->pos + 3 * (size_t)v, &st->label[v]))
        return false;
    *A = st->label[v];
    return true;
}

/* Asks edge u-w split (once), for the split `by` of a crease edge (NONE: it is one); its
 * index in *at. */
static bool want_split(refine_state *st, uint32_t u, uint32_t w, uint32_t A, uint32_t by,
                       uint32_t *at)
{
    bool added;
    uint32_t i = cut_edge_slot(&st->edge, u, w, (void **)&st->split, &st->cap_split,
                               sizeof *st->split, &added);
    if (i == CUT_NONE)
        return false;
    refine_split *sp = &st->split[i];
    if (added)
        *sp = (refine_split){u, w, A, by == NONE, {by, NONE}};
    else if (by != NONE && sp->by[0] != by)
        sp->by[1] = by;
    *at = i;
    return true;
}

/* The cut edge of the crease a-b, or NONE. */
static uint32_t crease_edge(const refine_state *st, uint32_t a, uint32_t b)
{
    if (!st->on[a] || !st->on[b])
        return NONE;
    uint32_t e = cut_find_cut_edge(st->s, a, b);
    return e != NONE && st->s->c->edges[e].fn == st->k ? e : NONE;
}

/* Notes triangle t on crease edge a-b (two kept: a crease edge inside the surface). */
static bool note_side(refine_state *st, uint32_t a, uint32_t b, uint32_t t)
{
    bool added;
    uint32_t i = cut_edge_slot(&st->side, a, b, (void **)&st->sides, &st->cap_sides,
                               sizeof *st->sides, &added);
    if (i == CUT_NONE)
        return false;
    if (added)
        st->sides[i][0] = st->sides[i][1] = NONE;
    st->sides[i][st->sides[i][0] != NONE] = t;
    return true;
}

/* Triangle t: when it lies on a crease edge with its third corner off the crease and
 * misses, its three edges are asked split (measured only when st->all or fresh: a triangle
 * left whole by the last pass, no vertex moved since, misses as it did, and was asked). */
static bool check_triangle(refine_state *st, uint32_t t)
{
    const ism_mesh *m = st->s->m;
    const uint32_t *tv = m->tri + 3 * (size_t)t;
    for (int i = 0; i < 3; i++) {
        uint32_t a = tv[i], b = tv[(i + 1) % 3], c = tv[(i + 2) % 3];
        if (crease_edge(st, a, b) == NONE)
            continue;
        if (!note_side(st, a, b, t))
            return false;
        if (st->on[c] || !(st->all || st->fresh[t]))
            continue;
        uint32_t A;
        const double *pc = m->pos + 3 * (size_t)c;
        if (!label_of(st, c, &A))
            return false;
        if (A == ISM_BRANCH_NONE ||
            !(side_miss(st->s->branches, A, m->pos + 3 * (size_t)a, m->pos + 3 * (size_t)b,
                        pc) > CREASE_REFINE_DEG))
            return true;
        uint32_t i, j;
        return want_split(st, a, b, A, NONE, &i) && want_split(st, a, c, A, i, &j) &&
               want_split(st, b, c, A, i, &j);
    }
    return true;
}

/* Whether putting p between u and w keeps the triangles on crease edge u-w facing as they
 * did: both halves of each within CREASE_REFINE_TURN_COS of its normal (the crease point can
 * lie off the chord past a near corner on the other side). */
static bool halves_keep_facing(const refine_state *st, uint32_t u, uint32_t w, const double *p)
{
    const ism_mesh *m = st->s->m;
    uint32_t i = ism_key_map_find(&st->side, cut_edge_key(u, w));
    for (int j = 0; i != ISM_KEY_NONE && j < 2; j++) {
        uint32_t t = st->sides[i][j];
        if (t == NONE)
            continue;
        const uint32_t *tv = m->tri + 3 * (size_t)t;
        double n[3], h[3];
        cut_tri_normal(m, tv, NONE, NULL, n);
        for (int half = 0; half < 2; half++) { /* p in place of u, then of w */
            cut_tri_normal(m, tv, half ? w : u, p, h);
            double nn = ism_norm3(n) * ism_norm3(h);
            if (!(ism_dot3(n, h) >= CREASE_REFINE_TURN_COS * nn) || !(nn > 0))
                return false;
        }
    }
    return true;
}

/* The midpoint of crease edge u-w put on both its branches (NONE: Newton failed or a
 * triangle beside it would turn over; the edge stays whole). */
static uint32_t crease_midpoint(refine_state *st, const refine_split *sp)
{
    cut_state *s = st->s;
    const double *u = s->m->pos + 3 * (size_t)sp->u, *w = s->m->pos + 3 * (size_t)sp->w;
    const ism_cut_edge *e = &s->c->edges[cut_find_cut_edge(s, sp->u, sp->w)];
    if (e->branch[0] == ISM_CUT_NO_BRANCH || e->branch[1] == ISM_CUT_NO_BRANCH)
        return NONE;
    double p[3], plane[4] = {0, 0, 0, 0}, len = ism_dist3(u, w);
    for (int i = 0; i < 3; i++) {
        p[i] = 0.5 * (u[i] + w[i]);
        plane[i] = (w[i] - u[i]) / len;
        plane[3] += plane[i] * p[i];
    }
    size_t ks[1] = {e->branch[1]};
    if (!ism_branches_refine(s->branches, e->branch[0], ks, 1, plane, s->tol,
                             CREASE_REFINE_MOVE * len, p) ||
        !halves_keep_facing(st, sp->u, sp->w, p))
        return NONE;
    uint32_t br[2] = {e->branch[0], e->branch[1]};
    float nrm[3];
    cut_normal_at(s, p, NULL, nrm);
    uint32_t v = ism_mesh_add_vertex(s->m, p, nrm);
    return v != NONE && cut_set_vcurve(s, v, (uint32_t)st->k) &&
                   cut_split_cut_edge(s, sp->u, sp->w, v, (uint32_t)st->k) &&
                   cut_set_branches(s, sp->u, v, br) && cut_set_branches(s, v, sp->w, br)
               ? v
               : NONE;
}

/* The midpoint of edge u-w (u on the crease) put on the zero set of branch A. */
static uint32_t side_midpoint(refine_state *st, const refine_split *sp, bool *across)
{
    cut_state *s = st->s;
    const double *u = s->m->pos + 3 * (size_t)sp->u, *w = s->m->pos + 3 * (size_t)sp->w;
    double p[3], q[3];
    for (int i = 0; i < 3; i++)
        p[i] = q[i] = 0.5 * (u[i] + w[i]);
    double reach = CREASE_REFINE_MOVE * ism_dist3(u, w);
    ism_branches_project(s->branches, sp->A, CREASE_REFINE_NEWTON, s->tol, q);
    if (ism_sqdist3(p, q) <= reach * reach)
        memcpy(p, q, sizeof p);
    uint32_t B;
    if (!ism_branches_at(s->branches, p, &B))
        return NONE;
    if (B != sp->A) {
        *across = true;
        return NONE;
    }
    float nrm[3];
    cut_normal_at(s, p, s->m->normal + 3 * (size_t)sp->w, nrm);
    return ism_mesh_add_vertex(s->m, p, nrm);
}

/* The new vertex on edge a-b, NONE when it is not split. */
static uint32_t split_of(const refine_state *st, uint32_t a, uint32_t b)
{
    uint32_t i = ism_key_map_find(&st->edge, cut_edge_key(a, b));
    return i == ISM_KEY_NONE ? NONE : st->vert[i];
}

/* Emits triangle tv split at its split edges (winding kept). */
static bool emit_split(refine_state *st, const uint32_t *tv)
{
    cut_state *s = st->s;
    uint32_t sp[3];
    int n = 0, whole = 0;
    for (int i = 0; i < 3; i++) {
        sp[i] = split_of(st, tv[i], tv[(i + 1) % 3]);
        if (sp[i] != NONE)
            n++;
        else
            whole = i;
    }
    if (n == 0)
        return cut_add_triangle(s, tv[0], tv[1], tv[2]);
    if (n == 1) {
        int i = sp[0] != NONE ? 0 : sp[1] != NONE ? 1 : 2;
        uint32_t a = tv[i], b = tv[(i + 1) % 3], o = tv[(i + 2) % 3];
        return cut_add_triangle(s, a, sp[i], o) && cut_add_triangle(s, sp[i], b, o);
    }
    if (n == 2) { /* the corner between the split edges, lone */
        uint32_t l = tv[(whole + 2) % 3], u = tv[whole], w = tv[(whole + 1) % 3];
        return cut_emit_lone(s, l, u, w, sp[(whole + 2) % 3], sp[(whole + 1) % 3]);
    }
    return cut_add_triangle(s, tv[0], sp[0], sp[2]) && cut_add_triangle(s, sp[0], tv[1], sp[1]) &&
           cut_add_triangle(s, sp[2], sp[1], tv[2]) && cut_add_triangle(s, sp[0], sp[1], sp[2]);
}

/* One pass: the asked splits made and the triangles written afresh. *added: new vertices. */
static bool refine_pass(refine_state *st, size_t *added)
{
    cut_state *s = st->s;
    ism_mesh *m = s->m;
    size_t nt = m->ntris;
    *added = 0;
    ism_key_map_free(&st->edge);
    ism_key_map_init(&st->edge);
    ism_key_map_free(&st->side);
    ism_key_map_init(&st->side);
    for (size_t t = 0; t < nt; t++)
        if (!check_triangle(st, (uint32_t)t))
            return false;
    size_t n = st->edge.n;
    if (!n)
        return true;
    if (!ism_grow((void **)&st->vert, &st->cap_vert, n, sizeof *st->vert, CUT_FIRST))
        return false;
    for (size_t i = 0; i < n; i++) /* the crease's points first: they decide the others */
        if (st->split[i].crease) {
            st->vert[i] = crease_midpoint(st, &st->split[i]);
            *added += st->vert[i] != NONE;
        }
    for (size_t i = 0; i < n; i++) {
        const refine_split *sp = &st->split[i];
        if (sp->crease)
            continue;
        bool across = false, asked = st->vert[sp->by[0]] != NONE ||
                                     (sp->by[1] != NONE && st->vert[sp->by[1]] != NONE);
        st->vert[i] = asked ? side_midpoint(st, sp, &across) : NONE;
        if (asked && st->vert[i] == NONE && !across)
            return false; /* out of memory */
        *added += st->vert[i] != NONE;
    }
    uint32_t *old = malloc(3 * nt * sizeof *old), *parent = cut_parents_copy(s, nt);
    uint8_t *end = calloc(m->nverts + 1, 1); /* an end of a split edge */
    bool ok = old && parent && end;
    for (size_t i = 0; ok && i < n; i++)
        if (st->vert[i] != NONE)
            end[st->split[i].u] = end[st->split[i].w] = 1;
    if (ok) {
        memcpy(old, m->tri, 3 * nt * sizeof *old);
        m->ntris = 0;
    }
    for (size_t t = 0; ok && t < nt; t++) {
        const uint32_t *tv = old + 3 * t;
        s->from = parent[t];
        size_t first = m->ntris;
        bool split = end[tv[0]] || end[tv[1]] || end[tv[2]];
        ok = split ? emit_split(st, tv) : cut_add_triangle(s, tv[0], tv[1], tv[2]);
        ok = ok && ism_grow((void **)&st->fresh, &st->cap_fresh, m->ntris, 1, CUT_FIRST);
        for (size_t u = first; ok && u < m->ntris; u++)
            st->fresh[u] = split;
    }
    free(old);
    free(parent);
    free(end);
    return ok;
}

/* Marks the ends of the crease's cut edges in st->on (sized for the mesh's vertices). */
static bool mark_crease(refine_state *st)
{
    free(st->on);
    st->on = calloc(st->s->m->nverts + 1, 1);
    if (!st->on)
        return false;
    for (size_t i = 0; i < st->s->c->nedges; i++) {
        const ism_cut_edge *e = &st->s->c->edges[i];
        if (e->fn == st->k)
            st->on[e->a] = st->on[e->b] = 1;
    }
    return true;
}

bool cut_crease_refine(cut_state *s, size_t k, size_t *added)
{
    refine_state st = {.s = s, .k = k};
    ism_key_map_init(&st.edge);
    ism_key_map_init(&st.side);
    *added = 0;
    bool ok = s->branches != NULL && mark_crease(&st);
    for (int pass = 0; ok && pass < CREASE_REFINE_PASSES; pass++) {
        size_t n = 0, moved = 0;
        st.all = pass < CREASE_RELAX_PASSES;
        ok = (!st.all || cut_crease_relax(s, k, &st.relax, &moved)) && refine_pass(&st, &n) &&
             mark_crease(&st);
        *added += n;
        if (!n)
            break;
    }

    ism_key_map_free(&st.edge);
    ism_key_map_free(&st.side);
    free(st.sides);
    free(st.label);
    free(st.split);
    free(st.vert);
    free(st.on);
    free(st.fresh);
    cut_relax_memo_free(&st.relax);
    return ok;
}
