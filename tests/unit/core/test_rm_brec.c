/* test_rm_brec.c — the quality pass's bounded records (core/remesh/rm_brec.c): a fan point
 * taken from its triangle's record, carried along a move by the bent bound, must lie within
 * the error bound E. The bent bound leans on how fast f's unit normal may turn about the fan;
 * here the surface is a plane with a narrow bump (z = H exp(−ρ²/w²), w a thirtieth of an
 * edge) set where one centroid of the fan goes, far from every vertex: the vertices' normals
 * are the plane's to 1e-40, so a turn rate sampled at them says 0 and the bent bound would
 * carry the centroid's record (on the plane, u ≈ 0) over the bump, 3.5 E off the surface.
 * The check must refuse the move, and every point of a fan it accepts must lie within E by
 * the surface's own distance (a surface of revolution: a one-dimensional minimum over the
 * meridian, sampled and refined in the test). With the bump far away the same move is
 * accepted. The configuration runs in place and moved by 1e-3 and by irrational fractions of
 * an edge (tests/unit/placements.h). */
#include <criterion/criterion.h>
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "core/remesh/rm_bound.h"
#include "core/remesh/rm_brec.h"
#include "core/remesh/rm_memo.h"
#include "core/remesh/rm_pass.h"
#include "tests/unit/core/poly_fixture.h"
#include "tests/unit/placements.h"

/* The grid: GRID × GRID vertices an edge apart, each square split along its diagonal; the
 * middle vertex's fan and its corners lie inside (the outer ring, a boundary, is locked). */
#define GRID 5
#define BUMP_H 0.05
#define BUMP_W 0.03
#define BOUND_E 0.01

typedef struct bump {
    double a, b, c; /* the bump's foot (the plane is z = c) */
} bump;

/* The distance from p to z = c + H exp(−ρ²/w²) about (a, b): the nearest point lies in p's
 * meridian half-plane, at some ρ ≥ 0 — sampled every 1e-4 out to where the surface cannot be
 * nearer than the foot below p, then refined by golden sections about the best sample. */
static double bump_dist(const bump *s, const double p[3])
{
    double r0 = hypot(p[0] - s->a, p[1] - s->b), z0 = p[2] - s->c;
    double reach = r0 + fabs(z0) + BUMP_H + 1e-3;
#define D2(r) (((r) - r0) * ((r) - r0) + (z0 - BUMP_H * exp(-(r) * (r) / (BUMP_W * BUMP_W))) * \
                                             (z0 - BUMP_H * exp(-(r) * (r) / (BUMP_W * BUMP_W))))
    double best = INFINITY, at = 0;
    for (double r = 0; r <= reach; r += 1e-4) {
        double d = D2(r);
        if (d < best)
            best = d, at = r;
    }
    double lo = fmax(0, at - 1e-4), hi = at + 1e-4, g = (sqrt(5) - 1) / 2;
    for (int i = 0; i < 60; i++) {
        double m1 = hi - g * (hi - lo), m2 = lo + g * (hi - lo);
        if (D2(m1) < D2(m2))
            hi = m2;
        else
            lo = m1;
    }
    double r = 0.5 * (lo + hi);
    best = fmin(best, D2(r));
#undef D2
    return sqrt(best);
}

/* The grid moved by off, its middle vertex's index into *v. */
static void grid(ism_mesh *m, const double off[3], uint32_t *v)
{
    ism_mesh_init(m);
    for (int j = 0; j < GRID; j++)
        for (int i = 0; i < GRID; i++) {
            double p[3] = {i - GRID / 2 + off[0], j - GRID / 2 + off[1], off[2]};
            float n[3] = {0, 0, 1};
            cr_assert_neq(ism_mesh_add_vertex(m, p, n), UINT32_MAX);
        }
    for (int j = 0; j + 1 < GRID; j++)
        for (int i = 0; i + 1 < GRID; i++) { /* counter-clockwise seen from +z, where ∇f points */
            uint32_t a = j * GRID + i, b = a + 1, c = a + GRID + 1, d = a + GRID;
            cr_assert(ism_mesh_add_triangle(m, a, b, c) && ism_mesh_add_triangle(m, a, c, d));
        }
    *v = (GRID / 2) * GRID + GRID / 2;
}

/* Whether v's fan check for x accepts, on the grid moved by off with the bump's foot at
 * (a, b) (moved too); the records hold the fan's points as measured with v where it is. With
 * an acceptance every point of the fan with v at x (x, the centroids, the midpoints of the
 * edges at v) must lie within E of the bump's surface; *worst gets the farthest of them,
 * *boxes how many boxes the turn was bounded over. */
static bool fan_check(const double off[3], double a, double b, const double dx[3],
                      double *worst, size_t *boxes)
{
    ism_param par[3] = {{.name = "a", .value = a + off[0]},
                        {.name = "b", .value = b + off[1]},
                        {.name = "c", .value = off[2]}};
    char expr[160];
    snprintf(expr, sizeof expr, "z - c - %.17g * exp(-((x - a)^2 + (y - b)^2) / %.17g)", BUMP_H,
             BUMP_W * BUMP_W);
    pf_surface s = {.expr = expr, .params = par, .nparams = 3};
    ism_tape *t = pf_compile(&s);
    bump surf = {par[0].value, par[1].value, par[2].value};
    ism_mesh m;
    uint32_t v;
    grid(&m, off, &v);
    ism_remesh_options o = {.f = t, .max_error = BOUND_E};
    rm_pass p;
    cr_assert(rm_pass_open(&p, &m, &o, 0));
    p.bounded = true;
    cr_assert(rm_brec_open(&p));
    p.memo = rm_memo_new();
    cr_assert_eq(p.r.count[v], 6);
    for (uint32_t i = 0; i < p.r.count[v]; i++) { /* a free fan: the bent bound may be asked */
        const uint32_t *c = m.tri + 3 * (size_t)p.r.vt[p.r.start[v] + i];
        for (int k = 0; k < 3; k++)
            cr_assert(!p.r.locked[c[k]], "corner %u of the middle fan is locked", c[k]);
    }
    /* the records: every point of the fan measured where it is (the plane's points, u ≈ 0) */
    const double *pos = m.pos + 3 * (size_t)v;
    cr_assert(rm_brec_fan_within(&p, v, pos));
    rm_brec_moved(&p, v, pos);
    double x[3] = {pos[0] + dx[0], pos[1] + dx[1], pos[2] + dx[2]};
    bool ok = rm_brec_fan_within(&p, v, x);
    rm_brec_drop(&p);
    *worst = bump_dist(&surf, x);
    for (uint32_t i = 0; i < p.r.count[v]; i++) {
        uint32_t tri;
        int k;
        double g[3], mid[3];
        rm_fan_point(&p, v, i, x, &tri, &k, g, mid);
        *worst = fmax(*worst, fmax(bump_dist(&surf, g), bump_dist(&surf, mid)));
    }
    *boxes = p.bend_boxes;
    rm_memo_free(p.memo);
    p.memo = NULL;
    size_t nv = m.nverts, nt = m.ntris;
    rm_pass_close(&p, nv, nt, NULL);
    ism_mesh_free(&m);
    ism_tape_free(t);
    return ok;
}

Test(remesh_brec, a_bump_between_the_vertices_is_not_carried_over)
{
    const double offs[3][3] = {{0, 0, 0},
                               {PF_OFF_X, PF_OFF_Y, PF_OFF_Z},
                               {PF_IRR_X, PF_IRR_Y, PF_IRR_Z}};
    /* v moves a quarter edge; the fan's triangle (−1, −1), (0, −1), v: its centroid moves a
       twelfth of an edge, to where the bump stands */
    const double dx[3] = {0.2, 0.15, 0};
    double a = (-1 + 0 + dx[0]) / 3, b = (-1 - 1 + dx[1]) / 3;
    for (int o = 0; o < 3; o++) {
        double worst;
        size_t boxes;
        bool ok = fan_check(offs[o], a, b, dx, &worst, &boxes);
        cr_assert_gt(worst, 3 * BOUND_E, "placement %d: the bump's centroid %g off", o, worst);
        cr_expect(!ok, "placement %d: a fan %g off (E %g) accepted", o, worst, BOUND_E);
        /* the same move, the bump 10 edges away: accepted, every point within E, the bent
           bound asked (the plain one cannot hold a twelfth of an edge within E) */
        ok = fan_check(offs[o], 10, 10, dx, &worst, &boxes);
        cr_expect(ok, "placement %d: the plane's fan refused", o);
        cr_expect_leq(worst, BOUND_E, "placement %d", o);
        cr_expect_gt(boxes, 0, "placement %d: no turn bounded", o);
    }
}

/* The ring torus polygonised (depths 3-5, one thread) in placement which of its ±1.5 box. */
static void torus_mesh(ism_tape *t, int which, ism_mesh *m)
{
    static const double box0[6] = {-1.5, -1.5, -1.5, 1.5, 1.5, 1.5};
    double box[6];
    ism_poly_stats st;
    pf_sweep_box(box0, 5, which, box);
    pf_run(t, box, 3, 5, 1, m, &st);
}

/* Every vertex's first offset is kept when the records open (rm_brec_open, from rm_normals'
 * batch): the record holds the vertex's place, and its offset is what rm_bound_signed
 * measures there one point at a time (no memo: afresh), bit for bit. The vertices of a
 * polygonised ring torus pushed off it along ∇f by 0 to 0.9 of the bound, and one more at the
 * origin, where ∇f vanishes (no offset: infinite both ways); each finite offset is also the
 * torus's closed-form distance to second order (test_rm_distances' 8 d²). In the box on the
 * lattice and both shifted ones. */
Test(remesh_brec, the_first_offsets_kept_at_open_are_the_ones_measured)
{
    ism_tape *t = pf_compile(&pf_ring_torus);
    ism_eval_ws *ws = ism_eval_ws_new(t);
    cr_assert(t && ws);
    for (int which = pf_first_box() - 1; which < 2; which++) {
        double e = 3e-3;
        ism_mesh m;
        torus_mesh(t, which, &m);
        for (size_t v = 0; v < m.nverts; v++) { /* pushed by (v mod 10) tenths of e */
            double *x = m.pos + 3 * v, g[3];
            ism_eval_gradient(t, ws, x[0], x[1], x[2], g);
            double l = sqrt(g[0] * g[0] + g[1] * g[1] + g[2] * g[2]);
            for (int k = 0; k < 3; k++)
                x[k] += (double)(v % 10) / 10 * e * g[k] / l;
        }
        float n0[3] = {0, 0, 1};
        uint32_t origin = ism_mesh_add_vertex(&m, (double[3]){0, 0, 0}, n0);
        cr_assert_neq(origin, UINT32_MAX);
        ism_remesh_options o = {.f = t, .max_error = e};
        rm_pass p;
        cr_assert(rm_pass_open(&p, &m, &o, 0));
        p.bounded = true;
        cr_assert(rm_brec_open(&p));
        size_t finite = 0;
        for (uint32_t v = 0; v < m.nverts; v++) {
            const double *x = m.pos + 3 * (size_t)v;
            cr_assert(memcmp(p.offset + 4 * (size_t)v, x, 3 * sizeof *x) == 0,
                      "vertex %u: no offset kept for its place", v);
            double kept = rm_brec_offset(&p, v), fresh = rm_bound_signed(&p, x);
            cr_assert(memcmp(&kept, &fresh, sizeof kept) == 0,
                      "vertex %u: kept %.17g, measured %.17g", v, kept, fresh);
            if (v == origin) {
                cr_assert(isinf(kept), "the origin's offset %g", kept);
                continue;
            }
            double d = pf_ring_torus_dist(x);
            cr_assert(fabs(fabs(kept) - d) <= 8 * d * d + 1e-15, "vertex %u: offset %.17g, "
                      "distance %.17g", v, kept, d);
            finite++;
        }
        cr_assert_eq(finite, m.nverts - 1);
        rm_pass_close(&p, m.nverts, m.ntris, NULL);
        ism_mesh_free(&m);
    }
    ism_eval_ws_free(ws);
    ism_tape_free(t);
}

/* The offsets kept at open pair each vertex counted when rm_normals measured them with its
 * place; a vertex added after (revD 3: the records opened past rm_pass_open's steps) has
 * none kept, and its offset is measured when asked: rm_bound_signed's afresh, bit for bit,
 * beside the found vertices' kept ones. (Before, the kept values were read up to the mesh's
 * count then: one past their end for the added vertex.) In the three placements. */
Test(remesh_brec, a_vertex_added_after_the_offsets_were_taken_is_measured)
{
    ism_tape *t = pf_compile(&pf_ring_torus);
    cr_assert(t);
    for (int which = pf_first_box() - 1; which < 2; which++) {
        double e = 3e-3;
        ism_mesh m;
        torus_mesh(t, which, &m);
        size_t found = m.nverts;
        ism_remesh_options o = {.f = t, .max_error = e};
        rm_pass p;
        cr_assert(rm_pass_open(&p, &m, &o, 2));
        cr_assert_eq(p.found_offset_n, found);
        /* a point 0.4 E outside the torus's tube (R 1, r 0.3 in pf_ring_torus: on the
           outer equator), not a vertex of the mesh found */
        float n0[3] = {1, 0, 0};
        uint32_t added = ism_mesh_add_vertex(&m, (double[3]){1.3 + 0.4 * e, 0, 0}, n0);
        cr_assert_eq(added, found);
        p.bounded = true;
        cr_assert(rm_brec_open(&p));
        cr_assert_null(p.found_offset);
        for (uint32_t v = 0; v < m.nverts; v++) {
            const double *x = m.pos + 3 * (size_t)v;
            double kept = rm_brec_offset(&p, v), fresh = rm_bound_signed(&p, x);
            cr_assert(memcmp(&kept, &fresh, sizeof kept) == 0,
                      "vertex %u: kept %.17g, measured %.17g", v, kept, fresh);
        }
        double d = pf_ring_torus_dist(m.pos + 3 * (size_t)added);
        cr_assert(fabs(rm_brec_offset(&p, added) - d) <= 8 * d * d + 1e-15);
        rm_pass_close(&p, m.nverts, m.ntris, NULL);
        ism_mesh_free(&m);
    }
    ism_tape_free(t);
}
