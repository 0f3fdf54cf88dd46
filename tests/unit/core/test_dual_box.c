/* test_dual_box.c — the dual mesh of surfaces the box cuts (core/octree/dual_box.h): made in
 * a grown box and clipped by the given one's planes. Each surface in its box as given and
 * shifted off the lattice by 1e-3 and by irrational fractions of a finest cell (pf_sweep_box):
 * - a sphere of radius 1.2 in the box ±1: each face cuts a circle of radius √0.44, so the
 *   mesh is the sphere less 6 caps: dual, χ = 2 − 6 = −4, one piece, 6 boundary loops;
 * - a cylinder of radius 0.6 along z in ±1: cut by the two z faces, χ 0, 2 loops;
 * - a small sphere whose cap pokes through one face between the first look's samples: the
 *   tree finds the cut, the grown box is meshed then: a disc, χ 1, one loop; and that mesh is
 *   bit for bit the one made in the grown box from the start (ism_dual_mesh_grown): nothing
 *   of the first tree (its point memo keyed by the old lattice) reaches the second.
 * Everywhere: the boundary loops as many as f's sign regions on the box's faces say (counted
 * on a lattice of the faces, no mesh involved: k disjoint closed curves on the box's surface
 * part it into k + 1 regions), every boundary vertex on a face plane (exactly) and on f = 0
 * (|f| / |∇f| ≤ 1e-9 × the box's diagonal), every other edge in two triangles, every
 * centroid and edge midpoint within E (closed form), none turned against ∇f.
 * Kummer's quartic with 16 nodes still declines for the box (test_dual_points.c): its
 * balls fail off the lattice. */
#include <criterion/criterion.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include "core/eval/eval.h"
#include "core/octree/dual.h"
#include "core/octree/dual_box.h"
#include "core/octree/mesher.h"
#include "core/singular/surface.h"
#include "core/util/vec3.h"
#include "poly_fixture.h"

#define DEPTH 9
/* Samples per face side for the sign regions: the smallest loop here (the sphere's circles,
 * radius 0.66 in a face of side 2) spans 60 of them. */
#define FACE_SAMPLES 96
/* A boundary vertex's |f| / |∇f| bound, relative to the box's diagonal (dual_box.c's Newton
 * stops at 1e-14 of it and accepts 1e-11). */
#define ON_F 1e-9

static const pf_surface sphere12 = {"x^2 + y^2 + z^2 - 1.44", NULL, 0, NULL, 0};
static const pf_surface cylinder = {"x^2 + y^2 - 0.36", NULL, 0, NULL, 0};

static double sphere12_dist(const double *p)
{
    return fabs(sqrt(p[0] * p[0] + p[1] * p[1] + p[2] * p[2]) - 1.2);
}

static double cylinder_dist(const double *p) { return fabs(hypot(p[0], p[1]) - 0.6); }

/* Closed loops of f = 0 on the box's faces from f's signs alone: sign regions of the faces'
 * lattice (4-neighbours across face edges too) less one; 0 when f keeps one sign there. */
static size_t face_loops(const ism_tape *t, const double box[6])
{
    const int n = FACE_SAMPLES, side = n + 1;
    size_t np = (size_t)side * side * side;
    signed char *sg = calloc(np, 1);
    int *stack = malloc(np * sizeof *stack);
    uint8_t *seen = calloc(np, 1);
    ism_eval_ws *ws = ism_eval_ws_new(t);
    cr_assert(sg && stack && seen && ws);
    for (int i = 0; i <= n; i++)
        for (int j = 0; j <= n; j++)
            for (int k = 0; k <= n; k++) {
                if (i && i < n && j && j < n && k && k < n)
                    continue;
                double p[3];
                int ijk[3] = {i, j, k};
                for (int a = 0; a < 3; a++)
                    p[a] = box[a] + (box[a + 3] - box[a]) * ijk[a] / n;
                double f = ism_eval_point(t, ws, p[0], p[1], p[2]);
                sg[((size_t)i * side + j) * side + k] = f > 0 ? 1 : f < 0 ? -1 : 2;
            }
    size_t regions = 0;
    for (size_t s = 0; s < np; s++) {
        if (!sg[s] || sg[s] == 2 || seen[s])
            continue;
        regions++;
        int top = 0;
        stack[top++] = (int)s;
        seen[s] = 1;
        while (top) {
            int q = stack[--top], ijk[3] = {q / side / side, q / side % side, q % side};
            for (int a = 0; a < 3; a++)
                for (int d = -1; d <= 1; d += 2) {
                    int r[3] = {ijk[0], ijk[1], ijk[2]};
                    r[a] += d;
                    if (r[a] < 0 || r[a] > n)
                        continue;
                    size_t at = ((size_t)r[0] * side + r[1]) * side + r[2];
                    if (sg[at] == sg[s] && !seen[at]) {
                        seen[at] = 1;
                        stack[top++] = (int)at;
                    }
                }
        }
    }
    free(sg);
    free(stack);
    free(seen);
    ism_eval_ws_free(ws);
    return regions ? regions - 1 : 0;
}

typedef struct edge_use {
    uint32_t a, b; /* a < b */
    uint32_t n;
} edge_use;

static int by_ends(const void *x, const void *y)
{
    const edge_use *p = x, *q = y;
    return p->a != q->a ? (p->a > q->a) - (p->a < q->a) : (p->b > q->b) - (p->b < q->b);
}

static uint32_t find(uint32_t *up, uint32_t v)
{
    while (up[v] != v)
        v = up[v] = up[up[v]];
    return v;
}

/* The mesh's boundary (edges in one triangle): its loops (pieces of the boundary edges'
 * graph, every boundary vertex meeting exactly two of them, else the count is SIZE_MAX), the
 * edges in more than two triangles into *nm, and every boundary vertex checked on a face
 * plane of box and on f = 0. */
static size_t boundary_loops(const ism_mesh *m, const ism_tape *t, const double box[6],
                             size_t *nm)
{
    size_t ne = 3 * m->ntris;
    edge_use *e = malloc((ne + 1) * sizeof *e);
    uint32_t *deg = calloc(m->nverts + 1, sizeof *deg), *up = malloc((m->nverts + 1) * 4);
    cr_assert(e && deg && up);
    for (size_t i = 0; i < ne; i++) {
        uint32_t a = m->tri[i], b = m->tri[i / 3 * 3 + (i + 1) % 3];
        e[i] = (edge_use){a < b ? a : b, a < b ? b : a, 1};
    }
    qsort(e, ne, sizeof *e, by_ends);
    for (uint32_t v = 0; v < m->nverts; v++)
        up[v] = v;
    ism_eval_ws *ws = ism_eval_ws_new(t);
    double diag = ism_box_diagonal(box), worst_f = 0;
    size_t off_plane = 0;
    *nm = 0;
    for (size_t i = 0; i < ne;) {
        size_t j = i + 1;
        while (j < ne && e[j].a == e[i].a && e[j].b == e[i].b)
            j++;
        *nm += j - i > 2;
        if (j - i == 1) {
            uint32_t ends[2] = {e[i].a, e[i].b};
            deg[ends[0]]++;
            deg[ends[1]]++;
            up[find(up, ends[0])] = find(up, ends[1]);
        }
        i = j;
    }
    size_t loops = 0;
    bool simple = true;
    for (uint32_t v = 0; v < m->nverts; v++) {
        if (!deg[v])
            continue;
        simple &= deg[v] == 2;
        loops += find(up, v) == v;
        const double *p = m->pos + 3 * (size_t)v;
        bool on = false;
        for (int a = 0; a < 6; a++)
            on |= p[a % 3] == box[a];
        off_plane += !on;
        double g[3], f = ism_eval_gradient(t, ws, p[0], p[1], p[2], g);
        worst_f = fmax(worst_f, fabs(f) / sqrt(g[0] * g[0] + g[1] * g[1] + g[2] * g[2]));
    }
    cr_expect_eq(off_plane, 0, "%zu boundary vertices off the box's planes", off_plane);
    cr_expect_leq(worst_f, ON_F * diag, "a boundary vertex %g from f = 0", worst_f);
    ism_eval_ws_free(ws);
    free(e);
    free(deg);
    free(up);
    return simple ? loops : SIZE_MAX;
}

/* The dual mesh of s in each of the three boxes from base under e: dual, χ, one piece, the
 * loops f's signs say (and `loops`), on the planes and on f = 0, within e. */
static void expect_clipped(const pf_surface *s, double (*dist)(const double *),
                           const double base[6], double e, long chi, size_t loops)
{
    ism_tape *t = pf_compile(s);
    for (int which = pf_first_box() - 1; which < 2; which++) {
        double box[6];
        pf_sweep_box(base, DEPTH, which, box);
        ism_poly_options o;
        pf_options(&o, box, 3, DEPTH);
        o.max_error = e;
        o.dual = true;
        o.threads = 1;
        ism_mesh m;
        ism_poly_stats ps;
        ism_mesh_init(&m);
        pf_run_options(t, &o, &m, &ps);
        cr_expect_eq(ps.mesher, ISM_MESHER_DUAL, "box %d: mesher %s (%s)", which,
                     ism_mesher_name(ps.mesher), ism_dual_reason_name(ps.dual_declined));
        pf_props p;
        pf_measure(&m, t, &p);
        size_t nm, bl = boundary_loops(&m, t, box, &nm), fl = face_loops(t, box), turned;
        cr_expect_eq(fl, loops, "box %d: f's signs say %zu loops", which, fl);
        cr_expect_eq(bl, fl, "box %d: %zu boundary loops, f says %zu", which, bl, fl);
        cr_expect_eq(nm, 0, "box %d: %zu edges in 3+ triangles", which, nm);
        cr_expect_eq(p.euler, chi, "box %d: χ %ld", which, p.euler);
        cr_expect_eq(p.components, 1, "box %d: %zu pieces", which, p.components);
        double w = pf_worst_turned(&m, t, dist, &turned);
        cr_expect_leq(w, e, "box %d: a centroid or midpoint %g from f = 0", which, w);
        cr_expect_eq(turned, 0, "box %d: %zu triangles against ∇f", which, turned);
        ism_mesh_free(&m);
    }
    ism_tape_free(t);
}

/* The grown box: on every side a margin of 1.1-1.4 cells of level L of the grown box (a leaf
 * of level L + 1 touching it then lies farther than half a cell beyond the given box). */
Test(dual_box, grown_box_margins_over_a_cell)
{
    static const double box[6] = {-3, -1, 0.5, 3, 2, 0.75};
    double g[6];
    ism_dual_box_grow(box, 4, g);
    for (int a = 0; a < 3; a++) {
        double cell = (g[a + 3] - g[a]) / 16, lo = (box[a] - g[a]) / cell,
               hi = (g[a + 3] - box[a + 3]) / cell;
        cr_expect(lo > 1.1 && lo < 1.4 && hi > 1.1 && hi < 1.4, "axis %d: margins %g, %g cells",
                  a, lo, hi);
    }
}

/* The faces' interval proof before the first look (dual_box.c faces_free): the unit sphere
 * in the box ±1.5 lies 0.5 inside every face (f >= 1.25 on them), so the faces are shown
 * free and none of the look's 6 × 17² points is evaluated (answer false: no cut seen; 1,734
 * points without the proof); in ±0.9 every face cuts it (f = -0.19 at a face's centre, 1.43
 * at its corners), so the proof fails and the look evaluates points and sees the cut. In
 * the three placements. */
Test(dual_box, free_faces_skip_the_look)
{
    static const pf_surface unit = {"x^2 + y^2 + z^2 - 1", NULL, 0, NULL, 0};
    static const double far[6] = {-1.5, -1.5, -1.5, 1.5, 1.5, 1.5},
                        near[6] = {-0.9, -0.9, -0.9, 0.9, 0.9, 0.9};
    ism_tape *t = pf_compile(&unit);
    for (int which = pf_first_box() - 1; which < 2; which++) {
        double box[6];
        ism_sampler s = {.tape = t, .ws = ism_eval_ws_new(t)};
        cr_assert(s.ws);
        pf_sweep_box(far, DEPTH, which, box);
        cr_expect_not(ism_dual_box_seen_cut(&s, box, ISM_DUAL_BOX_LOOK), "box %d", which);
        cr_expect_eq(s.n_point, 0, "box %d: %llu look points on free faces", which,
                     (unsigned long long)s.n_point);
        cr_expect_gt(s.n_interval, 0, "box %d: no faces' proof", which);
        s.n_point = s.n_interval = 0;
        pf_sweep_box(near, DEPTH, which, box);
        cr_expect(ism_dual_box_seen_cut(&s, box, ISM_DUAL_BOX_LOOK), "box %d: cut unseen",
                  which);
        cr_expect_gt(s.n_point, 0, "box %d: the look skipped on cut faces", which);
        ism_eval_ws_free(s.ws);
    }
    ism_tape_free(t);
}

Test(dual_box, sphere_cut_by_every_face_six_circles)
{
    static const double base[6] = {-1, -1, -1, 1, 1, 1};
    expect_clipped(&sphere12, sphere12_dist, base, 1e-2, -4, 6);
    expect_clipped(&sphere12, sphere12_dist, base, 3e-3, -4, 6);
}

Test(dual_box, cylinder_cut_by_two_faces)
{
    static const double base[6] = {-1, -1, -1, 1, 1, 1};
    expect_clipped(&cylinder, cylinder_dist, base, 1e-2, 0, 2);
}

/* A small sphere whose cap pokes through the face x = 1 between the first look's samples
 * (its circle, radius 0.067 round (0.0625, 0.0625), misses the points 1/8 apart): the tree
 * finds the cut (box_cut), the mesh is made again in the grown box: a disc, χ 1, one loop. */
static const pf_surface poking = {"(x - 1.06)^2 + (y - 0.0625)^2 + (z - 0.0625)^2 - 0.0081",
                                  NULL, 0, NULL, 0};

static double poking_dist(const double *p)
{
    return fabs(sqrt(pow(p[0] - 1.06, 2) + pow(p[1] - 0.0625, 2) + pow(p[2] - 0.0625, 2)) -
                0.09);
}

Test(dual_box, cap_between_the_face_samples)
{
    static const double base[6] = {-1, -1, -1, 1, 1, 1};
    /* at 2e-3 in the irrational box (and 1e-3 in the own one) slivers beside a corner a
     * hair from the face turned against ∇f at every depth until mark_turned snapped it */
    expect_clipped(&poking, poking_dist, base, 2e-3, 1, 1);
    expect_clipped(&poking, poking_dist, base, 1e-3, 1, 1);
}

/* The poking cap's mesh after the tree found the cut (a first tree in the given box, then
 * the grown box's) against the grown box's from the start: the same vertices and triangles,
 * bit for bit, in the three boxes at 2e-3 and 1e-3. The first tree's point memo holds f and
 * ∇f under the given box's lattice keys; the grown box's lattice gives the same keys to other
 * points, so a memo not emptied between them answers with the wrong points' values. */
Test(dual_box, tree_found_cut_meshes_as_grown_from_the_start)
{
    static const double base[6] = {-1, -1, -1, 1, 1, 1}, es[2] = {2e-3, 1e-3};
    ism_tape *t = pf_compile(&poking);
    for (int which = pf_first_box() - 1; which < 2; which++)
        for (int k = 0; k < 2; k++) {
            double box[6];
            pf_sweep_box(base, DEPTH, which, box);
            ism_sampler s = {.tape = t, .ws = ism_eval_ws_new(t)};
            cr_assert(s.ws);
            cr_assert_not(ism_dual_box_seen_cut(&s, box, ISM_DUAL_BOX_LOOK),
                          "box %d: the look sees the cap (the tree must find it)", which);
            ism_eval_ws_free(s.ws);
            ism_poly_options o;
            pf_options(&o, box, 3, DEPTH);
            o.max_error = es[k];
            o.dual = true;
            o.threads = 1;
            ism_mesh a, b;
            ism_dual_stats sa, sb;
            ism_mesh_init(&a);
            ism_mesh_init(&b);
            cr_assert_eq(ism_dual_mesh(t, &o, &a, &sa), ISM_DUAL_OK, "box %d E %g: declined (%s)",
                         which, es[k], ism_dual_reason_name(sa.declined));
            cr_assert_eq(ism_dual_mesh_grown(t, &o, &b, &sb), ISM_DUAL_OK,
                         "box %d E %g: grown declined (%s)", which, es[k],
                         ism_dual_reason_name(sb.declined));
            cr_assert(a.ntris > 0, "box %d E %g: no triangles", which, es[k]);
            cr_expect_eq(a.nverts, b.nverts, "box %d E %g: %zu vertices, %zu from the start",
                         which, es[k], a.nverts, b.nverts);
            cr_expect_eq(a.ntris, b.ntris, "box %d E %g: %zu triangles, %zu from the start", which,
                         es[k], a.ntris, b.ntris);
            if (a.nverts == b.nverts && a.ntris == b.ntris) {
                cr_expect(!memcmp(a.pos, b.pos, 3 * a.nverts * sizeof *a.pos),
                          "box %d E %g: vertex positions differ", which, es[k]);
                cr_expect(!memcmp(a.tri, b.tri, 3 * a.ntris * sizeof *a.tri),
                          "box %d E %g: triangles differ", which, es[k]);
            }
            ism_mesh_free(&a);
            ism_mesh_free(&b);
        }
    ism_tape_free(t);
}
