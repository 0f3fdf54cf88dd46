/* test_polygonise_closed.c — closed manifold surfaces come out as closed manifold meshes:
 * every edge in exactly two triangles, the right Euler characteristic, one piece, vertices
 * on the surface and the area of the true surface, at several depths and in boxes whose
 * centre is off the surface's symmetry planes (so lattice and surface never line up). */
#include <criterion/criterion.h>
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include "core/eval/eval.h"
#include "poly_fixture.h"

static const ism_param sphere_r[] = {{"r", 1}};
static const pf_surface sphere = {"x^2 + y^2 + z^2 - r^2", sphere_r, 1, NULL, 0};
static const ism_param torus_rr[] = {{"R", 1}, {"r", 0.3}};
static const pf_surface torus = {"(x^2 + y^2 + z^2 + R^2 - r^2)^2 - 4*R^2*(x^2 + y^2)",
                                 torus_rr, 2, NULL, 0};
static const ism_param pretzel_t[] = {{"t", 0.03}};
static const pf_surface pretzel = {"(x*(x-1)^2*(x-2) + y^2)^2 + z^2 - t", pretzel_t, 1, NULL, 0};

/* Checks a closed surface; area_expect <= 0 skips the area check. */
static void check_closed(const pf_surface *s, const double box[6], int dmin, int dmax,
                         long euler, double area_expect)
{
    dmax -= pf_quick();
    if (dmin > dmax)
        dmin = dmax;
    ism_tape *t = pf_compile(s);
    ism_mesh m;
    ism_poly_stats st;
    pf_run(t, box, dmin, dmax, 0, &m, &st);
    pf_props p;
    pf_measure(&m, t, &p);
    cr_assert_gt(p.faces, 100, "%s: only %zu triangles", s->expr, p.faces);
    cr_expect_eq(p.boundary_edges, 0, "%s depth %d: %zu boundary edges", s->expr, dmax,
                 p.boundary_edges);
    cr_expect_eq(p.nonmanifold_edges, 0, "%s depth %d: %zu edges in more than two triangles",
                 s->expr, dmax, p.nonmanifold_edges);
    cr_expect_eq(p.euler, euler, "%s depth %d: Euler characteristic %ld, expected %ld", s->expr,
                 dmax, p.euler, euler);
    cr_expect_eq(p.components, 1, "%s depth %d: %zu components", s->expr, dmax, p.components);
    double cell = pf_cell(box, dmax);
    cr_expect_leq(p.max_dist, 0.05 * cell, "%s: a vertex is %g from the surface (cell %g)",
                  s->expr, p.max_dist, cell);
    if (area_expect > 0 && dmax >= 7)
        cr_expect_leq(fabs(p.area - area_expect), 0.01 * area_expect,
                      "%s: area %g, expected %g within 1%%", s->expr, p.area, area_expect);
    ism_mesh_free(&m);
    ism_tape_free(t);
}

static const double cube15[6] = {-1.5, -1.5, -1.5, 1.5, 1.5, 1.5};
static const double skew_sphere[6] = {-1.3, -1.1, -1.2, 1.7, 1.4, 1.25};
static const double skew_torus[6] = {-1.4, -1.3, -0.9, 1.6, 1.5, 1.1};
static const double pretzel_box[6] = {-0.5, -1.5, -1.5, 2.5, 1.5, 1.5};
static const double skew_pretzel[6] = {-0.63, -1.37, -1.21, 2.61, 1.52, 1.18};

#define SPHERE_AREA (4 * M_PI)
#define TORUS_AREA (4 * M_PI * M_PI * 1.0 * 0.3)

Test(closed, sphere_depths)
{
    for (int d = 4; d <= 7; d++)
        check_closed(&sphere, cube15, 2, d, 2, SPHERE_AREA);
}

Test(closed, sphere_off_centre_box) { check_closed(&sphere, skew_sphere, 3, 7, 2, SPHERE_AREA); }

Test(closed, sphere_uniform) { check_closed(&sphere, cube15, 6, 6, 2, 0); }

Test(closed, torus_depths)
{
    for (int d = 5; d <= 7; d++)
        check_closed(&torus, cube15, 3, d, 0, TORUS_AREA);
}

Test(closed, torus_off_centre_box) { check_closed(&torus, skew_torus, 3, 8, 0, TORUS_AREA); }

Test(closed, pretzel_genus2)
{
    check_closed(&pretzel, pretzel_box, 3, 7, -2, 0);
    check_closed(&pretzel, skew_pretzel, 3, 8, -2, 0);
}

/* splitmix64: a fixed, portable stream of pseudo-random numbers for the cases below. */
static uint64_t next_random(uint64_t *state)
{
    uint64_t z = (*state += 0x9e3779b97f4a7c15ull);
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
    return z ^ (z >> 31);
}

static double uniform(uint64_t *state, double lo, double hi)
{
    return lo + (hi - lo) * (double)(next_random(state) >> 11) / 9007199254740992.0;
}

/* Writes 0.5 - (sum of 2..5 Gaussian bumps) with random centres and widths: blobs that merge,
 * part, form necks and thin bridges, and pierce lattice lines and faces at every angle. */
static void random_blobs(uint64_t *state, char *out, size_t cap)
{
    int n = 2 + (int)(next_random(state) % 4);
    size_t len = (size_t)snprintf(out, cap, "0.5 - (");
    for (int i = 0; i < n && len < cap; i++) {
        double c[3], s = uniform(state, 0.15, 0.5);
        for (int k = 0; k < 3; k++)
            c[k] = uniform(state, -0.6, 0.6);
        len += (size_t)snprintf(out + len, cap - len, "%sexp(-((x-%.3f)^2+(y-%.3f)^2+(z-%.3f)^2)/%.4f)",
                                i ? " + " : "", c[0], c[1], c[2], s * s);
    }
    if (len < cap)
        snprintf(out + len, cap - len, ")");
}

/* The level set of a smooth function with no critical point on it is a closed manifold,
 * whatever its shape: no boundary edge, no edge in three or more triangles, an even Euler
 * characteristic, vertices on the surface. Random blobs at depths 5 to 8, and one case that
 * once broke it (a bump through a lattice line made a wedge polygon on two faces). */
Test(closed, random_blobs_are_closed_manifolds, .timeout = 120)
{
    char src[1024];
    uint64_t state = 20261122;
    for (int i = 0; i <= 30; i++) {
        if (i < 30)
            random_blobs(&state, src, sizeof src);
        else
            snprintf(src, sizeof src, "0.5 - (exp(-((x-0.299)^2+(y-0.431)^2+(z-0.067)^2)/0.027) + "
                     "exp(-((x-0.372)^2+(y+0.366)^2+(z+0.364)^2)/0.188) + "
                     "exp(-((x-0.512)^2+(y-0.578)^2+(z-0.328)^2)/0.116))");
        int depth = i < 30 ? 5 + i % 4 - pf_quick() : 5;
        const pf_surface s = {src, NULL, 0, NULL, 0};
        ism_tape *t = pf_compile(&s);
        ism_mesh m;
        ism_poly_stats st;
        pf_run(t, cube15, 3, depth, 0, &m, &st);
        pf_props p;
        pf_measure(&m, t, &p);
        cr_expect_eq(p.boundary_edges, 0, "case %d depth %d: %zu boundary edges (%s)", i, depth,
                     p.boundary_edges, src);
        cr_expect_eq(p.nonmanifold_edges, 0, "case %d depth %d: %zu non-manifold edges (%s)", i,
                     depth, p.nonmanifold_edges, src);
        cr_expect_eq(p.euler % 2, 0, "case %d depth %d: odd Euler characteristic %ld (%s)", i,
                     depth, p.euler, src);
        cr_expect_leq(p.max_dist, 0.05 * pf_cell(cube15, depth), "case %d: vertex %g off (%s)", i,
                      p.max_dist, src);
        ism_mesh_free(&m);
        ism_tape_free(t);
    }
}

/* The sphere r = 1.5 in the box ±1.6 passes through lattice points where f's sign is rounding
 * noise: at (±0.2, ±0.5, −1.4) and (±0.5, ±0.2, −1.4) the lattice's −1.6 + 64 × 3.2/2^d is
 * −1.4000000000000001 and f rounds to +4.4e-16 (at z = +1.4 to −4.4e-16). Each lattice
 * segment from such a point found a root 1e-15 away; the node on the negative side cut off
 * its corner by a triangle of those three roots that lies in its lower face in floating point,
 * which that face's owner never emits: 8 holes of three zero-length edges, χ −6 at depth 7
 * (the clipped Barth sextic max(B, r² − 2.25) in the box ±1.6: χ −32, 12 open edges, against
 * −28 in shifted boxes). The lattice point is a zero point where the interval over it holds 0
 * (face_lines.c zero_by_rounding). A sphere: closed, χ 2, one piece, in the lattice box, moved
 * by 1e-3 and by a fraction of a cell; with and without an error bound (primal polygons). */
Test(closed, sphere_through_lattice_points_within_rounding)
{
    static const ism_param r15[] = {{"r", 1.5}};
    const pf_surface s = {"x^2 + y^2 + z^2 - r^2", r15, 1, NULL, 0};
    const double base[6] = {-1.6, -1.6, -1.6, 1.6, 1.6, 1.6};
    ism_tape *t = pf_compile(&s);
    ism_eval_ws *ws = ism_eval_ws_new(t);
    /* the premise: f at the lattice point (0.2, 0.5, −1.4) of the box ±1.6 is not 0, but
     * within rounding (lattice coordinates lo + step × i, the polygoniser's grid.h) */
    double step = 3.2 / 1024, q[3] = {-1.6 + step * 576, -1.6 + step * 672, -1.6 + step * 64};
    double fq = ism_eval_point(t, ws, q[0], q[1], q[2]);
    cr_expect(fq != 0 && fabs(fq) < 1e-15, "f at the lattice point (0.2, 0.5, -1.4): %g", fq);
    ism_eval_ws_free(ws);
    for (int which = pf_first_box() - 1; which < 2; which++)
        for (int run = 0; run < 3; run++) {
            int d = run == 0 ? 7 : 8;
            double box[6];
            pf_sweep_box(base, d, which, box);
            ism_poly_options o;
            pf_options(&o, box, 3, d);
            if (run == 2)
                o.max_error = 3e-3; /* the primal polygons under a bound (o.dual is off) */
            ism_mesh m;
            ism_poly_stats st;
            pf_run_options(t, &o, &m, &st);
            pf_props p;
            pf_measure(&m, t, &p);
            cr_expect_eq(p.boundary_edges + p.nonmanifold_edges, 0,
                         "box %d run %d: %zu boundary, %zu non-manifold edges", which, run,
                         p.boundary_edges, p.nonmanifold_edges);
            cr_expect_eq(p.euler, 2, "box %d run %d: χ %ld", which, run, p.euler);
            cr_expect_eq(p.components, 1, "box %d run %d: %zu pieces", which, run, p.components);
            ism_mesh_free(&m);
        }
    ism_tape_free(t);
}
