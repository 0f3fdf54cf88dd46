/* test_curves_crease.c — creases of nested min/max cut into the mesh (core/curves/crease.c)
 * against closed forms, in the symmetric box and boxes shifted off the lattice by 1e-3 and
 * √2 − 1 of a finest cell. The solid is the intersection of three slabs |n_i·p| ≤ w_i with
 * unit normals off the axes and not orthogonal, f = max(max(n1·p − w1, −n1·p − w1), max(
 * max(...), max(...))): a parallelepiped of 6 faces, 12 edges (lines) and 8 corners, each
 * corner the solution of three plane equations. Checked: the arrangement is 8 corners of
 * degree 3 (within 1e-9 × diagonal of the solved corners), 12 crease edges of the
 * closed-form lengths, 6 faces; every crease vertex within 1e-9 × diagonal of both planes
 * of its edge, its points in order along the edge; the dihedral angle across every crease mesh edge equals the planes' angle;
 * the corner normals on each side of a crease vertex are their own plane's normal. */
#include <criterion/criterion.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include "poly_fixture.h"
#include "core/curves/arrangement.h"
#include "core/curves/crease_normals.h"
#include "core/curves/cut.h"

#define ON_PLANE_REL 1e-9   /* the issue: crease vertices within 1e-9 × diagonal of both */
#define LENGTH_REL 1e-8     /* a crease edge is a chain of points on a line between corners */
#define DIHEDRAL_DEG 0.5    /* triangles of a flat face: their corners on the plane to the
                               polygoniser's root precision */
#define NORMAL_TOL 1e-6     /* float corner normals against the plane's unit normal */

static double n_[3][3], w_[3] = {0.62, 0.5, 0.55};

static void normals(void)
{
    const double raw[3][3] = {{1, 0.2, 0.1}, {-0.15, 1, 0.25}, {0.1, -0.3, 1}};
    for (int i = 0; i < 3; i++) {
        double l = sqrt(raw[i][0] * raw[i][0] + raw[i][1] * raw[i][1] + raw[i][2] * raw[i][2]);
        for (int k = 0; k < 3; k++)
            n_[i][k] = raw[i][k] / l;
    }
}

/* Plane q (0..5): s·n_i·p = w_i with i = q / 2, s = ±1; signed distance s n_i·p − w_i. */
static double plane_dist(int q, const double *p)
{
    int i = q / 2;
    double s = q % 2 ? -1 : 1;
    return s * (n_[i][0] * p[0] + n_[i][1] * p[1] + n_[i][2] * p[2]) - w_[i];
}

/* The corner with signs s (bit i: −n_i side) by Cramer's rule. */
static void corner(int s, double p[3])
{
    double r[3], d = 0;
    for (int i = 0; i < 3; i++)
        r[i] = (s >> i & 1 ? -1 : 1) * w_[i];
    const double(*a)[3] = n_;
    d = a[0][0] * (a[1][1] * a[2][2] - a[1][2] * a[2][1]) -
        a[0][1] * (a[1][0] * a[2][2] - a[1][2] * a[2][0]) +
        a[0][2] * (a[1][0] * a[2][1] - a[1][1] * a[2][0]);
    for (int c = 0; c < 3; c++) {
        double m[3][3];
        memcpy(m, a, sizeof m);
        for (int i = 0; i < 3; i++)
            m[i][c] = r[i];
        p[c] = (m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1]) -
                m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0]) +
                m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0])) / d;
    }
}

static void slab_expr(char *buf, size_t n)
{
    char s[3][400];
    for (int i = 0; i < 3; i++)
        snprintf(s[i], sizeof s[i],
                 "max((%.17g)*x + (%.17g)*y + (%.17g)*z - %.17g, -((%.17g)*x + (%.17g)*y + "
                 "(%.17g)*z) - %.17g)",
                 n_[i][0], n_[i][1], n_[i][2], w_[i], n_[i][0], n_[i][1], n_[i][2], w_[i]);
    snprintf(buf, n, "max(%s, max(%s, %s))", s[0], s[1], s[2]);
}

/* The two planes nearest p (by |distance|). */
static void nearest_planes(const double *p, int q[2], double d[2])
{
    d[0] = d[1] = INFINITY;
    for (int k = 0; k < 6; k++) {
        double a = fabs(plane_dist(k, p));
        if (a < d[0]) {
            d[1] = d[0];
            q[1] = q[0];
            d[0] = a;
            q[0] = k;
        } else if (a < d[1]) {
            d[1] = a;
            q[1] = k;
        }
    }
}

static void plane_normal(int q, double out[3])
{
    for (int k = 0; k < 3; k++)
        out[k] = (q % 2 ? -1 : 1) * n_[q / 2][k];
}

/* The plane a triangle lies on: the one nearest its centroid. */
static int tri_plane(const ism_mesh *m, size_t t)
{
    double c[3] = {0, 0, 0}, d[2];
    for (int i = 0; i < 3; i++)
        for (int k = 0; k < 3; k++)
            c[k] += m->pos[3 * (size_t)m->tri[3 * t + i] + k] / 3;
    int q[2];
    nearest_planes(c, q, d);
    return q[0];
}

/* Crease mesh edges: the triangles on each side agree with their planes. */
static void check_sides(const ism_mesh *m, const ism_cut *cut, const float *cn, double *worst)
{
    for (size_t i = 0; i < cut->nedges; i++) {
        uint32_t a = cut->edges[i].a, b = cut->edges[i].b;
        size_t tris[2], nt = 0;
        int at[2][2];
        for (size_t t = 0; t < m->ntris && nt < 3; t++) {
            const uint32_t *v = m->tri + 3 * t;
            int ia = v[0] == a ? 0 : v[1] == a ? 1 : v[2] == a ? 2 : -1;
            int ib = v[0] == b ? 0 : v[1] == b ? 1 : v[2] == b ? 2 : -1;
            if (ia < 0 || ib < 0)
                continue;
            cr_assert_lt(nt, 2, "crease edge with more than two triangles");
            at[nt][0] = ia;
            at[nt][1] = ib;
            tris[nt++] = t;
        }
        cr_assert_eq(nt, 2, "crease edge %zu has %zu triangles", i, nt);
        int q0 = tri_plane(m, tris[0]), q1 = tri_plane(m, tris[1]);
        cr_assert_neq(q0, q1, "both sides of a crease edge on one plane");
        double t0[3], t1[3], p0[3], p1[3];
        pf_tri_normal(m, tris[0], t0);
        pf_tri_normal(m, tris[1], t1);
        plane_normal(q0, p0);
        plane_normal(q1, p1);
        double d = fabs(pf_vec_angle_deg(t0, t1) - pf_vec_angle_deg(p0, p1));
        *worst = fmax(*worst, d);
        for (int s = 0; s < 2; s++) /* per-side corner normals: the side's own plane */
            for (int e = 0; e < 2; e++) {
                const float *c = cn + 9 * tris[s] + 3 * at[s][e];
                const double *pn = s ? p1 : p0;
                for (int k = 0; k < 3; k++)
                    cr_assert_float_eq(c[k], pn[k], NORMAL_TOL, "corner normal %g vs %g",
                                       c[k], pn[k]);
            }
    }
}

static void parallelepiped(int which)
{
    normals();
    char expr[1400];
    slab_expr(expr, sizeof expr);
    pf_surface surf = {expr, NULL, 0, NULL, 0};
    double box[6] = {-1.3, -1.3, -1.3, 1.3, 1.3, 1.3}, shift_dir[3] = {1.0, 0.61, -0.83};
    int dmax = 7 - pf_quick();
    double s = which == 0 ? 0 : which == 1 ? 1e-3 : PF_IRR * 2.6 / (1 << dmax);
    for (int k = 0; k < 6; k++)
        box[k] += s * shift_dir[k % 3];
    double diag = sqrt(3) * 2.6;
    ism_tape *f = pf_compile(&surf);
    ism_mesh m;
    ism_mesh_init(&m);
    ism_poly_stats st;
    pf_run(f, box, 3, dmax, 1, &m, &st);
    cr_assert(ism_mesh_drop_loose(&m));
    ism_cut_fn crease;
    cr_assert(ism_cut_crease_fn(f, &crease));
    ism_cut_eval ev;
    cr_assert(ism_cut_eval_init(&ev, f, &crease, 1));
    ism_cut cut;
    memset(&cut, 0, sizeof cut);
    cr_assert(ism_cut_mesh(&ev, 1e-13 * diag, &m, &cut));
    ism_cut_eval_free(&ev);
    ism_arrangement arr;
    cr_assert(ism_arrangement_build(&m, &cut, NULL, 0, &arr));
    cr_log_info("slabs %d: %zu tris, %zu crease edges, V %zu E %zu F %zu, unrefined %zu", which,
                m.ntris, cut.nedges, arr.nvertices, arr.nedges, arr.nfaces, cut.unrefined);
    cr_assert_eq(cut.unrefined, 0);
    cr_assert(arr.euler_ok);
    cr_assert_eq(arr.nvertices, 8);
    cr_assert_eq(arr.nedges, 12);
    cr_assert_eq(arr.nfaces, 6);
    for (size_t i = 0; i < 8; i++) { /* each at a solved corner, degree 3 */
        const double *p = m.pos + 3 * (size_t)arr.vertices[i].v;
        double best = INFINITY;
        for (int c = 0; c < 8; c++) {
            double q[3];
            corner(c, q);
            best = fmin(best, sqrt((p[0] - q[0]) * (p[0] - q[0]) + (p[1] - q[1]) * (p[1] - q[1]) +
                                   (p[2] - q[2]) * (p[2] - q[2])));
        }
        cr_assert_leq(best, ON_PLANE_REL * diag, "corner off by %g", best);
        cr_assert_eq(arr.vertices[i].degree, 3);
    }
    double want[12], got[12]; /* the edges' lengths: corners differing in one sign */
    int nw = 0;
    for (int c = 0; c < 8; c++)
        for (int i = 0; i < 3; i++)
            if (!(c >> i & 1)) {
                double p[3], q[3];
                corner(c, p);
                corner(c | 1 << i, q);
                want[nw++] = sqrt((p[0] - q[0]) * (p[0] - q[0]) + (p[1] - q[1]) * (p[1] - q[1]) +
                                  (p[2] - q[2]) * (p[2] - q[2]));
            }
    for (int i = 0; i < 12; i++) { /* its points in order along it: no serration */
        const ism_arr_edge *e = &arr.edges[i];
        const double *p0 = m.pos + 3 * (size_t)arr.chain[e->first];
        const double *p1 = m.pos + 3 * (size_t)arr.chain[e->first + e->count - 1];
        double prev = -INFINITY;
        for (size_t c = 0; c < e->count; c++) {
            const double *q = m.pos + 3 * (size_t)arr.chain[e->first + c];
            double t = 0;
            for (int k = 0; k < 3; k++)
                t += (q[k] - p0[k]) * (p1[k] - p0[k]);
            cr_assert_gt(t, prev, "crease edge %d turns back at point %zu of %zu", i, c,
                         e->count);
            prev = t;
        }
        got[i] = e->length;
    }
    for (int i = 0; i < 12; i++)
        for (int j = i + 1; j < 12; j++) {
            if (want[j] < want[i]) {
                double t = want[i]; want[i] = want[j]; want[j] = t;
            }
            if (got[j] < got[i]) {
                double t = got[i]; got[i] = got[j]; got[j] = t;
            }
        }
    for (int i = 0; i < 12; i++)
        cr_assert_float_eq(got[i], want[i], LENGTH_REL * want[i], "edge %g vs %g", got[i],
                           want[i]);
    double worst_plane = 0;
    for (size_t i = 0; i < cut.nedges; i++) /* every crease vertex on both planes */
        for (int e = 0; e < 2; e++) {
            int q[2];
            double d[2];
            nearest_planes(m.pos + 3 * (size_t)(e ? cut.edges[i].b : cut.edges[i].a), q, d);
            worst_plane = fmax(worst_plane, d[1]);
        }
    cr_assert_leq(worst_plane, ON_PLANE_REL * diag, "crease vertex %g off a plane", worst_plane);
    float *cn = malloc(9 * m.ntris * sizeof *cn);
    cr_assert(ism_crease_corner_normals(f, &m, &cut, cn));
    double worst_angle = 0;
    check_sides(&m, &cut, cn, &worst_angle);
    cr_log_info("slabs %d: crease vertices off their planes by %.2e, dihedral off by %.3f deg",
                which, worst_plane, worst_angle);
    cr_assert_leq(worst_angle, DIHEDRAL_DEG);
    free(cn);
    ism_arrangement_free(&arr);
    ism_cut_free(&cut);
    ism_mesh_free(&m);
    ism_tape_free(f);
}

Test(curves_crease, parallelepiped) { parallelepiped(0); }
Test(curves_crease, parallelepiped_shift_1e3) { parallelepiped(1); }
Test(curves_crease, parallelepiped_shift_037) { parallelepiped(2); }
