/* test_rm_hcell.c — the Hessian cells (core/remesh/rm_hcell.c) that let the quality pass under
 * an error bound leave out a distance measure's second Newton evaluation. At points placed
 * off a torus by 0.3 to 1.2 E along its normal (the closed form), the bound must be at least
 * the second step's term measured with two evaluations, it must be finite at most points (it
 * bounds something), and rm_bound_distance compared with E must answer as the two-step
 * measure does. On the union of two spheres (a min: a crease where they meet) the cells on
 * the crease give no bound. Each configuration runs in place and moved by 1e-3 and by
 * irrational fractions of an edge (tests/unit/placements.h). */
#include <criterion/criterion.h>
#include <math.h>
#include <stdio.h>

#include "core/remesh/rm_bound.h"
#include "core/remesh/rm_hcell.h"
#include "core/remesh/rm_memo.h"
#include "core/remesh/rm_pass.h"
#include "core/util/vec3.h"
#include "tests/unit/core/poly_fixture.h"
#include "tests/unit/placements.h"

#define TORUS_R 1.0
#define TORUS_A 0.4
#define BOUND_E 5e-3
#define GRID_U 48
#define GRID_V 16

/* The torus about (o) with its axis along z: the point at angles u (round the axis) and v
 * (round the tube) and its outward unit normal. */
static void torus_at(const double o[3], double u, double v, double p[3], double n[3])
{
    n[0] = cos(v) * cos(u), n[1] = cos(v) * sin(u), n[2] = sin(v);
    double rho = TORUS_R + TORUS_A * cos(v);
    p[0] = o[0] + rho * cos(u), p[1] = o[1] + rho * sin(u), p[2] = o[2] + TORUS_A * sin(v);
}

/* The torus's parameter grid as a mesh (GRID_U × GRID_V vertices, closed both ways): what
 * the cells are laid over (their side from its mean edge). */
static void torus_mesh(ism_mesh *m, const double o[3])
{
    ism_mesh_init(m);
    for (int j = 0; j < GRID_V; j++)
        for (int i = 0; i < GRID_U; i++) {
            double p[3], n[3];
            torus_at(o, 2 * M_PI * i / GRID_U, 2 * M_PI * j / GRID_V, p, n);
            float fn[3] = {(float)n[0], (float)n[1], (float)n[2]};
            cr_assert_neq(ism_mesh_add_vertex(m, p, fn), UINT32_MAX);
        }
    for (int j = 0; j < GRID_V; j++)
        for (int i = 0; i < GRID_U; i++) {
            uint32_t a = j * GRID_U + i, b = j * GRID_U + (i + 1) % GRID_U;
            uint32_t c = ((j + 1) % GRID_V) * GRID_U + (i + 1) % GRID_U;
            uint32_t d = ((j + 1) % GRID_V) * GRID_U + i;
            cr_assert(ism_mesh_add_triangle(m, a, b, c) && ism_mesh_add_triangle(m, a, c, d));
        }
}

/* The three placements' offsets (the irrational one a tenth of PF_IRR: edges about 0.13). */
static const double OFFS[3][3] = {{0, 0, 0},
                                  {PF_OFF_X, PF_OFF_Y, PF_OFF_Z},
                                  {PF_IRR_X * 0.1, PF_IRR_Y * 0.1, PF_IRR_Z * 0.1}};

/* A pass under the bound E over the torus grid moved by off, for f = expr in x − a, y − b,
 * z − c ((a, b, c) = off), with its memo and cells; hc_close frees it all. */
typedef struct hc_case {
    ism_tape *t;
    ism_mesh m;
    rm_pass p;
} hc_case;

static void hc_open(hc_case *c, const char *expr, const double off[3])
{
    ism_param par[3] = {{.name = "a", .value = off[0]},
                        {.name = "b", .value = off[1]},
                        {.name = "c", .value = off[2]}};
    pf_surface s = {.expr = expr, .params = par, .nparams = 3};
    c->t = pf_compile(&s);
    torus_mesh(&c->m, off);
    ism_remesh_options opt = {.f = c->t, .max_error = BOUND_E};
    cr_assert(rm_pass_open(&c->p, &c->m, &opt, 0));
    c->p.bounded = true;
    c->p.memo = rm_memo_new();
    c->p.hcell = rm_hcell_new(&c->p);
    cr_assert(c->p.hcell);
}

static void hc_close(hc_case *c)
{
    rm_hcell_free(c->p.hcell);
    c->p.hcell = NULL;
    rm_memo_free(c->p.memo);
    c->p.memo = NULL;
    size_t nv = c->m.nverts, nt = c->m.ntris;
    rm_pass_close(&c->p, nv, nt, NULL);
    ism_mesh_free(&c->m);
    ism_tape_free(c->t);
}

/* The two Newton terms at x measured with two evaluations: s1 = f/|∇f| at x, |∇f| there
 * (*gn), and s2 = |f|/|∇f| where the step lands. */
static double second_term(const ism_tape *t, ism_eval_ws *ws, const double x[3], double *s1,
                          double *gn)
{
    double g[3], f = ism_eval_gradient(t, ws, x[0], x[1], x[2], g), g2 = ism_dot3(g, g);
    *gn = sqrt(g2);
    *s1 = f / *gn;
    double y[3], h[3];
    for (int k = 0; k < 3; k++)
        y[k] = x[k] - f / g2 * g[k];
    double fy = ism_eval_gradient(t, ws, y[0], y[1], y[2], h);
    return fabs(fy) / ism_norm3(h);
}

Test(remesh_hcell, the_bound_holds_the_second_step_and_decides_as_it)
{
    for (int o = 0; o < 3; o++) {
        hc_case c;
        hc_open(&c, "((x-a)^2 + (y-b)^2 + (z-c)^2 + 1 - 0.16)^2 - 4 * ((x-a)^2 + (y-b)^2)",
                OFFS[o]);
        rm_pass *p = &c.p;
        ism_eval_ws *ws = ism_eval_ws_new(c.t);
        int asked = 0, bounded = 0, within = 0;
        for (int i = 0; i < 400; i++) {
            double q[3], n[3], x[3], s1, gn;
            double off = BOUND_E * (0.3 + 0.9 * ((i * 7) % 400) / 400.0);
            torus_at(OFFS[o], 0.0157 * i + 0.3, 0.131 * i, q, n);
            for (int k = 0; k < 3; k++)
                x[k] = q[k] + (i % 2 ? off : -off) * n[k];
            double s2 = second_term(c.t, ws, x, &s1, &gn);
            if (!(fabs(s1) <= BOUND_E))
                continue;
            asked++;
            double r = rm_hcell_residual(p, x, s1, gn);
            if (isfinite(r)) {
                bounded++;
                cr_expect_geq(r, s2, "placement %d point %d: bound %g under the term %g", o, i,
                              r, s2);
            }
            /* the exact measure's verdict (rm_bound_distance: one step within its share of E) */
            bool exact = fabs(s1) <= RM_BOUND_ONE_STEP_SHARE * BOUND_E || fabs(s1) + s2 <= BOUND_E;
            bool got = rm_bound_distance(p, x, BOUND_E) <= BOUND_E;
            within += got;
            cr_expect_eq(got, exact, "placement %d point %d: s1 %g s2 %g", o, i, s1, s2);
        }
        cr_expect_gt(asked, 300, "placement %d", o);
        cr_expect_gt(bounded, asked * 9 / 10, "placement %d: %d of %d bounded", o, bounded,
                     asked);
        cr_expect_gt(within, 0, "placement %d", o);
        /* the verdicts above hold with or without the shortcut: it must have been taken */
        size_t n_asked, n_spared;
        rm_hcell_counts(p, &n_asked, &n_spared);
        cr_expect_gt(n_spared, 0, "placement %d: no second step spared", o);
        ism_eval_ws_free(ws);
        hc_close(&c);
    }
}

Test(remesh_hcell, no_bound_where_a_min_switches_branches)
{
    for (int o = 0; o < 3; o++) {
        /* two unit spheres 1.2 apart along x: they meet on the circle x = a, ρ = 0.8 */
        hc_case c;
        hc_open(&c, "min((x-a-0.6)^2 + (y-b)^2 + (z-c)^2, (x-a+0.6)^2 + (y-b)^2 + (z-c)^2) - 1",
                OFFS[o]);
        /* on the crease circle: both branches in the cell */
        double on[3] = {OFFS[o][0], OFFS[o][1] + 0.8, OFFS[o][2]};
        cr_expect(isinf(rm_hcell_residual(&c.p, on, 0.8 * BOUND_E, 1.6)), "placement %d", o);
        /* on the far cap of one sphere: one branch, a bound (|H|_F = 2√3, |∇f| = 2) */
        double far[3] = {OFFS[o][0] + 1.6, OFFS[o][1], OFFS[o][2]};
        double r = rm_hcell_residual(&c.p, far, 0.8 * BOUND_E, 2.0);
        double least = 0.5 * 2 * sqrt(3) * pow(0.8 * BOUND_E, 2) / 2.0;
        cr_expect(isfinite(r) && r >= least, "placement %d: %g (at least %g)", o, r, least);
        hc_close(&c);
    }
}

Test(remesh_hcell, no_bound_where_the_landing_gradient_is_below_the_threshold)
{
    /* The unit sphere f = |x − o|² − 1 (‖H‖_F = 2√3, |∇f| = 2ρ at radius ρ). From radius
     * ρ = 1 + d the Newton step (length (ρ² − 1) / 2ρ, about d) lands at radius (ρ² + 1) / 2ρ,
     * where |∇f| = (ρ² + 1) / ρ ≈ 2 + d²; with the pass's threshold set to 2 + d the first
     * step stands (2 + 2d) and the second finds ∇f vanished, so the measure is INFINITY,
     * while the cells' denominator 2 + 2d − 2√3 d stays positive. */
    const double d = 0.7 * BOUND_E, rho = 1 + d;
    for (int o = 0; o < 3; o++) {
        hc_case c;
        hc_open(&c, "(x-a)^2 + (y-b)^2 + (z-c)^2 - 1", OFFS[o]);
        c.p.gthresh = 2 + d;
        cr_assert_gt(2 * rho, c.p.gthresh);                 /* the first step stands */
        cr_assert_leq((rho * rho + 1) / rho, c.p.gthresh); /* the second does not */
        for (int i = 0; i < 8; i++) {
            double u = 2 * M_PI * i / 8 + 0.1;
            double x[3] = {OFFS[o][0] + rho * cos(u), OFFS[o][1] + rho * sin(u), OFFS[o][2]};
            double got = rm_bound_distance(&c.p, x, BOUND_E);
            cr_expect(isinf(got), "placement %d point %d: %g, the measure rejects it", o, i, got);
        }
        hc_close(&c);
    }
}
