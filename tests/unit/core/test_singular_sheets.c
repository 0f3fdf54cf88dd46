/* test_singular_sheets.c — double sheets (zero sets where f does not change sign) from
 * closed forms: a sphere counted twice, a plane x² = 0, a torus counted twice; and what
 * must give none (a sign-changing sphere, a valley g² + ε). Every geometric case runs in the
 * symmetric box and in boxes shifted off the lattice by 1e-3 and by an irrational fraction of a
 * finest cell. Topology, area, vertex, edge-midpoint and centroid errors are measured here, not
 * taken from the stage. */
#include <criterion/criterion.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include "core/singular/search.h"
#include "core/singular/sheets.h"
#include "poly_fixture.h"

#define SPHERE_R2 0.5

typedef struct run {
    ism_tape *t;
    ism_mesh m;
    ism_locus l;
    double box[6];
    int depth;
} run;

/* Box `base` shifted on every axis by `shift` (shift_cells: in finest cells). */
static void shifted_box(const double base[6], int depth, double shift, bool shift_cells,
                        double out[6])
{
    double s = shift_cells ? shift * pf_cell(base, depth) : shift;
    for (int k = 0; k < 6; k++)
        out[k] = base[k] + s;
}

static void run_sheets(run *r, const char *expr, const double box[6], int depth)
{
    pf_surface s = {expr, NULL, 0, NULL, 0};
    r->t = pf_compile(&s);
    memcpy(r->box, box, sizeof r->box);
    r->depth = depth;
    ism_locus_options o;
    ism_locus_options_default(&o);
    memcpy(o.box, box, sizeof o.box);
    o.max_depth = depth;
    ism_locus_init(&r->l);
    ism_mesh_init(&r->m);
    ism_error err = {0};
    cr_assert(ism_sing_double_sheets(r->t, &o, &r->l, &r->m, &err), "%s: %s", expr, err.message);
    cr_assert(!r->l.incomplete, "%s: incomplete (%s)", expr, r->l.incomplete_why);
}

static void free_run(run *r)
{
    ism_mesh_free(&r->m);
    ism_locus_free(&r->l);
    ism_tape_free(r->t);
}

typedef struct dedge {
    uint32_t a, b;
} dedge;

static int cmp_dedge(const void *x, const void *y)
{
    const dedge *p = x, *q = y;
    if (p->a != q->a)
        return p->a < q->a ? -1 : 1;
    return (p->b > q->b) - (p->b < q->b);
}

/* Directed edges used twice: 0 when neighbouring triangles are oriented alike. */
static size_t misoriented_edges(const ism_mesh *m)
{
    dedge *e = malloc((3 * m->ntris + 1) * sizeof *e);
    cr_assert(e);
    for (size_t t = 0; t < m->ntris; t++)
        for (int k = 0; k < 3; k++)
            e[3 * t + k] = (dedge){m->tri[3 * t + k], m->tri[3 * t + (k + 1) % 3]};
    qsort(e, 3 * m->ntris, sizeof *e, cmp_dedge);
    size_t bad = 0;
    for (size_t i = 1; i < 3 * m->ntris; i++)
        bad += e[i].a == e[i - 1].a && e[i].b == e[i - 1].b;
    free(e);
    return bad;
}

static void tri_normal(const ism_mesh *m, size_t t, double n[3])
{
    const double *a = m->pos + 3 * m->tri[3 * t], *b = m->pos + 3 * m->tri[3 * t + 1],
                 *c = m->pos + 3 * m->tri[3 * t + 2];
    double u[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]};
    double w[3] = {c[0] - a[0], c[1] - a[1], c[2] - a[2]};
    n[0] = u[1] * w[2] - u[2] * w[1];
    n[1] = u[2] * w[0] - u[0] * w[2];
    n[2] = u[0] * w[1] - u[1] * w[0];
}

/* Triangles whose winding disagrees with their vertices' normals (sum of the three). */
static size_t normals_against_winding(const ism_mesh *m)
{
    size_t bad = 0;
    for (size_t t = 0; t < m->ntris; t++) {
        double n[3], s = 0;
        tri_normal(m, t, n);
        for (int k = 0; k < 3; k++) {
            const float *v = m->normal + 3 * m->tri[3 * t + k];
            s += n[0] * v[0] + n[1] * v[1] + n[2] * v[2];
        }
        bad += !(s > 0);
    }
    return bad;
}

/* The locus's sheets cover the mesh's triangles in order, and their areas are the areas
 * of their triangles. */
static void check_records(const run *r, double area)
{
    size_t next = 0;
    double sum = 0;
    for (size_t i = 0; i < r->l.nsheets; i++) {
        cr_expect_eq(r->l.sheets[i].first_triangle, next);
        next += r->l.sheets[i].triangles;
        sum += r->l.sheets[i].area;
    }
    cr_expect_eq(next, r->m.ntris);
    cr_expect_leq(fabs(sum - area), 1e-12 * area, "recorded area %.15g, measured %.15g", sum, area);
}

static double longest_edge(const ism_mesh *m, size_t t)
{
    double l = 0;
    for (int k = 0; k < 3; k++) {
        const double *a = m->pos + 3 * m->tri[3 * t + k], *b = m->pos + 3 * m->tri[3 * t + (k + 1) % 3];
        l = fmax(l, sqrt((a[0] - b[0]) * (a[0] - b[0]) + (a[1] - b[1]) * (a[1] - b[1])
                         + (a[2] - b[2]) * (a[2] - b[2])));
    }
    return l;
}

/* (x²+y²+z²−R²)²: one closed double sheet, the sphere of radius R. Vertices on it within
 * 1e-9. Between vertices, the chord error bounds the rest: for a point c = Σ wᵢvᵢ of a
 * triangle with |vᵢ| = R, |c|² = R² − ½ Σᵢⱼ wᵢwⱼ|vᵢ − vⱼ|², so an edge midpoint lies
 * R − √(R² − ℓ²/4) inside the sphere (ℓ its length) and a centroid at most R − √(R² − L²/3)
 * inside (L the longest edge; Σ_{i≠j} wᵢwⱼ = 2/3). */
static void check_double_sphere(const double box[6], int depth)
{
    run r;
    run_sheets(&r, "(x^2 + y^2 + z^2 - 0.5)^2", box, depth);
    double R = sqrt(SPHERE_R2), cell = pf_cell(box, depth);
    pf_props p;
    pf_measure(&r.m, r.t, &p);
    cr_assert_eq(r.l.nsheets, 1, "%zu double sheets, expected 1", r.l.nsheets);
    cr_expect_gt(p.faces, 1000);
    cr_expect_eq(p.boundary_edges, 0, "%zu boundary edges", p.boundary_edges);
    cr_expect_eq(p.nonmanifold_edges, 0, "%zu non-manifold edges", p.nonmanifold_edges);
    cr_expect_eq(p.euler, 2, "Euler characteristic %ld", p.euler);
    cr_expect_eq(p.components, 1);
    cr_expect_eq(misoriented_edges(&r.m), 0);
    cr_expect_eq(normals_against_winding(&r.m), 0);
    double area = 4 * M_PI * SPHERE_R2;
    cr_expect_leq(fabs(p.area - area), 0.01 * area, "area %g, expected %g", p.area, area);
    check_records(&r, p.area);
    double vmax = 0, nmax = 0, mid_excess = 0, cen_excess = 0, cen_max = 0, lmax = 0;
    for (size_t v = 0; v < r.m.nverts; v++) {
        const double *q = r.m.pos + 3 * v;
        const float *n = r.m.normal + 3 * v;
        double len = sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2]);
        vmax = fmax(vmax, fabs(len - R));
        nmax = fmax(nmax, 1 - fabs((q[0] * n[0] + q[1] * n[1] + q[2] * n[2]) / len));
    }
    for (size_t t = 0; t < r.m.ntris; t++) {
        double c[3] = {0, 0, 0}, L = longest_edge(&r.m, t);
        lmax = fmax(lmax, L);
        for (int k = 0; k < 3; k++) {
            const double *a = r.m.pos + 3 * r.m.tri[3 * t + k],
                         *b = r.m.pos + 3 * r.m.tri[3 * t + (k + 1) % 3];
            double m[3], l2 = 0;
            for (int j = 0; j < 3; j++) {
                m[j] = 0.5 * (a[j] + b[j]);
                c[j] += a[j] / 3;
                l2 += (a[j] - b[j]) * (a[j] - b[j]);
            }
            double d = R - sqrt(m[0] * m[0] + m[1] * m[1] + m[2] * m[2]);
            mid_excess = fmax(mid_excess, fabs(d - (R - sqrt(R * R - l2 / 4))));
        }
        double d = R - sqrt(c[0] * c[0] + c[1] * c[1] + c[2] * c[2]);
        cen_max = fmax(cen_max, fabs(d));
        cen_excess = fmax(cen_excess, d - (R - sqrt(R * R - L * L / 3)));
    }
    cr_expect_leq(vmax, 1e-9, "a vertex is %g off the sphere", vmax);
    cr_expect_leq(nmax, 1e-6, "a normal is %g off radial", nmax);
    cr_expect_leq(mid_excess, 1e-9, "an edge midpoint is %g farther than its chord allows",
                  mid_excess);
    cr_expect_leq(cen_excess, 1e-9, "a centroid is %g farther than its chords allow", cen_excess);
    /* Crossings lie on cell edges or diagonals and move along the normal by less than a
       cell, so no edge is longer than two cell diagonals; the centroid bound is then
       R − √(R² − 4·3·cell²/3) ≈ 2·cell²/R. */
    cr_expect_leq(lmax, 2 * sqrt(3) * cell, "an edge is %g long (cell %g)", lmax, cell);
    cr_expect_leq(cen_max, R - sqrt(R * R - 4 * cell * cell), "a centroid is %g off", cen_max);
    free_run(&r);
}

static const double cube1[6] = {-1, -1, -1, 1, 1, 1};

Test(sheets, double_sphere) { check_double_sphere(cube1, 6); }

Test(sheets, double_sphere_shifted_1e3)
{
    double b[6];
    shifted_box(cube1, 6, 1e-3, false, b);
    check_double_sphere(b, 6);
}

Test(sheets, double_sphere_shifted_037_cell)
{
    double b[6];
    shifted_box(cube1, 6, PF_IRR, true, b);
    check_double_sphere(b, 6);
}

/* x²: the plane x = 0 clipped to the box, an open disc whose boundary lies on the box. */
static void check_double_plane(const double box[6], int depth)
{
    run r;
    run_sheets(&r, "x^2", box, depth);
    pf_props p;
    pf_measure(&r.m, r.t, &p);
    cr_assert_eq(r.l.nsheets, 1, "%zu double sheets, expected 1", r.l.nsheets);
    cr_expect_eq(p.nonmanifold_edges, 0);
    cr_expect_eq(p.euler, 1, "Euler characteristic %ld (a disc: 1)", p.euler);
    cr_expect_eq(p.components, 1);
    cr_expect_eq(misoriented_edges(&r.m), 0);
    cr_expect_eq(normals_against_winding(&r.m), 0);
    double area = (box[4] - box[1]) * (box[5] - box[2]);
    cr_expect_leq(fabs(p.area - area), 1e-9 * area, "area %.15g, expected %.15g", p.area, area);
    check_records(&r, p.area);
    double xmax = 0;
    for (size_t v = 0; v < r.m.nverts; v++)
        xmax = fmax(xmax, fabs(r.m.pos[3 * v]));
    cr_expect_leq(xmax, 1e-12, "a vertex is at x = %g", xmax);
    free_run(&r);
}

static const double plane_box[6] = {-1, -0.8, -0.6, 1, 1.1, 0.7};

Test(sheets, double_plane)
{
    check_double_plane(cube1, 6); /* x = 0 is a lattice plane here */
    check_double_plane(plane_box, 5);
}

Test(sheets, double_plane_shifted)
{
    double b[6];
    shifted_box(cube1, 6, 1e-3, false, b);
    check_double_plane(b, 6);
    shifted_box(plane_box, 5, PF_IRR, true, b);
    check_double_plane(b, 5);
}

/* (g)² of a torus g (R = 0.6, r = 0.25): one closed double sheet of genus 1. */
static void check_double_torus(const double box[6], int depth)
{
    run r;
    run_sheets(&r, "((x^2 + y^2 + z^2 + 0.36 - 0.0625)^2 - 1.44*(x^2 + y^2))^2", box, depth);
    pf_props p;
    pf_measure(&r.m, r.t, &p);
    cr_assert_eq(r.l.nsheets, 1, "%zu double sheets, expected 1", r.l.nsheets);
    cr_expect_eq(p.boundary_edges, 0, "%zu boundary edges", p.boundary_edges);
    cr_expect_eq(p.nonmanifold_edges, 0);
    cr_expect_eq(p.euler, 0, "Euler characteristic %ld", p.euler);
    cr_expect_eq(misoriented_edges(&r.m), 0);
    double area = 4 * M_PI * M_PI * 0.6 * 0.25;
    cr_expect_leq(fabs(p.area - area), 0.01 * area, "area %g, expected %g", p.area, area);
    double dmax = 0; /* distance to the torus: |(√(x²+y²) − R, z)| − r */
    for (size_t v = 0; v < r.m.nverts; v++) {
        const double *q = r.m.pos + 3 * v;
        double rho = sqrt(q[0] * q[0] + q[1] * q[1]) - 0.6;
        dmax = fmax(dmax, fabs(sqrt(rho * rho + q[2] * q[2]) - 0.25));
    }
    cr_expect_leq(dmax, 1e-9, "a vertex is %g off the torus", dmax);
    free_run(&r);
}

/* Runs check at depth 6 in the unit cube, and in it shifted by 1e-3 and by √2 − 1 cell. */
static void in_three_boxes(void (*check)(const double box[6], int depth))
{
    double b[6];
    check(cube1, 6);
    shifted_box(cube1, 6, 1e-3, false, b);
    check(b, 6);
    shifted_box(cube1, 6, PF_IRR, true, b);
    check(b, 6);
}

Test(sheets, double_torus) { in_three_boxes(check_double_torus); }

/* No double sheet: a sphere where f changes sign (the polygoniser's), and a valley whose
 * bottom stays above 0. */
static void check_none(const char *expr, const double box[6], int depth)
{
    run r;
    run_sheets(&r, expr, box, depth);
    cr_expect_eq(r.l.nsheets, 0, "%s: %zu double sheets", expr, r.l.nsheets);
    cr_expect_eq(r.m.ntris, 0, "%s: %zu triangles", expr, r.m.ntris);
    free_run(&r);
}

Test(sheets, sign_change_is_no_double_sheet)
{
    double b[6];
    check_none("x^2 + y^2 + z^2 - 0.5", cube1, 6);
    shifted_box(cube1, 6, PF_IRR, true, b);
    check_none("x^2 + y^2 + z^2 - 0.5", b, 6);
    check_none("(x^2 + y^2 + z^2 - 0.5)^2 + 1e-4", cube1, 6);
    check_none("x^2 + 1e-6", b, 6);
}

/* Runs expr at depth 5 in the unit cube shifted by √2 − 1 of a cell, and measures the mesh. */
static void run_shifted_5(run *r, pf_props *p, const char *expr)
{
    double b[6];
    shifted_box(cube1, 5, PF_IRR, true, b);
    run_sheets(r, expr, b, 5);
    pf_measure(&r->m, r->t, p);
}

/* −(g²)·(2 + x): the same sphere where f ≤ 0 and a positive factor varies; the mesh is
 * closed, its normals agree with its winding. */
Test(sheets, negative_double_sphere)
{
    run r;
    pf_props p;
    run_shifted_5(&r, &p, "-(x^2 + y^2 + z^2 - 0.5)^2 * (2 + x)");
    cr_expect_eq(r.l.nsheets, 1);
    cr_expect_eq(p.boundary_edges + p.nonmanifold_edges, 0);
    cr_expect_eq(p.euler, 2);
    cr_expect_eq(misoriented_edges(&r.m), 0);
    cr_expect_eq(normals_against_winding(&r.m), 0);
    free_run(&r);
}

/* Appending to a mesh that already holds triangles: the sheet's range starts after them
 * and its vertices are its own. */
Test(sheets, appends_after_existing_triangles)
{
    ism_tape *t = pf_compile(&(pf_surface){"x^2", NULL, 0, NULL, 0});
    ism_locus_options o;
    ism_locus_options_default(&o);
    o.max_depth = 4;
    ism_locus l;
    ism_locus_init(&l);
    ism_mesh m;
    ism_mesh_init(&m);
    double p[3] = {0, 0, 0};
    for (int i = 0; i < 3; i++)
        ism_mesh_add_vertex(&m, p, NULL);
    ism_mesh_add_triangle(&m, 0, 1, 2);
    ism_error err = {0};
    cr_assert(ism_sing_double_sheets(t, &o, &l, &m, &err), "%s", err.message);
    cr_assert_eq(l.nsheets, 1);
    cr_expect_eq(l.sheets[0].first_triangle, 1);
    cr_expect_eq(l.sheets[0].triangles, m.ntris - 1);
    for (size_t i = 3; i < 3 * m.ntris; i++)
        cr_expect_geq(m.tri[i], 3, "a sheet triangle uses a vertex that was there before");
    ism_mesh_free(&m);
    ism_locus_free(&l);
    ism_tape_free(t);
}

/* Cut short by cancel, an expired deadline or the cell budget: incomplete with the reason,
 * nothing appended, no error. */
static void check_cut_short(const volatile int *cancel, double deadline_ms, size_t budget,
                            const char *why)
{
    ism_tape *t = pf_compile(&(pf_surface){"(x^2 + y^2 + z^2 - 0.5)^2", NULL, 0, NULL, 0});
    ism_locus_options o;
    ism_locus_options_default(&o);
    o.max_depth = 5;
    o.cancel = cancel;
    o.deadline_ms = deadline_ms;
    o.max_boxes = budget;
    ism_locus l;
    ism_locus_init(&l);
    ism_mesh m;
    ism_mesh_init(&m);
    ism_error err = {0};
    cr_assert(ism_sing_double_sheets(t, &o, &l, &m, &err), "%s", err.message);
    cr_expect(l.incomplete, "%s: not marked incomplete", why);
    cr_expect(strstr(l.incomplete_why, why), "reason '%s', expected '%s'", l.incomplete_why, why);
    cr_expect_eq(m.ntris, 0);
    cr_expect_eq(l.nsheets, 0);
    ism_mesh_free(&m);
    ism_locus_free(&l);
    ism_tape_free(t);
}

Test(sheets, cut_short)
{
    static const volatile int cancelled = 1;
    check_cut_short(&cancelled, 0, 1000000, "cancelled");
    check_cut_short(NULL, 1, 1000000, "deadline"); /* 1 ms after the clock's origin: past */
    check_cut_short(NULL, 0, 10, "budget");
}

/* The same mesh, bit for bit, whatever the number of threads. */
Test(sheets, threads_do_not_change_the_mesh)
{
    ism_tape *t = pf_compile(&(pf_surface){"(x^2 + y^2 + z^2 - 0.5)^2", NULL, 0, NULL, 0});
    ism_mesh m[2];
    for (int i = 0; i < 2; i++) {
        ism_locus_options o;
        ism_locus_options_default(&o);
        o.max_depth = 5;
        o.threads = i ? 3 : 1;
        ism_locus l;
        ism_locus_init(&l);
        ism_mesh_init(&m[i]);
        ism_error err = {0};
        cr_assert(ism_sing_double_sheets(t, &o, &l, &m[i], &err));
        ism_locus_free(&l);
    }
    cr_assert_eq(m[0].nverts, m[1].nverts);
    cr_assert_eq(m[0].ntris, m[1].ntris);
    cr_expect(!memcmp(m[0].pos, m[1].pos, 3 * m[0].nverts * sizeof *m[0].pos));
    cr_expect(!memcmp(m[0].tri, m[1].tri, 3 * m[0].ntris * sizeof *m[0].tri));
    ism_mesh_free(&m[0]);
    ism_mesh_free(&m[1]);
    ism_tape_free(t);
}

/* Candidates from the singular search instead of the stage's own octree: the same sheet
 * (triangles, area), and the search boxes it meshed are flagged as explained. */
Test(sheets, from_search_boxes)
{
    run r;
    pf_props p;
    run_shifted_5(&r, &p, "(x^2 + y^2 + z^2 - 0.5)^2");
    ism_locus_options o;
    ism_locus_options_default(&o);
    memcpy(o.box, r.box, sizeof o.box);
    o.max_depth = 5;
    ism_locus l;
    ism_locus_init(&l);
    ism_mesh m;
    ism_mesh_init(&m);
    ism_error err = {0};
    cr_assert(ism_sing_search(r.t, &o, &l, &err), "%s", err.message);
    cr_assert_gt(l.nboxes, 0);
    cr_assert(ism_sing_double_sheets_from_search(r.t, &o, &l, &m, &err), "%s", err.message);
    cr_expect_eq(l.nsheets, 1);
    cr_expect_eq(m.ntris, r.m.ntris);
    pf_props q;
    pf_measure(&m, r.t, &q);
    cr_expect_leq(fabs(q.area - p.area), 1e-12 * p.area, "area %.15g, own octree %.15g", q.area,
                  p.area);
    cr_expect_eq(q.euler, 2);
    size_t used = 0;
    for (size_t i = 0; i < l.nboxes; i++)
        used += (l.boxes[i].flags & ISM_LBOX_USED) != 0;
    cr_expect_gt(used, l.nboxes / 2, "%zu of %zu boxes explained", used, l.nboxes);
    ism_mesh_free(&m);
    ism_locus_free(&l);
    free_run(&r);
}

/* g²·(z − 0.3): the sphere stays a double sheet above and below the plane z = 0.3, where f
 * changes sign (the polygoniser's plane). Within two cells of the plane the Hessian's
 * direction turns from ∇g toward ∇h and the sheet's border there is ragged (holes of a
 * cell), so what is asserted is: vertices on the sphere, a manifold, consistently oriented
 * mesh; the sheets above z₀ cover the cap minus at most a band of two cells,
 * 2πR(R − z₀) − 4πR·cell ≤ area ≤ 2πR(R − z₀), likewise below; and it is one sheet on
 * each side (no scraps of a few cells along the plane). */
static void check_sphere_cut_by_plane(const double box[6], int depth)
{
    run r;
    run_sheets(&r, "(x^2 + y^2 + z^2 - 0.5)^2 * (z - 0.3)", box, depth);
    double R = sqrt(SPHERE_R2), z0 = 0.3, cell = pf_cell(box, depth);
    double side[2] = {0, 0}, vmax = 0;
    int count[2] = {0, 0};
    for (size_t s = 0; s < r.l.nsheets; s++) {
        const ism_double_sheet *d = &r.l.sheets[s];
        int up = r.m.pos[3 * r.m.tri[3 * d->first_triangle] + 2] > z0;
        side[up] += d->area;
        count[up]++;
    }
    for (size_t v = 0; v < r.m.nverts; v++) {
        const double *q = r.m.pos + 3 * v;
        vmax = fmax(vmax, fabs(sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2]) - R));
    }
    double full[2] = {2 * M_PI * R * (R + z0), 2 * M_PI * R * (R - z0)};
    double band = 2 * M_PI * R * 2 * cell;
    for (int up = 0; up < 2; up++) {
        cr_expect(side[up] <= full[up] && side[up] >= full[up] - band,
                  "%s: area %g, expected %g less at most %g", up ? "above" : "below", side[up],
                  full[up], band);
        cr_expect_eq(count[up], 1, "%s: %d sheets", up ? "above" : "below", count[up]);
    }
    cr_expect_leq(vmax, 1e-9);
    pf_props p;
    pf_measure(&r.m, r.t, &p);
    cr_expect_eq(p.nonmanifold_edges, 0);
    cr_expect_eq(misoriented_edges(&r.m), 0);
    free_run(&r);
}

Test(sheets, sphere_cut_by_a_sign_change) { in_three_boxes(check_sphere_cut_by_plane); }
