/* test_rm_relax_far.c — the relaxation's least step away from features (rm_relax.c
 * far_from_features, rm_pass.relax_far_step; f3bfebb, revD 1). A plane z = c meshed as a
 * triangular lattice of unit edges (a hexagon of radius 4 round the vertex v asked), v pushed
 * 0.15 along x off its lattice point: its step toward its fan's centroid (measured here from
 * the triangles, not by rm_relax.c) lies between the least step near features (0.05 of the
 * fan's mean edge) and the one away from them (0.15). Under a bound on a plane (f cannot
 * crease): v stays where nothing is near, and moves when a corner of its fan is locked or a
 * triangle at a corner is under 10° (a second-ring vertex drawn 0.9 of the way to that
 * corner). The lattice is moved with the placements' boxes (pf_sweep_box's centre): the
 * plane moves with it, so only rounding differs between placements. */
#include <criterion/criterion.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "core/remesh/rm_pass.h"
#include "tests/unit/core/poly_fixture.h"

#define RADIUS 4
#define SIDE (2 * RADIUS + 1)
#define PUSH 0.15    /* v's push along x, of an edge */
#define MIN_STEP 0.05 /* the least steps given the pass: remesh.c's ISM_RM_MIN_STEP, */
#define FAR_STEP 0.15 /* ISM_RM_FAR_STEP */

enum near { NOTHING, LOCKED, NEEDLE };

static bool in_hexagon(int i, int j)
{
    return abs(i) <= RADIUS && abs(j) <= RADIUS && abs(i + j) <= RADIUS;
}

/* The lattice point (i, j) at i a + j b (a = (1, 0), b = (1/2, √3/2)) about c. */
static void point(int i, int j, const double c[3], double x[3])
{
    x[0] = c[0] + i + 0.5 * j;
    x[1] = c[1] + sqrt(3) / 2 * j;
    x[2] = c[2];
}

/* The hexagon's mesh, counter-clockwise seen from +z (∇f's side); id[i][j] its vertices. */
static void lattice(ism_mesh *m, const double c[3], uint32_t id[SIDE][SIDE])
{
    ism_mesh_init(m);
    for (int i = -RADIUS; i <= RADIUS; i++)
        for (int j = -RADIUS; j <= RADIUS; j++) {
            id[i + RADIUS][j + RADIUS] = UINT32_MAX;
            if (!in_hexagon(i, j))
                continue;
            double x[3];
            point(i, j, c, x);
            id[i + RADIUS][j + RADIUS] = ism_mesh_add_vertex(m, x, NULL);
            cr_assert_neq(id[i + RADIUS][j + RADIUS], UINT32_MAX);
        }
    for (int i = -RADIUS; i < RADIUS; i++)
        for (int j = -RADIUS; j < RADIUS; j++) {
            uint32_t p = id[i + RADIUS][j + RADIUS], q = id[i + 1 + RADIUS][j + RADIUS],
                     r = id[i + RADIUS][j + 1 + RADIUS], s = id[i + 1 + RADIUS][j + 1 + RADIUS];
            if (p != UINT32_MAX && q != UINT32_MAX && r != UINT32_MAX)
                cr_assert(ism_mesh_add_triangle(m, p, q, r));
            if (q != UINT32_MAX && s != UINT32_MAX && r != UINT32_MAX)
                cr_assert(ism_mesh_add_triangle(m, q, s, r));
        }
}

/* |v's step| / its spokes' mean length: the area-weighted centroid of its triangles'
 * centroids less v (all in the plane). */
static double step_share(const ism_mesh *m, uint32_t v)
{
    double sum[3] = {0, 0, 0}, area = 0, spokes = 0;
    int n = 0;
    const double *x = m->pos + 3 * (size_t)v;
    for (size_t t = 0; t < m->ntris; t++) {
        const uint32_t *c = m->tri + 3 * t;
        if (c[0] != v && c[1] != v && c[2] != v)
            continue;
        const double *a = m->pos + 3 * (size_t)c[0], *b = m->pos + 3 * (size_t)c[1],
                     *d = m->pos + 3 * (size_t)c[2];
        double w = fabs((b[0] - a[0]) * (d[1] - a[1]) - (b[1] - a[1]) * (d[0] - a[0])) / 2;
        for (int k = 0; k < 2; k++)
            sum[k] += w * (a[k] + b[k] + d[k]) / 3;
        area += w;
        for (int k = 0; k < 3; k++)
            if (c[k] != v) {
                const double *u = m->pos + 3 * (size_t)c[k];
                spokes += hypot(u[0] - x[0], u[1] - x[1]) / 2; /* each spoke in two triangles */
            }
        n++;
    }
    return hypot(sum[0] / area - x[0], sum[1] / area - x[1]) / (spokes / n);
}

/* Whether the pass moves v (at lattice (0, 0), pushed) with `near` beside it. */
static bool moves(const double c[3], enum near near)
{
    char expr[80];
    snprintf(expr, sizeof expr, "z - %.17g", c[2]);
    const pf_surface s = {expr, NULL, 0, NULL, 0};
    ism_tape *t = pf_compile(&s);
    ism_mesh m;
    uint32_t id[SIDE][SIDE];
    lattice(&m, c, id);
    uint32_t v = id[RADIUS][RADIUS], u = id[RADIUS + 1][RADIUS], w = id[RADIUS + 2][RADIUS];
    m.pos[3 * (size_t)v] += PUSH;
    if (near == NEEDLE) /* w 0.9 of the way to u: its triangles at u under 6.4° */
        for (int k = 0; k < 2; k++)
            m.pos[3 * (size_t)w + k] += 0.9 * (m.pos[3 * (size_t)u + k] - m.pos[3 * (size_t)w + k]);
    double share = step_share(&m, v);
    cr_assert(share > MIN_STEP && share < FAR_STEP, "v's step %g of its mean spoke", share);
    ism_remesh_options o = {.f = t, .max_error = 1e-3};
    rm_pass p;
    cr_assert(rm_pass_open(&p, &m, &o, 0));
    cr_assert(!p.may_crease);
    p.bounded = true;
    p.relax_min_step = MIN_STEP;
    p.relax_far_step = FAR_STEP;
    p.active[v] = 1;
    for (uint32_t k = 0; k < p.r.count[v]; k++) { /* nothing locked round v but as asked */
        const uint32_t *tri = m.tri + 3 * (size_t)p.r.vt[p.r.start[v] + k];
        for (int q = 0; q < 3; q++)
            cr_assert(!p.r.locked[tri[q]], "vertex %u locked by the pass", tri[q]);
    }
    if (near == LOCKED)
        p.r.locked[u] = 1;
    double before[3] = {m.pos[3 * (size_t)v], m.pos[3 * (size_t)v + 1], m.pos[3 * (size_t)v + 2]};
    bool moved = rm_relax_vertex(&p, v);
    cr_assert_eq(moved, memcmp(before, m.pos + 3 * (size_t)v, sizeof before) != 0);
    rm_pass_close(&p, m.nverts, m.ntris, NULL);
    ism_mesh_free(&m);
    ism_tape_free(t);
    return moved;
}

Test(rm_relax_far, a_short_step_is_taken_only_near_a_feature)
{
    const double base[6] = {-5, -5, -5, 5, 5, 5};
    for (int which = pf_first_box() - 1; which < 2; which++) {
        double box[6], c[3];
        pf_sweep_box(base, 7, which, box);
        for (int a = 0; a < 3; a++)
            c[a] = (box[a] + box[a + 3]) / 2;
        cr_expect(!moves(c, NOTHING), "placement %d: moved with no feature near", which);
        cr_expect(moves(c, LOCKED), "placement %d: kept beside a locked corner", which);
        cr_expect(moves(c, NEEDLE), "placement %d: kept beside a needle", which);
    }
}
