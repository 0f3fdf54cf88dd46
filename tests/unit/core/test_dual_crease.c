/* test_dual_crease.c — the dual mesh of surfaces with one min/max at the top of f
 * (core/octree/dual_crease.h; the option dual_crease), through the service's meshing, each
 * in three boxes: as given, moved by 1e-3 and by irrational fractions of a finest cell
 * (pf_sweep_box, tests/unit/placements.h):
 * - a ball cut by a plane, max(|p|² − 1, z − 1/2): one circle crease, radius √3/2 at
 *   z = 1/2; closed-form distance to the solid's boundary (nearest point on the sphere's
 *   piece, the disc, or the circle);
 * - a lens, max(|p − c1|² − 1, |p − c2|² − 1) with c = (±1/2, 0, 0): crease x = 0, radius
 *   √3/2; closed form the same way;
 * each made by the dual mesher, closed (every edge in two triangles), χ 2, one piece, every
 * centroid and edge midpoint within E of the closed form, no triangle facing against the
 * active branch's gradient (beside the crease: of both), vertices on the crease (within
 * 1e-9 of both surfaces by |a| / |∇a| and |b| / |∇b|: the crease Newton's rounding is
 * ~1e-16, a cell ~1e-2) lying on the closed-form circle to 1e-9 and joined by mesh edges
 * into one piece along it, each meeting two such edges or more;
 * - Barth's sextic in the ball r² ≤ 2.25 (bench_error's barth-sextic) at E 1e-2, depth 10:
 *   where the dual mesh is made (the box shifted by 1e-3 at least), χ, pieces and
 *   non-manifold vertices those of the primal path's mesh, closed and manifold elsewhere,
 *   within E by Newton, none turned;
 * - a corner of three smooth pieces (a nested max) declines `min_max` before meshing; so does
 *   the cut ball without the option dual_crease (the default). */
#include <criterion/criterion.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include "core/eval/eval.h"
#include "core/octree/mesher.h"
#include "core/singular/surface.h"
#include "core/util/vec3.h"
#include "poly_fixture.h"

#define DEPTH 9
/* A vertex on the crease: within this of both branch surfaces (first-order distance): the
 * minimum-norm Newton's result is exact to rounding (~1e-16), far below it. */
#define ON_CREASE 1e-9

static const pf_surface cut_ball = {"max(x^2 + y^2 + z^2 - 1, z - 0.5)", NULL, 0, NULL, 0};
static const pf_surface lens = {"max((x - 0.5)^2 + y^2 + z^2 - 1, (x + 0.5)^2 + y^2 + z^2 - 1)",
                                NULL, 0, NULL, 0};
static const pf_surface corner = {"max(max(x^2 + y^2 + z^2 - 1, z - 0.5), x - 0.5)", NULL, 0,
                                  NULL, 0};

/* Directions searched round a point Newton puts beyond E (within_e): a Fibonacci sphere of
 * this many, about 3.2° apart, enough to meet any sheet crossing the ball of radius E. */
#define SIGN_DIRECTIONS 4000

/* The distance from q to f = 0 for the E test: Newton's projection (pf_newton_dist), or — where
 * that exceeds e — e itself when f changes sign between q and q + e u for a direction u of
 * SIGN_DIRECTIONS (a point of f = 0 lies within e: by continuity along the segment). Inside
 * the solid beside the crease Newton follows the active branch's gradient past the other
 * branch's nearer sheet (Barth's sextic at 1e-3: 2.1e-3 by Newton, 6.9e-4 to the sextic's
 * sheet by sampling rays). Independent of the mesher's own measure. */
static double within_e(const ism_tape *t, ism_eval_ws *ws, const double q[3], double e)
{
    double d = pf_newton_dist(t, ws, q);
    if (d <= e)
        return d;
    bool neg = ism_eval_point(t, ws, q[0], q[1], q[2]) < 0;
    for (int i = 0; i < SIGN_DIRECTIONS; i++) {
        double u[3];
        ism_fibonacci_dir(i, SIGN_DIRECTIONS, u);
        if ((ism_eval_point(t, ws, q[0] + e * u[0], q[1] + e * u[1], q[2] + e * u[2]) < 0) != neg)
            return e;
    }
    return d;
}

/* The crease circle's radius (both surfaces' circle: √(1 − 1/4)). */
static const double RHO = 0.86602540378443864676;

/* Distance from p to the circle of radius RHO about axis `axis` in the plane where that
 * coordinate is `at`. */
static double circle_dist(const double p[3], int axis, double at)
{
    double r = 0;
    for (int a = 0; a < 3; a++)
        r += a == axis ? 0 : p[a] * p[a];
    return hypot(sqrt(r) - RHO, p[axis] - at);
}

/* The cut ball's boundary: the sphere's piece (z ≤ 1/2), the disc (ρ ≤ RHO at z = 1/2),
 * the circle; the nearest point is a foot on a piece that lies in it, or on the circle. */
static double cut_ball_dist(const double *p)
{
    double best = circle_dist(p, 2, 0.5), r = ism_norm3(p);
    if (r > 0 && p[2] / r <= 0.5)
        best = fmin(best, fabs(r - 1));
    if (p[0] * p[0] + p[1] * p[1] <= RHO * RHO)
        best = fmin(best, fabs(p[2] - 0.5));
    return best;
}

/* The lens: sphere 1 (centre (1/2, 0, 0)) where it lies in sphere 2, and so on. */
static double lens_dist(const double *p)
{
    double best = circle_dist(p, 0, 0);
    for (int k = 0; k < 2; k++) {
        double c = k ? -0.5 : 0.5, q[3] = {p[0] - c, p[1], p[2]}, r = ism_norm3(q);
        /* the foot c + q / r lies in the other ball when its x is on the other centre's
           side of the crease plane (x ≤ 0 for centre +1/2) */
        if (r > 0 && (k ? c + q[0] / r >= 0 : c + q[0] / r <= 0))
            best = fmin(best, fabs(r - 1));
    }
    return best;
}

/* Box number which: 0 as given, 1 moved by 1e-3, 2 by irrational fractions of a finest cell
 * at DEPTH (pf_sweep_box's placements, tests/unit/placements.h). */
static void box_at(const double base[6], int which, double box[6])
{
    pf_sweep_box(base, DEPTH, which - 1, box);
}

/* The service's meshing of t in box under e, depths 3..dmax, one thread. */
static void mesh_surface_to(const ism_tape *t, const double box[6], double e, bool dual,
                            int dmax, ism_mesh *m, ism_locus *l, ism_poly_stats *ps)
{
    ism_poly_options o;
    pf_options(&o, box, 3, dmax);
    o.max_error = e;
    o.dual = dual;
    o.dual_crease = dual;
    o.threads = 1;
    pf_mesh_surface_with(t, &o, m, l, ps);
}

/* ... down to DEPTH. */
static void mesh_surface(const ism_tape *t, const double box[6], double e, bool dual,
                         ism_mesh *m, ism_locus *l, ism_poly_stats *ps)
{
    mesh_surface_to(t, box, e, dual, DEPTH, m, l, ps);
}

/* Triangles facing against the gradient: of the branch active at their centroid, or —
 * where the switch surface a = b passes within the triangle's longest side of the centroid
 * (to first order: |a − b| <= side |∇a − ∇b|) — of both branches (a thin triangle between
 * crease vertices may face anywhere between the two normals). */
static size_t turned(const ism_mesh *m, const ism_tape *t)
{
    ism_eval_ws *ws = ism_eval_ws_new(t);
    size_t n = 0;
    for (size_t i = 0; i < m->ntris; i++) {
        const double *p[3];
        double c[3] = {0, 0, 0}, val[2], g[2][3], nr[3], side = 0;
        for (int j = 0; j < 3; j++)
            p[j] = m->pos + 3 * (size_t)m->tri[3 * i + j];
        for (int j = 0; j < 3; j++) {
            double e[3];
            for (int a = 0; a < 3; a++) {
                c[a] += p[j][a] / 3;
                e[a] = p[(j + 1) % 3][a] - p[j][a];
            }
            side = fmax(side, ism_norm3(e));
        }
        cr_assert(ism_eval_top_branches(t, ws, c[0], c[1], c[2], val, g));
        pf_tri_normal(m, i, nr);
        bool up[2];
        for (int k = 0; k < 2; k++)
            up[k] = nr[0] * g[k][0] + nr[1] * g[k][1] + nr[2] * g[k][2] > 0;
        double gd[3] = {g[0][0] - g[1][0], g[0][1] - g[1][1], g[0][2] - g[1][2]};
        int active = ism_top_active_branch(t, val);
        bool near = fabs(val[0] - val[1]) <= side * ism_norm3(gd);
        n += near ? !up[0] && !up[1] : !up[active];
    }
    ism_eval_ws_free(ws);
    return n;
}

/* The vertices on both branch surfaces (ON_CREASE) into on[] (1 / 0), their number
 * returned. */
static size_t crease_vertices(const ism_mesh *m, const ism_tape *t, uint8_t *on)
{
    ism_eval_ws *ws = ism_eval_ws_new(t);
    size_t n = 0;
    for (size_t v = 0; v < m->nverts; v++) {
        double val[2], g[2][3];
        const double *p = m->pos + 3 * v;
        cr_assert(ism_eval_top_branches(t, ws, p[0], p[1], p[2], val, g));
        on[v] = fabs(val[0]) <= ON_CREASE * ism_norm3(g[0]) &&
                fabs(val[1]) <= ON_CREASE * ism_norm3(g[1]);
        n += on[v];
    }
    ism_eval_ws_free(ws);
    return n;
}

static uint32_t find_root(uint32_t *up, uint32_t v)
{
    while (up[v] != v)
        v = up[v] = up[up[v]];
    return v;
}

/* The crease vertices joined by mesh edges between them into one piece in which every one
 * meets at least two such edges: the mesh follows the crease as one closed band (a crease
 * passing beside a face of two leaves gives both a vertex on it, so some meet 3 or more:
 * thin triangles along the curve). */
static bool one_crease_loop(const ism_mesh *m, const uint8_t *on)
{
    size_t nv = m->nverts;
    uint32_t *up = malloc((nv ? nv : 1) * sizeof *up);
    uint32_t *deg = calloc(nv ? nv : 1, sizeof *deg);
    cr_assert(up && deg);
    for (size_t v = 0; v < nv; v++)
        up[v] = (uint32_t)v;
    for (size_t t = 0; t < m->ntris; t++)
        for (int j = 0; j < 3; j++) {
            uint32_t a = m->tri[3 * t + j], b = m->tri[3 * t + (j + 1) % 3];
            if (!on[a] || !on[b] || a > b)
                continue; /* each edge once (from its smaller end: the meshes are closed) */
            deg[a]++;
            deg[b]++;
            up[find_root(up, a)] = find_root(up, b);
        }
    bool ok = true;
    uint32_t root = UINT32_MAX;
    for (size_t v = 0; v < nv; v++)
        if (on[v]) {
            uint32_t r = find_root(up, (uint32_t)v);
            root = root == UINT32_MAX ? r : root;
            ok = ok && deg[v] >= 2 && r == root;
        }
    free(up);
    free(deg);
    return ok;
}

/* The dual mesh of a one-crease surface in three boxes, checked as the top comment says. */
static void expect_crease(const pf_surface *s, const double base[6], double e,
                          double (*dist)(const double *), int axis, double at)
{
    ism_tape *t = pf_compile(s);
    for (int which = pf_first_box(); which < 3; which++) {
        double box[6];
        box_at(base, which, box);
        ism_mesh m;
        ism_locus l;
        ism_poly_stats ps;
        mesh_surface(t, box, e, true, &m, &l, &ps);
        cr_expect_eq(ps.mesher, ISM_MESHER_DUAL, "box %d E %g: mesher %s (%s)", which, e,
                     ism_mesher_name(ps.mesher), ism_dual_reason_name(ps.dual_declined));
        pf_props p;
        pf_measure(&m, t, &p);
        cr_expect(p.boundary_edges == 0 && p.nonmanifold_edges == 0 && p.euler == 2 &&
                      p.components == 1,
                  "box %d E %g: %zu open, %zu non-manifold edges, χ %ld, %zu pieces", which,
                  e, p.boundary_edges, p.nonmanifold_edges, p.euler, p.components);
        double w = pf_worst_distance(&m, dist);
        cr_expect_leq(w, e, "box %d E %g: a point %g from the surface", which, e, w);
        size_t tu = turned(&m, t);
        cr_expect_eq(tu, 0, "box %d E %g: %zu triangles against the gradient", which, e, tu);
        uint8_t *on = malloc(m.nverts ? m.nverts : 1);
        cr_assert(on);
        size_t nc = crease_vertices(&m, t, on);
        double off = 0;
        for (size_t v = 0; v < m.nverts; v++)
            if (on[v])
                off = fmax(off, circle_dist(m.pos + 3 * v, axis, at));
        /* the circle is 2π RHO = 5.4 long; leaves within E of it are at most ~0.1 across */
        cr_expect_geq(nc, 24, "box %d E %g: %zu crease vertices", which, e, nc);
        cr_expect_leq(off, ON_CREASE, "box %d E %g: a crease vertex %g off the circle", which,
                      e, off);
        cr_expect(one_crease_loop(&m, on), "box %d E %g: the %zu crease vertices are not "
                  "one band", which, e, nc);
        free(on);
        ism_mesh_free(&m);
        ism_locus_free(&l);
    }
    ism_tape_free(t);
}

Test(dual_crease, cut_ball_folds_along_its_circle)
{
    static const double base[6] = {-1.5, -1.5, -1.5, 1.5, 1.5, 1.5};
    expect_crease(&cut_ball, base, 1e-2, cut_ball_dist, 2, 0.5);
    expect_crease(&cut_ball, base, 3e-3, cut_ball_dist, 2, 0.5);
}

Test(dual_crease, lens_folds_along_its_circle)
{
    static const double base[6] = {-1.5, -1.5, -1.5, 1.5, 1.5, 1.5};
    expect_crease(&lens, base, 1e-2, lens_dist, 0, 0);
    expect_crease(&lens, base, 3e-3, lens_dist, 0, 0);
}

/* Without the option (the default) a crease is declined before meshing, as before. */
Test(dual_crease, off_unless_asked)
{
    ism_tape *t = pf_compile(&cut_ball);
    ism_poly_options o;
    ism_poly_options_default(&o);
    o.max_error = 1e-2;
    o.dual = true;
    cr_expect_eq(ism_dual_declined_before(t, &o), ISM_DUAL_WHY_MIN_MAX);
    o.dual_crease = true;
    cr_expect_eq(ism_dual_declined_before(t, &o), ISM_DUAL_WHY_NONE);
    ism_tape_free(t);
}

Test(dual_crease, a_corner_of_three_pieces_declines)
{
    ism_tape *t = pf_compile(&corner);
    static const double box[6] = {-1.5, -1.5, -1.5, 1.5, 1.5, 1.5};
    ism_mesh m;
    ism_locus l;
    ism_poly_stats ps;
    mesh_surface(t, box, 1e-2, true, &m, &l, &ps);
    cr_expect_eq(ps.mesher, ISM_MESHER_PRIMAL);
    cr_expect_eq(ps.dual_declined, ISM_DUAL_WHY_MIN_MAX, "%s",
                 ism_dual_reason_name(ps.dual_declined));
    ism_mesh_free(&m);
    ism_locus_free(&l);
    ism_tape_free(t);
}

/* Non-manifold vertices: joining more than one cone of triangles. */
static size_t nm_vertices(const ism_mesh *m)
{
    size_t n = 0, *cones = pf_all_vertex_cones(m);
    for (uint32_t v = 0; v < m->nverts; v++)
        n += cones[v] > 1;
    free(cones);
    return n;
}


/* Barth's sextic clipped by the ball r² <= 2.25 at E 1e-2, depth.max 10 (bench_error's):
 * where the dual mesher makes the mesh (its 30 nodes in the ball fanned, its crease
 * followed) it has the primal path's χ, pieces and non-manifold vertices (the nodes: counted
 * on the primal run's mesh, not from the locus), no open or non-manifold edge, every
 * centroid and midpoint within E (Newton's projection, else a sign change of f within E of
 * it: within_e), none facing against the gradient.
 * As given and shifted by 1e-3 it makes it, χ -28 and 30 nodes. As given f is exactly 0 at
 * lattice points ((1/2, 1/2, 1/2) on the sextic, (1.4, -0.2, -0.5) on the sphere) with
 * every other corner of one cell on one side: the sheet crosses them transversally, each
 * such cell a plain leaf cut at its corner (declined not_plain before: every cell as the
 * tooth's). In the irrational box a depth-10 cell on the crease near (-0.8, -0.89, -0.91)
 * has a face crossed four times (the ridge along its diagonal, at every level: declined
 * min_max). */
/* Barth's sextic meshed in box under e (depth.max 10) with and without the crease followed:
 * false when the dual mesher declined; else checked as the comment above says. */
static bool barth_as_the_primal_path(const ism_tape *t, const double box[6], double e,
                                     const char *where)
{
    const int dmax = 10;
    ism_mesh m[2];
    ism_locus l[2];
    ism_poly_stats ps[2];
    mesh_surface_to(t, box, e, true, dmax, &m[0], &l[0], &ps[0]);
    if (ps[0].mesher != ISM_MESHER_DUAL) {
        ism_mesh_free(&m[0]);
        ism_locus_free(&l[0]);
        return false;
    }
    mesh_surface_to(t, box, e, false, dmax, &m[1], &l[1], &ps[1]);
    pf_props p[2];
    size_t nm[2];
    for (int k = 0; k < 2; k++) {
        pf_measure(&m[k], t, &p[k]);
        nm[k] = nm_vertices(&m[k]);
    }
    cr_expect(p[0].euler == p[1].euler && p[0].components == p[1].components &&
                  nm[0] == nm[1] && p[0].euler == -28 && nm[0] == 30 &&
                  p[0].boundary_edges == 0 && p[0].nonmanifold_edges == 0,
              "%s E %g: χ %ld / %ld, pieces %zu / %zu, nm vertices %zu / %zu (dual / primal), "
              "%zu open, %zu non-manifold edges", where, e, p[0].euler, p[1].euler,
              p[0].components, p[1].components, nm[0], nm[1], p[0].boundary_edges,
              p[0].nonmanifold_edges);
    ism_eval_ws *ws = ism_eval_ws_new(t);
    double w = 0;
    for (size_t i = 0; i < m[0].ntris; i++) {
        const double *v[3];
        for (int j = 0; j < 3; j++)
            v[j] = m[0].pos + 3 * (size_t)m[0].tri[3 * i + j];
        for (int j = 0; j < 4; j++) {
            double q[3];
            for (int a = 0; a < 3; a++)
                q[a] = j == 3 ? (v[0][a] + v[1][a] + v[2][a]) / 3
                              : 0.5 * (v[j][a] + v[(j + 1) % 3][a]);
            w = fmax(w, within_e(t, ws, q, e));
        }
    }
    ism_eval_ws_free(ws);
    cr_expect_leq(w, e, "%s E %g: a point %g from the surface", where, e, w);
    size_t tu = turned(&m[0], t);
    cr_expect_eq(tu, 0, "%s E %g: %zu triangles against the gradient", where, e, tu);
    for (int k = 0; k < 2; k++) {
        ism_mesh_free(&m[k]);
        ism_locus_free(&l[k]);
    }
    return true;
}

/* barth_as_the_primal_path at E in the three boxes from pf_first_box() on; boxes before
 * `declines_from` must be dual. The number of dual meshes. */
static int barth_in_boxes(const ism_tape *t, double e, int declines_from)
{
    static const double base[6] = {-1.6, -1.6, -1.6, 1.6, 1.6, 1.6};
    int made = 0;
    for (int which = pf_first_box(); which < 3; which++) {
        double box[6];
        char where[16];
        box_at(base, which, box);
        snprintf(where, sizeof where, "box %d", which);
        bool dual = barth_as_the_primal_path(t, box, e, where);
        cr_expect(which >= declines_from || dual, "box %d E %g: declined", which, e);
        made += dual;
    }
    return made;
}

Test(dual_crease, barth_in_a_ball_as_the_primal_path)
{
    ism_tape *t = pf_compile(&pf_barth_sextic);
    int made = barth_in_boxes(t, 1e-2, 2);
    cr_expect_geq(made, pf_first_box() > 1 ? 0 : 2, "the dual mesh in %d boxes", made);
    ism_tape_free(t);
}

/* ... and at 3e-3, where in its own box the ridge runs along depth-10 cells' face diagonals:
 * the leaves there hold a piece of each branch apart (dual_crease.h ISM_CREASE_PAIR) or
 * their crease point with a face crossed four times (declined min_max before); the own box
 * must be dual. The shifted boxes decline today; a dual mesh made there is checked alike. */
Test(dual_crease, barth_pairs_beside_the_ridge)
{
    if (pf_quick())
        return;
    ism_tape *t = pf_compile(&pf_barth_sextic);
    barth_in_boxes(t, 3e-3, 1);
    ism_tape_free(t);
}
