/* node.c — a node of the curve f = 0, g = 0 on the surface (g = 0 tangent to it: two
 * branches cross) made to meet the cut whatever the mesh: a vertex is on the node
 * (tangency.c puts it there); its branches' directions are the null directions of the
 * Lagrangian's Hessian in the tangent plane, and each branch is followed out of the vertex's
 * star for a few triangles, the edges it crosses split at it and the vertices it passes put
 * on it, so that the sign cut leaves the node four times and the sectors between the
 * branches take their own signs. */
#include "core/curves/cut_internal.h"
#include "core/util/vec3.h"
#include <math.h>
#include <stdlib.h>
#include <string.h>

#define NONE CUT_NONE

/* Orthonormal e1, e2 spanning the plane normal to n (n ≠ 0). */
static void tangent_basis(const double n[3], double e1[3], double e2[3])
{
    double u[3] = {n[0], n[1], n[2]}, e[2][3];
    ism_normalise3(u);
    ism_across3(u, e);
    for (int c = 0; c < 3; c++) {
        e1[c] = e[0][c];
        e2[c] = e[1][c];
    }
}

/* The node's two branch directions in the tangent plane (e1, e2 coordinates): the null
 * directions of the Lagrangian's Hessian H_g − λ H_f restricted to the plane. False when
 * the form is not indefinite (no node). */
static bool node_directions(cut_state *s, size_t k, const double p[3], double h,
                            double e1[3], double e2[3], double dir[2][2])
{
    double gf[3], hf[6], gg[3], hg[6];
    ism_eval_hessian(s->ev->f, s->ev->fws, p[0], p[1], p[2], gf, hf);
    ism_cut_g_hessian(s->ev, k, p, h, gg, hg);
    double ff = gf[0] * gf[0] + gf[1] * gf[1] + gf[2] * gf[2];
    if (!(ff > 0))
        return false;
    double lam = (gg[0] * gf[0] + gg[1] * gf[1] + gg[2] * gf[2]) / ff, Q[6];
    for (int i = 0; i < 6; i++)
        Q[i] = hg[i] - lam * hf[i];
    tangent_basis(gf, e1, e2);
    const double *e[2] = {e1, e2};
    double q[2][2];
    for (int i = 0; i < 2; i++)
        for (int j = 0; j < 2; j++) {
            const double *x = e[i], *y = e[j];
            q[i][j] = Q[0] * x[0] * y[0] + Q[3] * x[1] * y[1] + Q[5] * x[2] * y[2] +
                      Q[1] * (x[0] * y[1] + x[1] * y[0]) + Q[2] * (x[0] * y[2] + x[2] * y[0]) +
                      Q[4] * (x[1] * y[2] + x[2] * y[1]);
        }
    double det = q[0][0] * q[1][1] - q[0][1] * q[0][1];
    if (!(det < 0))
        return false;
    /* q11 c² + 2 q12 c s + q22 s² = 0: c = −q12 ± √−det, s = q11 (or the swap when q11 ≈ 0) */
    double r = sqrt(-det);
    for (int i = 0; i < 2; i++) {
        double sg = i ? -1 : 1;
        if (fabs(q[0][0]) >= fabs(q[1][1])) {
            dir[i][0] = -q[0][1] + sg * r;
            dir[i][1] = q[0][0];
        } else {
            dir[i][0] = q[1][1];
            dir[i][1] = -q[0][1] + sg * r;
        }
        double l = hypot(dir[i][0], dir[i][1]);
        dir[i][0] /= l;
        dir[i][1] /= l;
    }
    return true;
}

static double cross2(const double a[2], const double b[2])
{
    return a[0] * b[1] - a[1] * b[0];
}

/* The ray from vertex u along r (coordinates in the tangent plane e1, e2) out through its
 * star: the link edge a-b it crosses and where (parameter *at along a-b). False when none. */
static bool ray_exit(const cut_state *s, const uint32_t *tris, size_t nt, uint32_t u,
                     const double e1[3], const double e2[3], const double r[2], uint32_t *a,
                     uint32_t *b, double *at)
{
    const ism_mesh *m = s->m;
    const double *p = m->pos + 3 * (size_t)u;
    for (size_t i = 0; i < nt; i++) {
        const uint32_t *tv = m->tri + 3 * (size_t)tris[i];
        int c = tv[0] == u ? 0 : tv[1] == u ? 1 : tv[2] == u ? 2 : -1;
        if (c < 0)
            continue;
        uint32_t va = tv[(c + 1) % 3], vb = tv[(c + 2) % 3];
        double A[2] = {0, 0}, B[2] = {0, 0};
        for (int k = 0; k < 3; k++) {
            double da = m->pos[3 * (size_t)va + k] - p[k], db = m->pos[3 * (size_t)vb + k] - p[k];
            A[0] += da * e1[k];
            A[1] += da * e2[k];
            B[0] += db * e1[k];
            B[1] += db * e2[k];
        }
        double ab = cross2(A, B), ar = cross2(A, r), rb = cross2(r, B);
        if (ab == 0 || (ar > 0) != (ab > 0) || (rb > 0) != (ab > 0))
            continue; /* r not inside the angle a-u-b */
        double BA[2] = {B[0] - A[0], B[1] - A[1]}, den = cross2(BA, r);
        if (den == 0)
            continue;
        *a = va;
        *b = vb;
        *at = -ar / den;
        return true;
    }
    return false;
}

/* A branch crossing a link edge this close to one of its ends (edge fractions) passes
 * through that vertex: the vertex is put on the branch rather than the edge split into a
 * sliver. */
#define NODE_RAY_END 0.02
/* Triangles a branch is followed through from its node: where the mesh's vertices hug the
 * branch (on a lattice plane tangent to the surface at the node), the sign of g at them does
 * not show which side of it they lie on for a few cells. */
#define NODE_WALK_STEPS 6

static bool has_vertex(const uint32_t *tv, uint32_t v)
{
    return tv[0] == v || tv[1] == v || tv[2] == v;
}

/* Moves q onto the branch along the unit direction R, at distance d ahead of from: Newton
 * on f, g_k and the plane across R there (the minimum-norm step alone may run to the other
 * branch of a node when q lies nearer to it). False (q kept) when it fails or d ≤ 0. */
static bool onto_branch(cut_state *s, size_t k, const double from[3], const double R[3],
                        double d, double max_move, double q[3])
{
    double plane[4] = {R[0], R[1], R[2], ism_dot3(R, from) + d};
    return d > 0 && ism_cut_refine_on_plane(s->ev, k, plane, s->tol, max_move, q);
}

/* Whether a neighbour of cur (through the triangles tris) on the curve lies within r of q. */
static bool curve_vertex_near(cut_state *s, const uint32_t *tris, size_t nt,
                              uint32_t cur, const double q[3], double r)
{
    for (size_t i = 0; i < nt; i++) {
        const uint32_t *tv = s->m->tri + 3 * (size_t)tris[i];
        if (tv[0] != cur && tv[1] != cur && tv[2] != cur)
            continue;
        for (int c = 0; c < 3; c++)
            if (tv[c] != cur && cut_sign_of(s, tv[c]) == 0 &&
                ism_sqdist3(s->m->pos + 3 * (size_t)tv[c], q) <= r * r)
                return true;
    }
    return false;
}

/* Whether w may be merged into z: w's triangles without z keep their orientation at z's
 * place, and w and z share no neighbour but the apexes of their edge's triangles (so the
 * mesh stays a surface). tris: the triangles round w. */
static bool can_merge(cut_state *s, const uint32_t *tris, size_t nt, uint32_t w,
                      uint32_t z)
{
    const ism_mesh *m = s->m;
    if (!cut_can_move(s, tris, nt, w, m->pos + 3 * (size_t)z, false, z))
        return false;
    for (size_t i = 0; i < nt; i++) {
        const uint32_t *tv = m->tri + 3 * (size_t)tris[i];
        if (!has_vertex(tv, w))
            continue;
        for (int c = 0; c < 3; c++) {
            uint32_t x = tv[c];
            bool joined_z = false, apex = false;
            for (size_t j = 0; x != w && x != z && j < nt; j++) {
                const uint32_t *tu = m->tri + 3 * (size_t)tris[j];
                bool both = has_vertex(tu, x) && has_vertex(tu, z);
                joined_z |= both;
                apex |= both && has_vertex(tu, w);
            }
            if (joined_z && !apex)
                return false;
        }
    }
    return true;
}

/* Merges vertex w into z: the triangles with both are dropped, w becomes z in the others
 * (w stays, unused). */
static void merge_vertex(cut_state *s, uint32_t w, uint32_t z)
{
    ism_mesh *m = s->m;
    size_t n = 0;
    for (size_t t = 0; t < m->ntris; t++) {
        uint32_t tv[3] = {m->tri[3 * t], m->tri[3 * t + 1], m->tri[3 * t + 2]};
        if (has_vertex(tv, w) && has_vertex(tv, z))
            continue;
        for (int c = 0; c < 3; c++)
            m->tri[3 * n + c] = tv[c] == w ? z : tv[c];
        s->parent[n++] = s->parent[t];
    }
    m->ntris = n;
    s->cells.valid = false; /* the triangles are renumbered */
    s->edits++;
}

/* Puts link vertex w on the branch (R from `from`) at its own distance along R; where a
 * vertex on the curve already lies there (the polygoniser's vertices on two lattice lines a
 * hair apart, the Klein bottle's (0, −1, ±1.4375) and its neighbour on x = 0), w is merged
 * into it. *moved tells whether w moved; false only when out of memory. */
static bool branch_through_vertex(cut_state *s, size_t k, const double from[3],
                                  const double R[3], uint32_t w, double edge, bool *moved)
{
    *moved = false;
    if (!cut_on_no_other(s, w, k))
        return true;
    uint32_t *tris = NULL;
    size_t nt = 0;
    if (!cut_ring_triangles(s->m, w, &tris, &nt))
        return false;
    const double *pw = s->m->pos + 3 * (size_t)w;
    double q[3] = {pw[0], pw[1], pw[2]}, near = NODE_RAY_END * edge;
    if (onto_branch(s, k, from, R, ism_dot3(R, pw) - ism_dot3(R, from), edge, q)) {
        *moved = cut_can_move(s, tris, nt, w, q, false, NONE);
        for (size_t i = 0; !*moved && i < nt; i++) /* a vertex on the curve there */
            for (int c = 0; c < 3; c++) {
                uint32_t z = s->m->tri[3 * (size_t)tris[i] + c];
                if (z != w && cut_sign_of(s, z) == 0 &&
                    ism_sqdist3(s->m->pos + 3 * (size_t)z, q) <= near * near &&
                    can_merge(s, tris, nt, w, z)) {
                    merge_vertex(s, w, z);
                    break;
                }
            }
    }
    bool ok = !*moved || cut_move_vertex(s, k, w, q, tris, nt);
    free(tris);
    return ok;
}

/* Splits link edge a-b at the branch point q: *x the new vertex on the curve. */
static bool branch_through_edge(cut_state *s, size_t k, uint32_t a, uint32_t b,
                                const double q[3], double reach, uint32_t *x)
{
    float nrm[3];
    cut_normal_at(s, q, s->m->normal + 3 * (size_t)a, nrm);
    *x = ism_mesh_add_vertex(s->m, q, nrm);
    if (*x == NONE || !cut_grow_vertex_arrays(s) || !cut_set_vcurve(s, *x, (uint32_t)k))
        return false;
    cut_on_curve_now(s, *x);
    s->reach[*x] = reach;
    return cut_split_triangles_at(s, a, b, *x);
}

/* The curve's unit tangent ∇f × ∇g_k at p, turned along R (R kept when it vanishes). */
static void branch_tangent(cut_state *s, size_t k, const double p[3], double R[3])
{
    double gf[3], gg[3], t[3];
    ism_eval_gradient(s->ev->f, s->ev->fws, p[0], p[1], p[2], gf);
    ism_cut_g(s->ev, k, p, gg);
    ism_cross3(gf, gg, t);
    double l = sqrt(ism_dot3(t, t));
    if (!(l > 0))
        return;
    l = ism_dot3(t, R) < 0 ? -l : l;
    for (int c = 0; c < 3; c++)
        R[c] = t[c] / l;
}

/* One step of a branch from vertex cur (on the curve) along R: where it leaves cur's star,
 * the link edge is split at the branch or the link vertex it passes put on it. *next is that
 * vertex, NONE where the walk ends: the branch leaves through a vertex on the curve, or
 * (after the first step, step > 0) through an edge whose ends take both signs, where the
 * cut finds it. False when out of memory. */
static bool branch_step(cut_state *s, size_t k, uint32_t cur, const double R[3], int step,
                        bool vertices_only, double reach, uint32_t *next)
{
    double e1[3], e2[3], gf[3], from[3];
    *next = NONE;
    memcpy(from, s->m->pos + 3 * (size_t)cur, sizeof from);
    ism_eval_gradient(s->ev->f, s->ev->fws, from[0], from[1], from[2], gf);
    if (!(ism_dot3(gf, gf) > 0))
        return true;
    tangent_basis(gf, e1, e2);
    double r[2] = {ism_dot3(R, e1), ism_dot3(R, e2)}, l = hypot(r[0], r[1]), at = 0;
    if (!(l > 0))
        return true;
    r[0] /= l;
    r[1] /= l;
    uint32_t *tris = NULL, a = NONE, b = NONE;
    size_t nt = 0;
    if (!cut_ring_triangles(s->m, cur, &tris, &nt))
        return false;
    bool hit = ray_exit(s, tris, nt, cur, e1, e2, r, &a, &b, &at), ok = true;
    const double *pa = s->m->pos + 3 * (size_t)a, *pb = s->m->pos + 3 * (size_t)b;
    double edge = hit ? sqrt(ism_sqdist3(pa, pb)) : 0, q[3], near = NODE_RAY_END * edge;
    for (int c = 0; hit && c < 3; c++)
        q[c] = pa[c] + at * (pb[c] - pa[c]);
    if (!hit || !onto_branch(s, k, from, R, ism_dot3(R, q) - ism_dot3(R, from), edge, q) ||
        curve_vertex_near(s, tris, nt, cur, q, near)) {
        free(tris);
        return true; /* no branch point, or it passes through a vertex on the curve */
    }
    free(tris);
    uint32_t w = at < NODE_RAY_END || ism_sqdist3(q, pa) <= near * near       ? a
                 : at > 1 - NODE_RAY_END || ism_sqdist3(q, pb) <= near * near ? b
                                                                      : NONE;
    if (w != NONE) {
        bool moved;
        ok = branch_through_vertex(s, k, from, R, w, edge, &moved);
        *next = ok && moved ? w : NONE;
    } else if (!vertices_only && (step == 0 || cut_sign_of(s, a) * cut_sign_of(s, b) >= 0)) {
        ok = branch_through_edge(s, k, a, b, q, reach, next);
    }
    return ok;
}

/* Each branch is followed out of u's star for up to NODE_WALK_STEPS triangles
 * (branch_step). The Klein bottle's section x = 0 in the symmetric box needs it: a branch
 * along a lattice line through a vertex of the polygoniser's 3e-6 off the plane (with a
 * vertex on the curve 1.4e-4 beyond it, on the plane), the sector past it without a vertex
 * of its sign, and vertices on the lattice plane (g = 0) whose edges hide the other
 * branch. */
bool cut_node_branches(cut_state *s, size_t k, uint32_t u, double reach)
{
    double e1[3], e2[3], dir[2][2], h = CUT_FD_STEP_REL * reach;
    if (!node_directions(s, k, s->m->pos + 3 * (size_t)u, h, e1, e2, dir))
        return true;
    for (int ray = 0; ray < 8; ray++) { /* where branches leave through link vertices first:
                                           a merge reshapes the star */
        double sign = ray & 2 ? -1 : 1, R[3];
        for (int c = 0; c < 3; c++)
            R[c] = sign * (dir[ray & 1][0] * e1[c] + dir[ray & 1][1] * e2[c]);
        uint32_t cur = u;
        for (int step = 0; step < (ray < 4 ? 1 : NODE_WALK_STEPS) && cur != NONE; step++) {
            uint32_t next;
            if (!branch_step(s, k, cur, R, step, ray < 4, reach, &next))
                return false;
            if (next != NONE)
                branch_tangent(s, k, s->m->pos + 3 * (size_t)next, R);
            cur = next;
        }
    }
    return true;
}
