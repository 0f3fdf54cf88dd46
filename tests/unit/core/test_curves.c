/* test_curves.c — curves cut on a meshed surface and their arrangement (core/curves/) against
 * closed forms, each in a symmetric box and in boxes shifted off the octree lattice by 1e-3
 * and by PF_IRR of a finest cell: the unit sphere cut by the three coordinate planes has 6
 * vertices where two circles cross (degree 4), 12 arcs, 8 faces of area π/2 (each a disk:
 * χ = 1, one boundary cycle), three circles of length 2π; the torus cut by x = 0 has two
 * circles of radius r and two half-tori (annuli: χ = 0, two boundary cycles) of area
 * 2π²Rr, cut by z = 0 the two equators of lengths 2π(R ∓ r). Every curve vertex lies
 * within 1e-10 × the diagonal of both surfaces, and mesh edges run along the curves:
 * the midpoints of the curve edges lie on the plane to rounding. Tangencies in every box:
 * Viviani's curve has its degree-4 node at (1, 0, 0) within 1e-9 × the diagonal, one curve,
 * 2 edges, 3 faces; two circles on the sphere that touch at (0.8, 0, 0.6) meet in one
 * crossing of degree 4 with 3 faces of the caps' closed-form areas. The gyroid ball's crease
 * (lattice box and PF_IRR of a cell off it): every crease vertex on the gyroid and the sphere
 * within 1e-9 × diagonal, no mesh edge across it, and at every crease edge the normals each
 * side carries (what the outputs ship) are that side's branch gradient — the side told by
 * the closed forms at its corner off the edge — so the dihedral angle between the sides is
 * the gradients' angle within 2° at every edge; the flat triangles' own normals within 2° at
 * every edge too (FLAT_OVER_MAX: the crease refinement splits the triangles
 * beside it until their flat normals meet their branch's gradient: before it 236 of 5439
 * edges missed 2° at depth 7, 273 of 5348 at 0.37 cell — the gyroid's normal turns ~k ×
 * width / 3 across a triangle), no side folded against the other, and at most 1% of the
 * edges with a side whose flat normal is off its branch's gradients at its own corners by
 * more than they spread + 1° (a sliver). Also in the box 1e-3 off the lattice. Every vertex
 * of the cut mesh is a corner of a triangle (the crease cut's welded copies dropped). */
#include <criterion/criterion.h>
#include <math.h>
#include <string.h>
#include "poly_fixture.h"
#include "core/curves/arrangement.h"
#include "core/curves/cut.h"
#include "core/util/vec3.h"

/* Mesh accuracy: the triangles lie within this of f = 0 (area deficit ~ 2E/R ≪ 0.5%). */
#define MESH_ERROR 1e-3
#define AREA_REL 0.005      /* the issue's 0.5% */
#define LENGTH_REL 0.005
#define CURVE_TOL_REL 1e-10 /* curve points within this × the diagonal of both surfaces */

static const double shift_dir[3] = {1.0, 0.61, -0.83};

/* which 0: base as given; 1: moved by 1e-3; 2: by PF_IRR of a finest cell — along shift_dir. */
static void shifted(const double base[6], int which, int dmax, double box[6])
{
    double s = which == 0 ? 0 : which == 1 ? 1e-3 : PF_IRR * pf_cell(base, dmax);
    for (int k = 0; k < 3; k++) {
        box[k] = base[k] + s * shift_dir[k];
        box[k + 3] = base[k + 3] + s * shift_dir[k];
    }
}

typedef struct cut_run {
    ism_mesh m;
    ism_cut cut;
    ism_arrangement arr;
    double diag;
} cut_run;

static void run(const pf_surface *s, const double box[6], const ism_cut_fn *fns, size_t n,
                cut_run *r)
{
    ism_tape *t = pf_compile(s);
    ism_poly_options o;
    ism_poly_options_default(&o);
    memcpy(o.box, box, sizeof o.box);
    o.min_depth = 3;
    o.max_depth = 8;
    o.max_error = MESH_ERROR;
    ism_poly_stats st;
    ism_error err;
    ism_mesh_init(&r->m);
    cr_assert_eq(ism_polygonise(t, &o, &r->m, &st, &err), ISM_POLY_OK, "%s", err.message);
    cr_assert(ism_mesh_drop_loose(&r->m));
    r->diag = ism_box_diagonal(box);
    ism_cut_eval ev;
    cr_assert(ism_cut_eval_init(&ev, t, fns, n));
    memset(&r->cut, 0, sizeof r->cut);
    cr_assert(ism_cut_mesh(&ev, 1e-3 * CURVE_TOL_REL * r->diag, &r->m, &r->cut));
    ism_cut_eval_free(&ev);
    cr_assert(ism_arrangement_build(&r->m, &r->cut, NULL, 0, &r->arr));
    ism_tape_free(t);
    cr_assert_eq(r->cut.unrefined, 0);
    cr_assert_leq(r->cut.worst_f, CURVE_TOL_REL * r->diag, "f residual %g", r->cut.worst_f);
    cr_assert_leq(r->cut.worst_g, CURVE_TOL_REL * r->diag, "g residual %g", r->cut.worst_g);
    cr_assert(r->arr.euler_ok, "V-E+F %ld != chi %ld", r->arr.euler_arr, r->arr.euler_mesh);
    /* triangles are sorted by face and every face range matches tri_face */
    for (size_t f = 0; f < r->arr.nfaces; f++)
        for (size_t i = 0; i < r->arr.faces[f].ntris; i++)
            cr_assert_eq(r->arr.tri_face[r->arr.faces[f].first + i], f);
}

static void run_free(cut_run *r)
{
    ism_arrangement_free(&r->arr);
    ism_cut_free(&r->cut);
    ism_mesh_free(&r->m);
}

static ism_cut_fn plane(double a, double b, double c, double d)
{
    return (ism_cut_fn){.n = {a, b, c}, .c = d, .kind = ISM_CUT_SECTION};
}

/* Midpoints of curve edges: on the plane of their function (the cut edge lies in it up to
 * the curve's curvature, which bends it off the plane only for non-planar curves). */
static void check_edges_on_planes(const cut_run *r, const ism_cut_fn *fns)
{
    for (size_t i = 0; i < r->cut.nedges; i++) {
        const ism_cut_edge *e = &r->cut.edges[i];
        const double *a = r->m.pos + 3 * (size_t)e->a, *b = r->m.pos + 3 * (size_t)e->b;
        double g = 0;
        for (int k = 0; k < 3; k++)
            g += fns[e->fn].n[k] * 0.5 * (a[k] + b[k]);
        cr_assert_leq(fabs(g - fns[e->fn].c), CURVE_TOL_REL * r->diag);
    }
}

static const pf_surface sphere = {"x^2 + y^2 + z^2 - 1", NULL, 0, NULL, 0};

static void sphere_octants(int which)
{
    const double base[6] = {-1.3, -1.3, -1.3, 1.3, 1.3, 1.3};
    double box[6];
    shifted(base, which, 8, box);
    ism_cut_fn fns[3] = {plane(1, 0, 0, 0), plane(0, 1, 0, 0), plane(0, 0, 1, 0)};
    cut_run r;
    run(&sphere, box, fns, 3, &r);
    check_edges_on_planes(&r, fns);
    const ism_arrangement *a = &r.arr;
    cr_assert_eq(a->nvertices, 6);
    cr_assert_eq(a->nedges, 12);
    cr_assert_eq(a->nfaces, 8);
    cr_assert_eq(a->ncurves, 3);
    for (size_t i = 0; i < 6; i++) {
        cr_assert_eq(a->vertices[i].type, ISM_ARR_CROSSING);
        cr_assert_eq(a->vertices[i].degree, 4);
        const double *p = r.m.pos + 3 * (size_t)a->vertices[i].v; /* an axis point ±e_k */
        double big = fmax(fabs(p[0]), fmax(fabs(p[1]), fabs(p[2])));
        cr_assert_float_eq(big, 1.0, 1e-9);
    }
    for (size_t f = 0; f < 8; f++) {
        cr_assert_float_eq(a->faces[f].area, M_PI / 2, AREA_REL * M_PI / 2, "face %zu %g", f,
                           a->faces[f].area);
        cr_assert_eq(a->faces[f].euler, 1);
        cr_assert_eq(a->faces[f].boundary, 1);
    }
    for (size_t c = 0; c < 3; c++) {
        cr_assert(a->curves[c].closed);
        cr_assert_float_eq(a->curves[c].length, 2 * M_PI, LENGTH_REL * 2 * M_PI);
    }
    cr_log_info("sphere %d: %zu tris, face0 area %.6f (rel %.2e)", which, r.m.ntris, a->faces[0].area, a->faces[0].area / (M_PI / 2) - 1);
    cr_assert_eq(a->euler_mesh, 2);
    run_free(&r);
}

Test(curves, sphere_octants) { sphere_octants(0); }
Test(curves, sphere_octants_shift_1e3) { sphere_octants(1); }
Test(curves, sphere_octants_shift_037) { sphere_octants(2); }

static const ism_param torus_rr[] = {{"R", 1}, {"r", 0.4}};
static const pf_surface torus = {"(x^2 + y^2 + z^2 + R^2 - r^2)^2 - 4*R^2*(x^2 + y^2)",
                                 torus_rr, 2, NULL, 0};

/* The torus cut by one plane: two closed curves of the given lengths, two annuli. */
static void torus_cut(int which, ism_cut_fn fn, double len_lo, double len_hi)
{
    const double base[6] = {-1.6, -1.6, -0.6, 1.6, 1.6, 0.6};
    double box[6];
    shifted(base, which, 8, box);
    cut_run r;
    run(&torus, box, &fn, 1, &r);
    check_edges_on_planes(&r, &fn);
    const ism_arrangement *a = &r.arr;
    cr_assert_eq(a->ncurves, 2);
    cr_assert_eq(a->nfaces, 2);
    cr_assert_eq(a->nvertices, 2);
    cr_assert_eq(a->nedges, 2);
    double l0 = fmin(a->curves[0].length, a->curves[1].length);
    double l1 = fmax(a->curves[0].length, a->curves[1].length);
    cr_assert_float_eq(l0, len_lo, LENGTH_REL * len_lo);
    cr_assert_float_eq(l1, len_hi, LENGTH_REL * len_hi);
    double half = 2 * M_PI * M_PI * 1.0 * 0.4;
    for (size_t f = 0; f < 2; f++) {
        cr_assert_float_eq(a->faces[f].area, half, AREA_REL * half, "%g", a->faces[f].area);
        cr_assert_eq(a->faces[f].euler, 0);
        cr_assert_eq(a->faces[f].boundary, 2);
    }
    cr_assert_eq(a->euler_mesh, 0);
    run_free(&r);
}

Test(curves, torus_x0)
{
    for (int w = pf_first_box(); w < 3; w++)
        torus_cut(w, plane(1, 0, 0, 0), 2 * M_PI * 0.4, 2 * M_PI * 0.4);
}

Test(curves, torus_z0)
{
    for (int w = pf_first_box(); w < 3; w++)
        torus_cut(w, plane(0, 0, 1, 0), 2 * M_PI * 0.6, 2 * M_PI * 1.4);
}

/* ---- the crease of a CSG surface: max(gyroid, ball) ---- */

#include <stdlib.h>
#include "core/curves/crease_normals.h"
#include "core/eval/eval.h"

static const ism_param gyroid_k[] = {{"k", 4}};
static const pf_surface gyroid_alone = {
    "sin(k*x)*cos(k*y) + sin(k*y)*cos(k*z) + sin(k*z)*cos(k*x)", gyroid_k, 1, NULL, 0};

#define CREASE_TOL_REL 1e-9  /* the issue: crease points within 1e-9 × diagonal of both */
#define DIHEDRAL_DEG 2.0     /* the issue: mesh dihedral vs the gradients' angle */

typedef struct edge_tri {
    uint64_t key;
    uint32_t tri;
} edge_tri;

static int cmp_edge_tri(const void *a, const void *b)
{
    uint64_t x = ((const edge_tri *)a)->key, y = ((const edge_tri *)b)->key;
    return (x > y) - (x < y);
}

static uint64_t ekey(uint32_t a, uint32_t b)
{
    return a < b ? ((uint64_t)a << 32) | b : ((uint64_t)b << 32) | a;
}

/* The gyroid ball's branches at p: the gyroid G (k = 4) and the ball B = |p|² − 1.96, each
 * with its gradient. */
static double gyroid_at(ism_tape *gy, ism_eval_ws *ws, const double *p, double g[3])
{
    return ism_eval_gradient(gy, ws, p[0], p[1], p[2], g);
}

static double ball_at(const double *p, double g[3])
{
    for (int k = 0; k < 3; k++)
        g[k] = 2 * p[k];
    return p[0] * p[0] + p[1] * p[1] + p[2] * p[2] - 1.96;
}

/* Carried normals may differ from the branch gradient by float rounding only. */
#define BRANCH_NORMAL_DEG 1e-3

/* A side triangle whose flat normal is off its branch's gradients at its own corners by more
 * than those gradients spread, plus this, is a sliver or a fold, not the surface's curvature
 * (degrees). */
#define SLIVER_SLACK_DEG 1.0
/* At most this fraction of crease edges may have such a side (measured at depth 7: 36 of
 * 5439 lattice, 39 of 5348 at 0.37 cell; 108 of 6030 and 98 of 5999 before the vertices
 * next to the crease were moved onto it). */
#define SLIVER_EDGES_REL 0.01
/* Crease edges whose flat dihedral angle may miss the gradients' by more than DIHEDRAL_DEG:
 * the issue asks none. Measured at depth 7 after the crease refinement (crease_refine.c): 0
 * of 8,388 (lattice), 0 of 8,172 (1e-3 off it), 0 of 8,146 (0.37 cell; worst 1.56 / 1.45 /
 * 1.59°); 236 / 255 / 273 before the refinement, and 1 of 8,177 at 0.37 cell (2.45°) before
 * the micro clusters beside the crease were welded (crease_micro.c: three edge roots 3.5e-5
 * from a lattice corner left a 0.11° sliver no relaxation or split could mend). At the
 * irrational placement (PF_IRR) 2 of 8,283 (worst 9.2°) until a micro cluster straddling
 * the crease was welded (its triangles judged against their own normals, not the star's
 * sum: crease_micro.c good_fan) and the refinement ran up to 12 passes (crease_refine.c):
 * now 0 of 8,361 / 8,159 / 8,295 (worst 1.56 / 1.45 / 1.53°), no sliver side. */
#define FLAT_OVER_MAX 0

typedef struct crease_sides {
    size_t n, undecided, flat_over, sliver, folded;
    double worst_carried, worst_branch, sum_flat, worst_flat;
    double over_fattest; /* the largest smallest angle of a pair whose flat normals miss */
} crease_sides;

/* The smallest angle of triangle t, degrees. */
static double min_angle(const ism_mesh *m, size_t t)
{
    double best = 180;
    for (int i = 0; i < 3; i++) {
        const double *p = m->pos + 3 * (size_t)m->tri[3 * t + i];
        const double *q = m->pos + 3 * (size_t)m->tri[3 * t + (i + 1) % 3];
        const double *r = m->pos + 3 * (size_t)m->tri[3 * t + (i + 2) % 3];
        double u[3] = {q[0] - p[0], q[1] - p[1], q[2] - p[2]};
        double v[3] = {r[0] - p[0], r[1] - p[1], r[2] - p[2]};
        best = fmin(best, pf_vec_angle_deg(u, v));
    }
    return best;
}

static double angle_f(const float *a, const double *b)
{
    double d[3] = {a[0], a[1], a[2]};
    return pf_vec_angle_deg(d, b);
}

/* The side (0 gyroid, 1 ball) triangle t lies on, by B − G at its corner off the crease
 * edge a-b (a point of the surface: the triangle's middle of a sliver lies off it by more
 * than the sliver is wide) over the gradient of B − G (the distance to the surface G = B);
 * −1 when that corner is within CREASE_TOL_REL × diag of it (on the crease too). */
static int crease_side(const ism_mesh *m, ism_tape *gy, ism_eval_ws *ws, size_t t, uint32_t a,
                       uint32_t b, double diag)
{
    const uint32_t *tv = m->tri + 3 * t;
    uint32_t o = tv[0] != a && tv[0] != b ? tv[0] : tv[1] != a && tv[1] != b ? tv[1] : tv[2];
    const double *c = m->pos + 3 * (size_t)o;
    double gg[3], gb[3];
    double d = ball_at(c, gb) - gyroid_at(gy, ws, c, gg);
    double n = sqrt((gb[0] - gg[0]) * (gb[0] - gg[0]) + (gb[1] - gg[1]) * (gb[1] - gg[1]) +
                    (gb[2] - gg[2]) * (gb[2] - gg[2]));
    if (fabs(d) <= CREASE_TOL_REL * diag * n)
        return -1;
    return d > 0;
}

/* The corner normal of triangle t at vertex v (9 floats per triangle in cn). */
static const float *corner_normal(const ism_mesh *m, const float *cn, size_t t, uint32_t v)
{
    int i = m->tri[3 * t] == v ? 0 : m->tri[3 * t + 1] == v ? 1 : 2;
    cr_assert_eq(m->tri[3 * t + i], v);
    return cn + 9 * t + 3 * i;
}

/* Crease mesh edge a-b between triangles t0, t1: each side's carried normals at a and b are
 * its branch's gradient, and the angle between the sides' normals is the gradients' angle. */
static void check_crease_edge(const ism_mesh *m, ism_tape *gy, ism_eval_ws *ws, const float *cn,
                              uint32_t a, uint32_t b, size_t t0, size_t t1, double diag,
                              crease_sides *cs)
{
    int s0 = crease_side(m, gy, ws, t0, a, b, diag), s1 = crease_side(m, gy, ws, t1, a, b, diag);
    cs->undecided += (s0 < 0) + (s1 < 0);
    cr_assert(s0 < 0 || s1 < 0 || s0 != s1, "both sides of a crease edge on one branch");
    cr_assert(s0 >= 0 || s1 >= 0, "a crease edge between two triangles of crease points");
    for (int e = 0; e < 2; e++) {
        const double *p = m->pos + 3 * (size_t)(e ? b : a);
        double grad[2][3];
        gyroid_at(gy, ws, p, grad[0]);
        ball_at(p, grad[1]);
        const float *n0 = corner_normal(m, cn, t0, e ? b : a), *n1 = corner_normal(m, cn, t1, e ? b : a);
        if (s0 >= 0)
            cs->worst_branch = fmax(cs->worst_branch, angle_f(n0, grad[s0]));
        if (s1 >= 0)
            cs->worst_branch = fmax(cs->worst_branch, angle_f(n1, grad[s1]));
        double d1[3] = {n1[0], n1[1], n1[2]};
        cs->worst_carried = fmax(cs->worst_carried,
                                 fabs(angle_f(n0, d1) - pf_vec_angle_deg(grad[0], grad[1])));
    }
    double f0[3], f1[3], ga[3], gb[3], mid[3];
    pf_tri_normal(m, t0, f0);
    pf_tri_normal(m, t1, f1);
    for (int k = 0; k < 3; k++)
        mid[k] = 0.5 * (m->pos[3 * (size_t)a + k] + m->pos[3 * (size_t)b + k]);
    gyroid_at(gy, ws, mid, ga);
    ball_at(mid, gb);
    double dev[2] = {0, 0}, spread[2] = {0, 0};
    for (int j = 0; j < 2; j++) { /* each side's flat normal against its corners' gradients */
        int sd = j ? s1 : s0;
        double g[3][3];
        for (int c = 0; c < 3 && sd >= 0; c++) {
            const double *p = m->pos + 3 * (size_t)m->tri[3 * (j ? t1 : t0) + c];
            if (sd)
                ball_at(p, g[c]);
            else
                gyroid_at(gy, ws, p, g[c]);
            dev[j] = fmax(dev[j], pf_vec_angle_deg(j ? f1 : f0, g[c]));
        }
        for (int c = 0; c < 3 && sd >= 0; c++)
            spread[j] = fmax(spread[j], pf_vec_angle_deg(g[c], g[(c + 1) % 3]));
    }
    /* both sides against ∇f: a piece the mesh orients inward (a thin wedge of gyroid cut off
     * by the ball), measured the other way round; one side alone is a fold */
    bool inward = dev[0] > 90 && dev[1] > 90;
    cs->folded += !inward && (dev[0] > 90 || dev[1] > 90);
    bool sliver = false;
    for (int j = 0; j < 2; j++)
        sliver |= (inward ? 180 - dev[j] : dev[j]) > spread[j] + SLIVER_SLACK_DEG;
    cs->sliver += sliver;
    double d = fabs(pf_vec_angle_deg(f0, f1) - pf_vec_angle_deg(ga, gb));
    cs->sum_flat += d;
    cs->worst_flat = fmax(cs->worst_flat, d);
    if (d > DIHEDRAL_DEG) { /* how thin the pair is where the flat normals miss */
        cs->flat_over++;
        cs->over_fattest = fmax(cs->over_fattest, fmin(min_angle(m, t0), min_angle(m, t1)));
    }
    cs->n++;
}

static void gyroid_crease(int which)
{
    const double base[6] = {-1.5, -1.5, -1.5, 1.5, 1.5, 1.5};
    double box[6];
    shifted(base, which, 7, box);
    ism_tape *f = pf_compile(&pf_gyroid_ball), *gy = pf_compile(&gyroid_alone);
    ism_cut_fn crease;
    cr_assert(ism_cut_crease_fn(f, &crease));
    ism_tape_free(f);
    cut_run r;
    ism_mesh_init(&r.m);
    {
        ism_tape *t = pf_compile(&pf_gyroid_ball);
        ism_poly_options o;
        ism_poly_options_default(&o);
        memcpy(o.box, box, sizeof o.box);
        o.min_depth = 3;
        o.max_depth = 7;
        ism_poly_stats st;
        ism_error err;
        cr_assert_eq(ism_polygonise(t, &o, &r.m, &st, &err), ISM_POLY_OK);
        cr_assert(ism_mesh_drop_loose(&r.m));
        ism_cut_eval ev;
        cr_assert(ism_cut_eval_init(&ev, t, &crease, 1));
        memset(&r.cut, 0, sizeof r.cut);
        r.diag = ism_box_diagonal(box);
        cr_assert(ism_cut_mesh(&ev, 1e-3 * CURVE_TOL_REL * r.diag, &r.m, &r.cut));
        ism_cut_eval_free(&ev);
        ism_tape_free(t);
    }
    cr_log_info("crease %d: %zu edges, %zu unrefined, worst f %g g %g; mesh %zu vertices, %zu "
                "triangles", which, r.cut.nedges, r.cut.unrefined, r.cut.worst_f, r.cut.worst_g,
                r.m.nverts, r.m.ntris);
    cr_assert_gt(r.cut.nedges, 100);
    {   /* no loose vertex: each one a corner of a triangle (no segments here) */
        uint8_t *used = calloc(r.m.nverts + 1, 1);
        for (size_t i = 0; i < 3 * r.m.ntris; i++)
            used[r.m.tri[i]] = 1;
        size_t loose = 0;
        for (size_t v = 0; v < r.m.nverts; v++)
            loose += !used[v];
        free(used);
        cr_assert_eq(loose, 0, "%zu of %zu vertices used by no triangle", loose, r.m.nverts);
    }
    ism_eval_ws *ws = ism_eval_ws_new(gy);
    /* every crease vertex on the gyroid and on the sphere (closed forms) */
    for (size_t i = 0; i < r.cut.nedges; i++)
        for (int e = 0; e < 2; e++) {
            const double *p = r.m.pos + 3 * (size_t)(e ? r.cut.edges[i].b : r.cut.edges[i].a);
            double g[3], v = ism_eval_gradient(gy, ws, p[0], p[1], p[2], g);
            double dg = fabs(v) / sqrt(g[0] * g[0] + g[1] * g[1] + g[2] * g[2]);
            double rr = sqrt(p[0] * p[0] + p[1] * p[1] + p[2] * p[2]);
            cr_assert_leq(dg, CREASE_TOL_REL * r.diag, "gyroid %g", dg);
            cr_assert_leq(fabs(rr - 1.4), CREASE_TOL_REL * r.diag, "sphere %g", rr - 1.4);
        }
    /* no mesh edge straddles the crease: its ends are on one branch's side (or on it) */
    double *side = malloc(r.m.nverts * sizeof *side);
    for (size_t v = 0; v < r.m.nverts; v++) {
        const double *p = r.m.pos + 3 * v;
        side[v] = ism_eval_point(gy, ws, p[0], p[1], p[2]) -
                  (p[0] * p[0] + p[1] * p[1] + p[2] * p[2] - 1.96);
    }
    uint8_t *on = calloc(r.m.nverts, 1);
    for (size_t i = 0; i < r.cut.nedges; i++)
        on[r.cut.edges[i].a] = on[r.cut.edges[i].b] = 1;
    size_t straddle = 0;
    for (size_t t = 0; t < r.m.ntris; t++)
        for (int i = 0; i < 3; i++) {
            uint32_t a = r.m.tri[3 * t + i], b = r.m.tri[3 * t + (i + 1) % 3];
            straddle += !on[a] && !on[b] && side[a] * side[b] < 0;
        }
    cr_assert_eq(straddle, 0, "%zu mesh edges cross the crease", straddle);
    /* every crease edge: the normals each side carries (ism_crease_corner_normals, what the
     * outputs ship) are its own branch's gradient, the side told by the closed forms at the
     * triangle's centroid, and the dihedral angle between the sides is the angle between
     * the two gradients; the triangles' own (flat) normals are measured too */
    edge_tri *et = malloc(3 * r.m.ntris * sizeof *et);
    for (size_t t = 0; t < r.m.ntris; t++)
        for (int i = 0; i < 3; i++)
            et[3 * t + i] = (edge_tri){ekey(r.m.tri[3 * t + i], r.m.tri[3 * t + (i + 1) % 3]),
                                       (uint32_t)t};
    qsort(et, 3 * r.m.ntris, sizeof *et, cmp_edge_tri);
    float *cn = malloc(9 * r.m.ntris * sizeof *cn);
    {
        ism_tape *t = pf_compile(&pf_gyroid_ball);
        cr_assert(ism_crease_corner_normals(t, &r.m, &r.cut, cn));
        ism_tape_free(t);
    }
    crease_sides cs = {0};
    for (size_t i = 0; i < r.cut.nedges; i++) {
        edge_tri key = {ekey(r.cut.edges[i].a, r.cut.edges[i].b), 0};
        edge_tri *hit = bsearch(&key, et, 3 * r.m.ntris, sizeof *et, cmp_edge_tri);
        cr_assert(hit);
        while (hit > et && hit[-1].key == key.key)
            hit--;
        size_t nt = 0;
        while (hit + nt < et + 3 * r.m.ntris && hit[nt].key == key.key)
            nt++;
        cr_assert(nt == 1 || nt == 2, "crease edge with %zu triangles", nt);
        if (nt == 2) /* else a border edge at the box */
            check_crease_edge(&r.m, gy, ws, cn, r.cut.edges[i].a, r.cut.edges[i].b, hit[0].tri,
                              hit[1].tri, r.diag, &cs);
    }
    cr_log_info("gyroid crease %d: %zu edges; carried normals: dihedral vs gradients worst %.2e "
                "deg, branch normals off by %.2e deg, %zu sides on the crease itself; flat "
                "triangle normals: mean %.3f, worst %.3f deg, %zu edges over %.0f deg (each "
                "beside a triangle with an angle under %.2f deg); %zu with a sliver side, %zu "
                "folded sides", which, cs.n, cs.worst_carried, cs.worst_branch, cs.undecided,
                cs.sum_flat / (double)cs.n, cs.worst_flat, cs.flat_over, DIHEDRAL_DEG,
                cs.over_fattest, cs.sliver, cs.folded);
    cr_assert_gt(cs.n, 100);
    cr_assert_leq(cs.worst_carried, DIHEDRAL_DEG);
    cr_assert_leq(cs.worst_branch, BRANCH_NORMAL_DEG);
    cr_assert_leq(cs.sum_flat / (double)cs.n, DIHEDRAL_DEG);
    cr_assert_leq(cs.flat_over, FLAT_OVER_MAX, "%zu of %zu crease edges over %.0f deg", cs.flat_over,
                  cs.n, DIHEDRAL_DEG);
    cr_assert_leq(cs.sliver, SLIVER_EDGES_REL * (double)cs.n, "%zu of %zu", cs.sliver, cs.n);
    cr_assert_eq(cs.folded, 0);
    free(cn);
    free(et);
    free(on);
    free(side);
    ism_eval_ws_free(ws);
    ism_tape_free(gy);
    ism_cut_free(&r.cut);
    ism_mesh_free(&r.m);
}

Test(curves, gyroid_ball_crease) { gyroid_crease(0); }
Test(curves, gyroid_ball_crease_shift_1e3) { gyroid_crease(1); }
Test(curves, gyroid_ball_crease_shift_irr) { gyroid_crease(2); }

/* ---- Viviani's curve: the unit sphere ∩ the cylinder (x − ½)² + y² = ¼ ---- */

static const pf_surface cylinder = {"(x - 0.5)^2 + y^2 - 0.25", NULL, 0, NULL, 0};

/* Its length from the parametrisation (cos²t, cos t sin t, sin t), |p'| = √(1 + cos²t),
 * by Simpson's rule on 20,000 intervals. */
static double viviani_length(void)
{
    const int n = 20000;
    double h = 2 * M_PI / n, s = 0;
    for (int i = 0; i <= n; i++) {
        double c = cos(i * h), w = (i == 0 || i == n) ? 1 : (i % 2 ? 4 : 2);
        s += w * sqrt(1 + c * c);
    }
    return s * h / 3;
}

static void viviani(int which)
{
    const double base[6] = {-1.3, -1.3, -1.3, 1.3, 1.3, 1.3};
    double box[6];
    shifted(base, which, 8, box);
    ism_tape *g = pf_compile(&cylinder);
    ism_cut_fn fn = {.tape = g, .kind = ISM_CUT_INTERSECTION};
    cut_run r;
    run(&sphere, box, &fn, 1, &r);
    const ism_arrangement *a = &r.arr;
    double len = 0;
    for (size_t c = 0; c < a->ncurves; c++)
        len += a->curves[c].length;
    double want = viviani_length();
    cr_log_info("viviani %d: %zu V (%s, degree %d), %zu curves, %zu faces, length %.5f of %.5f",
                which, a->nvertices, a->nvertices ? (a->vertices[0].type == ISM_ARR_BRANCH ?
                "branch" : "loop") : "-", a->nvertices ? a->vertices[0].degree : 0, a->ncurves,
                a->nfaces, len, want);
    cr_assert_float_eq(len, want, LENGTH_REL * want);
    /* The surfaces are tangent at (1, 0, 0), a node of the curve found from the equations
     * in every box: one curve, a degree-4 vertex there, three faces (two lobes, the rest). */
    cr_assert_eq(a->nfaces, 3);
    cr_assert_eq(a->ncurves, 1);
    cr_assert_eq(a->nvertices, 1);
    cr_assert_eq(a->nedges, 2);
    cr_assert_eq(a->vertices[0].degree, 4);
    cr_assert_eq(a->vertices[0].type, ISM_ARR_BRANCH);
    const double *p = r.m.pos + 3 * (size_t)a->vertices[0].v, node[3] = {1, 0, 0};
    double err = sqrt((p[0] - node[0]) * (p[0] - node[0]) + p[1] * p[1] + p[2] * p[2]);
    cr_assert_leq(err, 1e-9 * r.diag, "node off by %g", err);
    run_free(&r);
    ism_tape_free(g);
}

Test(curves, viviani) { viviani(0); }
Test(curves, viviani_shift_1e3) { viviani(1); }
Test(curves, viviani_shift_037) { viviani(2); }

/* ---- two curves that touch: the unit sphere cut by the sphere x² + y² + (z − 1)² = 0.8
 * (the circle z = 0.6 of radius 0.8) and by the plane x = 0.8 (the circle of radius 0.6
 * round the x axis), tangent at (0.8, 0, 0.6). The caps z ≥ 0.6 and x ≥ 0.8 meet only
 * there: one crossing of degree 4, two loops, three faces (areas 2π·0.4, 2π·0.2 and the
 * rest), whichever curve is cut first. ---- */

static const pf_surface second_sphere = {"x^2 + y^2 + (z - 1)^2 - 0.8", NULL, 0, NULL, 0};

static void touching_circles(int which, bool plane_first)
{
    const double base[6] = {-1.3, -1.3, -1.3, 1.3, 1.3, 1.3};
    double box[6];
    shifted(base, which, 8, box);
    ism_tape *g = pf_compile(&second_sphere);
    ism_cut_fn sph = {.tape = g, .kind = ISM_CUT_INTERSECTION}, pl = plane(1, 0, 0, 0.8);
    ism_cut_fn fns[2] = {plane_first ? pl : sph, plane_first ? sph : pl};
    cut_run r;
    run(&sphere, box, fns, 2, &r);
    const ism_arrangement *a = &r.arr;
    cr_log_info("touching %d %d: %zu V, %zu E, %zu F, %zu curves", which, plane_first,
                a->nvertices, a->nedges, a->nfaces, a->ncurves);
    cr_assert_eq(a->nvertices, 1);
    cr_assert_eq(a->nedges, 2);
    cr_assert_eq(a->nfaces, 3);
    cr_assert_eq(a->ncurves, 2);
    cr_assert_eq(a->vertices[0].type, ISM_ARR_CROSSING);
    cr_assert_eq(a->vertices[0].degree, 4);
    const double *p = r.m.pos + 3 * (size_t)a->vertices[0].v;
    double err = sqrt((p[0] - 0.8) * (p[0] - 0.8) + p[1] * p[1] + (p[2] - 0.6) * (p[2] - 0.6));
    cr_assert_leq(err, 1e-9 * r.diag, "touching point off by %g", err);
    double want[3] = {2 * M_PI * 0.2, 2 * M_PI * 0.4, 4 * M_PI - 2 * M_PI * 0.6}, got[3];
    for (size_t f = 0; f < 3; f++)
        got[f] = a->faces[f].area;
    for (int i = 0; i < 3; i++) /* sorted ascending */
        for (int j = i + 1; j < 3; j++)
            if (got[j] < got[i]) {
                double t = got[i];
                got[i] = got[j];
                got[j] = t;
            }
    for (int i = 0; i < 3; i++)
        cr_assert_float_eq(got[i], want[i], AREA_REL * want[i], "face %d: %g", i, got[i]);
    run_free(&r);
    ism_tape_free(g);
}

Test(curves, touching_circles)
{
    for (int w = pf_first_box(); w < 3; w++) {
        touching_circles(w, false);
        touching_circles(w, true);
    }
}
