/* test_crease_min_max.c — a CSG crease meshes the same whether f's top is min or max: the
 * union of the unit ball and a ball of radius 0.1 at (1.05, 0, 0) written as min(a, b)
 * (inside f < 0) and as max(−a, −b) (the same zero set, the inside where f > 0) under an
 * error bound, each in the lattice box and boxes shifted by 1e-3 and by an irrational fraction
 * of a finest cell. Closed forms: every crease vertex lies on both spheres (|p| = 1, |p − c| =
 * 0.1) within 1e-9 × the diagonal, and at every crease edge the normals each side carries meet
 * at the spheres' angle, acos((1 − |c|² + r²) / 2r) = 117.5°, within 2°; both meshes are closed
 * spheres (χ 2, one piece), no cell misses the bound, and their triangle counts agree within
 * EQUIV_TRIS_REL. The small ball's normals turn fast, so a crease cell judged by the wrong
 * branch's normals (min's dominated one) shows in the count.
 * A crease that never meets the surface (max(a, b) with b < 0 all over the box, active only
 * inside it; min(a, b) with b > 0) leaves f = 0 a's zero set: its primal polygons are as
 * coarse as a's own (no more than 1.05x as many). */
#include <criterion/criterion.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include "poly_fixture.h"
#include "core/curves/crease_normals.h"
#include "core/curves/cut.h"
#include "core/curves/cut_fn.h"
#include "core/eval/eval.h"
#include "core/octree/crease_split.h"
#include "core/singular/surface.h"

#define SEP 1.05              /* the second ball's centre (SEP, 0, 0) */
#define RAD 0.1               /* the second ball's radius (the first's is 1) */
#define MESH_E 1e-2           /* the error bound */
#define DEPTH 9               /* finest cell 2.6 / 512 = 0.005: E, not depth, sets the mesh */
#define CREASE_TOL_REL 1e-9   /* crease vertices on both spheres within this × the diagonal */
#define DIHEDRAL_DEG 2.0      /* carried normals' angle vs the spheres' closed-form angle */
/* min and max forms: triangle counts within 1% (measured: equal on the lattice, 4 apart of
 * 2470 at 0.37 cell; with min's branch read as the larger value, min gave 2264 vs 2408 on
 * the lattice: crease cells were judged by the dominated ball's normals, not the small
 * ball's, which turn by more than acos(flat_normal) across them) */
#define EQUIV_TRIS_REL 0.01

static const pf_surface as_min = {
    "min(x^2 + y^2 + z^2 - 1, (x - 1.05)^2 + y^2 + z^2 - 0.01)", NULL, 0, NULL, 0};
static const pf_surface as_max = {
    "max(-(x^2 + y^2 + z^2 - 1), -((x - 1.05)^2 + y^2 + z^2 - 0.01))", NULL, 0, NULL, 0};

typedef struct crease_run {
    size_t ntris, crease_edges, missed;
    long euler;
    size_t components;
    double worst_sphere, worst_dihedral, diag;
} crease_run;

/* The two triangles holding edge a-b (n: how many, up to 2 recorded). */
static size_t edge_tris(const ism_mesh *m, uint32_t a, uint32_t b, size_t t2[2])
{
    size_t n = 0;
    for (size_t t = 0; t < m->ntris; t++) {
        const uint32_t *v = m->tri + 3 * t;
        bool ha = v[0] == a || v[1] == a || v[2] == a, hb = v[0] == b || v[1] == b || v[2] == b;
        if (ha && hb && n++ < 2)
            t2[n - 1] = t;
    }
    return n;
}

static const float *corner_normal(const ism_mesh *m, const float *cn, size_t t, uint32_t v)
{
    int i = m->tri[3 * t] == v ? 0 : m->tri[3 * t + 1] == v ? 1 : 2;
    return cn + 9 * t + 3 * i;
}

/* m cut along f's crease (Newton to a thousandth of the crease tolerance × diag). */
static void cut_crease(const ism_tape *t, double diag, ism_mesh *m, ism_cut *cut)
{
    ism_cut_fn crease;
    cr_assert(ism_cut_crease_fn(t, &crease));
    ism_cut_eval ev;
    cr_assert(ism_cut_eval_init(&ev, t, &crease, 1));
    memset(cut, 0, sizeof *cut);
    cr_assert(ism_cut_mesh(&ev, 1e-3 * CREASE_TOL_REL * diag, m, cut));
    ism_cut_eval_free(&ev);
}

/* Polygonises t under o into m (loose pieces dropped) and measures it into p. */
static void mesh_measured(const ism_tape *t, const ism_poly_options *o, ism_mesh *m,
                          ism_poly_stats *st, pf_props *p)
{
    ism_error err;
    ism_mesh_init(m);
    cr_assert_eq(ism_polygonise(t, o, m, st, &err), ISM_POLY_OK, "%s", err.message);
    cr_assert(ism_mesh_drop_loose(m));
    pf_measure(m, t, p);
}

static void mesh_crease(const pf_surface *s, const double box[6], crease_run *r)
{
    ism_tape *t = pf_compile(s);
    ism_poly_options o;
    ism_poly_options_default(&o);
    memcpy(o.box, box, sizeof o.box);
    o.min_depth = 3, o.max_depth = DEPTH, o.max_error = MESH_E;
    ism_poly_stats st;
    ism_mesh m;
    pf_props p;
    mesh_measured(t, &o, &m, &st, &p);
    memset(r, 0, sizeof *r);
    r->ntris = m.ntris, r->euler = p.euler, r->components = p.components;
    r->missed = (size_t)st.error_missed_nodes;
    r->diag = sqrt(3) * (box[3] - box[0]);
    ism_cut cut;
    cut_crease(t, r->diag, &m, &cut);
    float *cn = malloc(9 * m.ntris * sizeof *cn);
    cr_assert(ism_crease_corner_normals(t, &m, &cut, cn));
    const double cos_spheres = (1 - SEP * SEP + RAD * RAD) / (2 * RAD);
    const double want = acos(cos_spheres) * 180 / M_PI;
    r->crease_edges = cut.nedges;
    for (size_t i = 0; i < cut.nedges; i++) {
        uint32_t ends[2] = {cut.edges[i].a, cut.edges[i].b};
        for (int e = 0; e < 2; e++) {
            const double *q = m.pos + 3 * (size_t)ends[e];
            double r0 = sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2]);
            double r1 = sqrt((q[0] - SEP) * (q[0] - SEP) + q[1] * q[1] + q[2] * q[2]);
            r->worst_sphere = fmax(r->worst_sphere, fmax(fabs(r0 - 1), fabs(r1 - RAD)));
        }
        size_t t2[2];
        if (edge_tris(&m, ends[0], ends[1], t2) != 2)
            continue;
        for (int e = 0; e < 2; e++) {
            const float *n0 = corner_normal(&m, cn, t2[0], ends[e]),
                        *n1 = corner_normal(&m, cn, t2[1], ends[e]);
            double d0[3] = {n0[0], n0[1], n0[2]}, d1[3] = {n1[0], n1[1], n1[2]};
            r->worst_dihedral = fmax(r->worst_dihedral, fabs(pf_vec_angle_deg(d0, d1) - want));
        }
    }
    free(cn);
    ism_cut_free(&cut);
    ism_mesh_free(&m);
    ism_tape_free(t);
}

static void expect_crease(const crease_run *r, const char *form, int w)
{
    cr_log_info("%s box %d: %zu triangles, χ %ld, %zu pieces, %zu missed, %zu crease edges, "
                "sphere %.3g, dihedral %.3g deg", form, w, r->ntris, r->euler, r->components,
                r->missed, r->crease_edges, r->worst_sphere, r->worst_dihedral);
    cr_expect_eq(r->euler, 2, "%s box %d: χ %ld", form, w, r->euler);
    cr_expect_eq(r->components, 1, "%s box %d", form, w);
    cr_expect_eq(r->missed, 0, "%s box %d: %zu cells missed E", form, w, r->missed);
    cr_expect_gt(r->crease_edges, 50, "%s box %d", form, w);
    cr_expect_leq(r->worst_sphere, CREASE_TOL_REL * r->diag, "%s box %d: %g", form, w,
                  r->worst_sphere);
    cr_expect_leq(r->worst_dihedral, DIHEDRAL_DEG, "%s box %d: %g deg", form, w,
                  r->worst_dihedral);
}

Test(crease_min_max, two_balls_min_and_max_forms_agree)
{
    const double base[6] = {-1.3, -1.3, -1.3, 1.7, 1.3, 1.3};
    for (int w = pf_first_box() - 1; w < 2; w++) {
        double box[6];
        pf_sweep_box(base, DEPTH, w, box);
        crease_run rmin, rmax;
        mesh_crease(&as_min, box, &rmin);
        mesh_crease(&as_max, box, &rmax);
        expect_crease(&rmin, "min", w);
        expect_crease(&rmax, "max", w);
        double lo = fmin(rmin.ntris, rmax.ntris), hi = fmax(rmin.ntris, rmax.ntris);
        cr_expect_leq(hi - lo, EQUIV_TRIS_REL * lo, "box %d: min %zu, max %zu triangles", w,
                      rmin.ntris, rmax.ntris);
    }
}

/* ism_crease_branch names the branch whose value f takes — min's smaller, max's larger — and
 * hands back that branch's gradient, for both forms, at points on either side of the crease
 * and across the box (closed forms: a = |p|² − 1, b = |p − c|² − RAD², ∇a = 2p, ∇b = 2(p − c)).
 * It once named the larger for min too: the dominated branch, whose gradients crease_cell
 * then compared at the corners the other branch owns. */
Test(crease_min_max, branch_is_the_one_f_takes)
{
    const pf_surface forms[2] = {as_min, as_max};
    for (int fm = 0; fm < 2; fm++) {
        ism_tape *t = pf_compile(&forms[fm]);
        ism_sampler s = {.tape = t, .ws = ism_eval_ws_new(t)};
        for (int i = 0; i < 9 * 9 * 9; i++) {
            double p[3] = {-1.3 + 0.37 * (i % 9), -1.3 + 0.31 * (i / 9 % 9),
                           -1.3 + 0.29 * (i / 81)};
            double c[2][3] = {{0, 0, 0}, {SEP, 0, 0}}, v[2], g[2][3];
            for (int b = 0; b < 2; b++) {
                double sgn = fm == 0 ? 1 : -1; /* the max form's branches are −a, −b */
                v[b] = -(b ? RAD * RAD : 1);
                for (int k = 0; k < 3; k++) {
                    v[b] += (p[k] - c[b][k]) * (p[k] - c[b][k]);
                    g[b][k] = sgn * 2 * (p[k] - c[b][k]);
                }
                v[b] *= sgn;
            }
            if (fabs(v[0] - v[1]) < 1e-9)
                continue; /* a tie: either branch */
            int want = fm == 0 ? v[1] < v[0] : v[1] > v[0]; /* the tape may swap a, b */
            double got_g[3];
            int label = ism_crease_branch(&s, p, got_g);
            cr_assert_geq(label, 0);
            cr_assert_eq(ism_crease_branch(&s, p, NULL), label);
            for (int k = 0; k < 3; k++)
                cr_assert_float_eq(got_g[k], g[want][k], 1e-12, "%s at (%g, %g, %g)",
                                   forms[fm].expr, p[0], p[1], p[2]);
        }
        ism_eval_ws_free(s.ws);
        ism_tape_free(t);
    }
}

/* Two unit balls centred 0.8 apart, box −1.3..2.1: the crease circle lies in the plane
 * x = 0.4, a lattice plane of the box (its middle), radius √0.84. Under an error bound the
 * polygoniser puts a crease point in each leaf meeting the crease (crease_split.h); on the
 * lattice plane f ties exactly at all of them, the copies of one point lie a rounding apart,
 * joined by triangles of no area, and no triangle edge had a branch on both sides: 0 crease
 * edges at depth 5, one 0.04 long at depth 6. Checked in the lattice box and the boxes
 * shifted by 1e-3 and by an irrational fraction of a finest cell: the crease edges form one
 * closed chain, their vertices within 1e-9 × diagonal of both spheres, and the circle's length
 * from the mesh — each chord's arc 2r asin(c / 2r) summed — equals 2πr within LATTICE_ARC_REL,
 * and the chords' sum falls short of 2πr by between Σ c³ / 24r² and twice that (arc − chord of a
 * chord c ≤ r: c³ / 24r² + 3c⁵ / 640r⁴ + ...). Every vertex of the cut mesh is a corner of a
 * triangle or a segment's end: the tie copies welded before the cut are dropped (they were loose
 * points in the PLY/OBJ outputs). */
#define LATTICE_SEP 0.8
#define LATTICE_DEPTH 5
#define LATTICE_E 1e-3
/* Arc sum against 2πr: vertices on the circle to Newton's precision (1e-12 of the diagonal)
 * make the arcs exact to rounding; one missing or doubled-back edge is a whole chord's arc,
 * ~0.1 of a radian here. */
#define LATTICE_ARC_REL 1e-8

static void lattice_crease(int w)
{
    const double base[6] = {-1.3, -1.3, -1.3, 2.1, 2.1, 2.1};
    double box[6];
    pf_sweep_box(base, LATTICE_DEPTH, w, box);
    const pf_surface s = {"min(x^2 + y^2 + z^2 - 1, (x - 0.8)^2 + y^2 + z^2 - 1)", NULL, 0,
                          NULL, 0};
    ism_tape *t = pf_compile(&s);
    ism_mesh m;
    ism_locus l;
    pf_run_surface_bounded(t, box, 3, LATTICE_DEPTH, LATTICE_E, &m, &l);
    double diag = sqrt(3) * (box[3] - box[0]), r = sqrt(1 - 0.25 * LATTICE_SEP * LATTICE_SEP);
    ism_cut cut;
    cut_crease(t, diag, &m, &cut);
    uint8_t *deg = calloc(m.nverts, 1);
    double arcs = 0, chords = 0, short_by = 0, worst = 0;
    for (size_t i = 0; i < cut.nedges; i++) {
        const double *p = m.pos + 3 * (size_t)cut.edges[i].a;
        const double *q = m.pos + 3 * (size_t)cut.edges[i].b;
        for (int e = 0; e < 2; e++) {
            const double *v = e ? q : p;
            double r0 = sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
            const double dx = v[0] - LATTICE_SEP;
            double r1 = sqrt(dx * dx + v[1] * v[1] + v[2] * v[2]);
            worst = fmax(worst, fmax(fabs(r0 - 1), fabs(r1 - 1)));
            deg[e ? cut.edges[i].b : cut.edges[i].a]++;
        }
        double c = sqrt((p[0] - q[0]) * (p[0] - q[0]) + (p[1] - q[1]) * (p[1] - q[1]) +
                        (p[2] - q[2]) * (p[2] - q[2]));
        chords += c;
        arcs += 2 * r * asin(fmin(1, c / (2 * r)));
        short_by += c * c * c / (24 * r * r);
    }
    size_t odd = 0;
    for (size_t v = 0; v < m.nverts; v++)
        odd += deg[v] != 0 && deg[v] != 2;
    cr_log_info("lattice crease box %d: %zu crease edges, arcs %.12f chords %.9f (2πr %.12f), "
                "off the spheres %.2e", w, cut.nedges, arcs, chords, 2 * M_PI * r, worst);
    cr_expect_gt(cut.nedges, 20, "box %d", w);
    cr_expect_eq(odd, 0, "box %d: %zu crease vertices not on exactly two crease edges", w, odd);
    cr_expect_leq(worst, CREASE_TOL_REL * diag, "box %d: %g", w, worst);
    cr_expect_float_eq(arcs, 2 * M_PI * r, LATTICE_ARC_REL * 2 * M_PI * r, "box %d: %.12f", w,
                       arcs);
    cr_expect_leq(chords, 2 * M_PI * r - short_by, "box %d: %.9f", w, chords);
    cr_expect_geq(chords, 2 * M_PI * r - 2 * short_by, "box %d: %.9f", w, chords);
    size_t loose = 0, welded = 0; /* every vertex a corner, a segment's end or the crease's */
    uint8_t *used = calloc(m.nverts + 1, 1);
    for (size_t i = 0; i < 3 * m.ntris; i++)
        used[m.tri[i]] = 1;
    for (size_t i = 0; i < 2 * m.nsegs; i++)
        used[m.seg[i]] = 1;
    for (size_t v = 0; v < m.nverts; v++) {
        loose += !used[v] && !deg[v];
        welded += !used[v];
    }
    cr_expect_eq(loose + welded, 0, "box %d: %zu of %zu vertices loose (%zu not in a triangle)",
                 w, loose, m.nverts, welded);
    free(used);
    free(deg);
    ism_cut_free(&cut);
    ism_locus_free(&l);
    ism_mesh_free(&m);
    ism_tape_free(t);
}

Test(crease_min_max, crease_on_a_lattice_plane)
{
    for (int w = pf_first_box() - 1; w < 2; w++)
        lattice_crease(w);
}

/* The unit sphere a = |p|² − 1 and max(a, b) with b = x / 100 − 0.3, below 0 all over the
 * box: the same zero set (max(a, b) = 0 exactly where a = 0, with a's sign), but b is the
 * active branch inside r² < 0.7 + x / 100, a crease 0.16 inside the sphere. Nodes straddling
 * the sphere have corners on both branches (crease cells, plot_test.c), and the sphere's
 * corner gradients there disagree beyond acos(flat_normal) at the nodes E allows; they were
 * split until they agreed, whatever E (at E 3e-2, depth.max 8: 1,256 / 1,328 / 1,304
 * triangles in the three boxes against a's 344 in each). Now b's interval over the box
 * proves it below 0 and a's zero set one graph (graph_cert.h): each box's mesh is a closed
 * sphere (χ 2, one piece) with every centroid and edge midpoint within E of it (closed form
 * ||p| − 1|), no node missing E, and no more than HUG_TRIS_REL of a's own primal polygons
 * in that box. The same under min(a, b) with b above 0 (the crease outside the sphere), and
 * with a curved b (−0.3 − x²/100, 0.3 + x²/100) whose gradient vanishes on a lattice plane. */
#define HUG_E 3e-2
#define HUG_DEPTH 8
#define HUG_TRIS_REL 1.05

static size_t primal_sphere(const pf_surface *s, const double box[6], double *worst, long *euler,
                            size_t *pieces)
{
    ism_tape *t = pf_compile(s);
    ism_poly_options o;
    ism_poly_options_default(&o);
    memcpy(o.box, box, sizeof o.box);
    o.max_depth = HUG_DEPTH, o.max_error = HUG_E, o.dual = false;
    ism_poly_stats st;
    ism_mesh m;
    pf_props p;
    mesh_measured(t, &o, &m, &st, &p);
    cr_expect_eq(st.error_missed_nodes, 0, "%s: %zu nodes miss E", s->expr,
                 (size_t)st.error_missed_nodes);
    *euler = p.euler, *pieces = p.components, *worst = 0;
    for (size_t i = 0; i < m.ntris; i++) {
        const double *v[3];
        for (int j = 0; j < 3; j++)
            v[j] = m.pos + 3 * (size_t)m.tri[3 * i + j];
        for (int j = 0; j < 4; j++) { /* three edge midpoints, then the centroid */
            double q[3];
            for (int a = 0; a < 3; a++)
                q[a] = j == 3 ? (v[0][a] + v[1][a] + v[2][a]) / 3
                              : 0.5 * (v[j][a] + v[(j + 1) % 3][a]);
            *worst = fmax(*worst, fabs(sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2]) - 1));
        }
    }
    size_t n = m.ntris;
    ism_mesh_free(&m);
    ism_tape_free(t);
    return n;
}

/* Which operand of f's top min/max (0 a, 1 b, as the compiler ordered them) is the sphere
 * over the box: the one whose interval holds 0 (the plane's lies wholly on one side of 0);
 * -1 if neither or both. */
static int sphere_operand(const pf_surface *s, const double box[6])
{
    ism_tape *t = pf_compile(s);
    ism_eval_ws *ws = ism_eval_ws_new(t);
    ism_interval v[2];
    int top = ism_eval_interval_top(t, ws, (ism_interval){box[0], box[3]},
                                    (ism_interval){box[1], box[4]},
                                    (ism_interval){box[2], box[5]}, v);
    int in[2] = {0, 0};
    for (int k = 0; k < 2; k++)
        in[k] = v[k].lo < 0 && v[k].hi > 0;
    ism_eval_ws_free(ws);
    ism_tape_free(t);
    return top < 0 || in[0] == in[1] ? -1 : in[1];
}

Test(crease_min_max, crease_off_the_surface_costs_nothing)
{
    static const pf_surface sphere = {"x^2 + y^2 + z^2 - 1", NULL, 0, NULL, 0};
    /* The plane below 0 under max, above 0 under min (there the crease lies outside the
     * sphere), spelled so that the compiler's operand order (by structural hash) puts the
     * sphere second in one form and first in the other of each: the certificate forces branch
     * B, then A (sphere_operand checks it). */
    static const pf_surface hugged[] = {
        {"max(x^2 + y^2 + z^2 - 1, x / 100 - 0.3)", NULL, 0, NULL, 0},
        {"max(x^2 + y^2 + z^2 - 1, x / 100 - 0.5)", NULL, 0, NULL, 0},
        {"min(x^2 + y^2 + z^2 - 1, 0.3 - x / 100)", NULL, 0, NULL, 0},
        {"min(x^2 + y^2 + z^2 - 1, 0.3 - z / 100)", NULL, 0, NULL, 0},
        /* curved: the other operand's gradient vanishes on x = 0, a lattice plane of the
         * base box, at corners inside the sphere (its branch active there): such a corner
         * was taken for a singular one and its nodes split, 1,016 and 1,112 triangles in
         * the base box (plot_test.c, crease_cell) */
        {"max(x^2 + y^2 + z^2 - 1, -0.3 - x^2 / 100)", NULL, 0, NULL, 0},
        {"min(x^2 + y^2 + z^2 - 1, 0.3 + x^2 / 100)", NULL, 0, NULL, 0},
    };
    enum { NH = sizeof hugged / sizeof hugged[0] };
    const double base[6] = {-1.3, -1.3, -1.3, 1.3, 1.3, 1.3};
    for (int w = pf_first_box() - 1; w < 2; w++) {
        double box[6], worst[NH + 1];
        long euler[NH + 1];
        size_t pieces[NH + 1], n[NH + 1];
        int reached[2][2] = {{0, 0}, {0, 0}}; /* [max][sphere operand] */
        pf_sweep_box(base, HUG_DEPTH, w, box);
        n[0] = primal_sphere(&sphere, box, &worst[0], &euler[0], &pieces[0]);
        for (int h = 0; h < NH; h++) {
            int op = sphere_operand(&hugged[h], box);
            cr_expect_geq(op, 0, "box %d form %d: no top min/max with the sphere alone", w, h);
            if (op >= 0)
                reached[hugged[h].expr[1] == 'a'][op] = 1;
            n[h + 1] = primal_sphere(&hugged[h], box, &worst[h + 1], &euler[h + 1],
                                     &pieces[h + 1]);
        }
        for (int m = 0; m < 2; m++)
            for (int op = 0; op < 2; op++)
                cr_expect(reached[m][op], "box %d: no %s form with the sphere as operand %d", w,
                          m ? "max" : "min", op);
        for (int k = 0; k <= NH; k++) {
            cr_expect_eq(euler[k], 2, "box %d form %d: χ %ld", w, k, euler[k]);
            cr_expect_eq(pieces[k], 1, "box %d form %d: %zu pieces", w, k, pieces[k]);
            cr_expect_leq(worst[k], HUG_E, "box %d form %d: a point %g off", w, k, worst[k]);
        }
        for (int k = 1; k <= NH; k++)
            cr_expect_leq((double)n[k], HUG_TRIS_REL * (double)n[0],
                          "box %d form %d: %zu triangles with the crease, %zu without", w, k,
                          n[k], n[0]);
    }
}
