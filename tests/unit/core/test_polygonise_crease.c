/* test_polygonise_crease.c — CSG unions and differences (min/max of smooth pieces) off the
 * octree lattice: their seams are C0 creases where two sheets meet at a shallow angle, and a
 * pocket of one sign there can be thinner than a cell. The mesh must stay closed: no boundary
 * edge, no non-manifold edge, one piece, the Euler characteristic of the solid's genus.
 * The boxes are the sweep's (tests/bench/sweep_singular.py) shifted by 1e-3 and by
 * (0.37, −0.23, 0.41) of a finest cell, where each of these once left a hole of one to three
 * triangles at the seam: a tile's arcs judged joined along a side that the pocket's mouth
 * crosses (three balls, cube minus ball), and two roots on a segment across the seam missed
 * because the two sheets' gradients agreed to 0.902 (double torus). */
#include <criterion/criterion.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include "core/util/vec3.h"
#include "poly_fixture.h"

/* Polygonises s at depth 7 in both shifted boxes of base (under sanitizers, ISOMESH_TEST_QUICK,
 * only in box quick_box, where the defect showed); the mesh must be closed with Euler
 * characteristic euler (2 − 2 genus) in one piece. */
static void check_seams(const char *expr, const double base[6], long euler, int quick_box)
{
    const pf_surface s = {expr, NULL, 0, NULL, 0};
    ism_tape *t = pf_compile(&s);
    int depth = 7;
    for (int w = 0; w < 2; w++) {
        if (pf_quick() && w != quick_box)
            continue;
        double box[6];
        pf_sweep_box(base, depth, w, box);
        ism_mesh m;
        ism_poly_stats st;
        pf_run(t, box, 3, depth, 0, &m, &st);
        pf_props p;
        pf_measure(&m, t, &p);
        const char *what = w == 0 ? "shift 1e-3" : "shift irr cell";
        cr_expect_eq(p.boundary_edges, 0, "%s, %s: %zu boundary edges", expr, what,
                     p.boundary_edges);
        cr_expect_eq(p.nonmanifold_edges, 0, "%s, %s: %zu non-manifold edges", expr, what,
                     p.nonmanifold_edges);
        cr_expect_eq(p.euler, euler, "%s, %s: χ = %ld, expected %ld", expr, what, p.euler,
                     euler);
        cr_expect_eq(p.components, 1, "%s, %s: %zu components", expr, what, p.components);
        ism_mesh_free(&m);
    }
    ism_tape_free(t);
}

/* Three overlapping balls: a sphere's topology, χ = 2. */
Test(crease, three_balls_closed_off_lattice)
{
    const double box[6] = {-1.5, -1.5, -1.5, 1.5, 1.5, 1.5};
    check_seams("min((x - 0.6)^2 + y^2 + z^2 - 0.5, (x + 0.3)^2 + (y - 0.52)^2 + z^2 - 0.5, "
                "(x + 0.3)^2 + (y + 0.52)^2 + z^2 - 0.5)", box, 2, 0);
}

/* The cube [−1, 1]³ minus the ball of radius 1.3 (> 1, < √2): a frame of 12 bars, genus 5,
 * χ = −8. */
Test(crease, cube_minus_ball_closed_off_lattice)
{
    const double box[6] = {-1.3, -1.3, -1.3, 1.3, 1.3, 1.3};
    check_seams("max(max(abs(x), abs(y), abs(z)) - 1, 1.69 - (x^2 + y^2 + z^2))", box, -8, 1);
}

/* Two tori (R = 1, r = 0.5) 2.2 apart, overlapping: genus 2, χ = −2. */
Test(crease, double_torus_closed_off_lattice)
{
    const double box[6] = {-1.8, -1.8, -0.8, 4, 1.8, 0.8};
    check_seams("min((x^2 + y^2 + z^2 + 0.75)^2 - 4*(x^2 + y^2), "
                "((x - 2.2)^2 + y^2 + z^2 + 0.75)^2 - 4*((x - 2.2)^2 + y^2))", box, -2, 1);
}

/* The double torus's seam at depth 9 in the sweep's 1e-3 box, where the seam's pocket (the
 * notch between the tori, x = 1.1) runs along the lattice line z = −0.489925, its crease
 * 3e-5 to 7.5e-5 above it: a + strip 4e-4 to 7e-4 wide crossing tiles 0.011 wide. Two
 * defects left a hole there (χ −3, one boundary loop): the tangent lines of the two sheets
 * at a segment's ends met at f = −1.1e-4 while f rose to +9e-5 between them (roots missed,
 * a chord that could not be lifted), and with the roots found the − sign's diagonal stepped
 * over the strip, so both signs looked joined and the centre's sign cut the strip into two
 * bumps (11 boundary edges, 4 non-manifold). Meshed here in the block of 128 × 128 × 128
 * finest cells of that lattice around the spot (same cells; 0.04 s), at depth 7: no
 * boundary edge off the box's faces, no non-manifold edge. */
Test(crease, double_torus_pocket_along_a_lattice_line)
{
    const double base[6] = {-1.8, -1.8, -0.8, 4, 1.8, 0.8};
    const int lo[3] = {192, 192, 64}, cells = 128, depth = 7;
    double big[6], box[6];
    pf_sweep_box(base, 9, 0, big);
    for (int k = 0; k < 3; k++) {
        double ext = big[k + 3] - big[k];
        box[k] = big[k] + ext * lo[k] / 512;
        box[k + 3] = big[k] + ext * (lo[k] + cells) / 512;
    }
    const pf_surface s = {"min((x^2 + y^2 + z^2 + 0.75)^2 - 4*(x^2 + y^2), "
                          "((x - 2.2)^2 + y^2 + z^2 + 0.75)^2 - 4*((x - 2.2)^2 + y^2))",
                          NULL, 0, NULL, 0};
    ism_tape *t = pf_compile(&s);
    ism_mesh m;
    ism_poly_stats st;
    pf_run(t, box, 3, depth, 0, &m, &st);
    size_t holes = pf_count_edges(&m, 1, 1, pf_inside_box, box);
    size_t nm = pf_count_edges(&m, 3, SIZE_MAX, NULL, NULL);
    cr_expect_eq(holes, 0, "%zu boundary edges inside the box", holes);
    cr_expect_eq(nm, 0, "%zu non-manifold edges", nm);
    ism_mesh_free(&m);
    ism_tape_free(t);
}

/* The double torus under an error bound E = 2e-3 of its box's width (0.0116), depth 8: closed
 * (no boundary edge, no non-manifold edge), χ −2, one piece, in the three placements and on
 * the lattice where the sweep under a bound found a crack (the box moved by (0.37, −0.23,
 * 0.41) of a depth-8 cell, the placement PF_OLD_* once was: a regression case). There the
 * crease passes 1e-5 from the lattice edge y = −1.015734375, z = 0.0525625, which holds two
 * roots 1.8e-5 apart either side of the mirror plane x = 1.1; a tile beside it paired them as
 * a chord whose lift ran up the mirror plane inside the wedge between the tori and found no
 * arc, and the flat triangle this left in the node above was emitted by no node (face_lines.c
 * unlifted_chord): χ −3, 4 boundary edges. */
Test(crease, double_torus_closed_under_a_bound)
{
    const pf_surface s = {"min((x^2 + y^2 + z^2 + 0.75)^2 - 4*(x^2 + y^2), "
                          "((x - 2.2)^2 + y^2 + z^2 + 0.75)^2 - 4*((x - 2.2)^2 + y^2))",
                          NULL, 0, NULL, 0};
    const double base[6] = {-1.8, -1.8, -0.8, 4, 1.8, 0.8};
    const int depth = 8;
    ism_tape *t = pf_compile(&s);
    for (int w = pf_first_box() - 1; w < 3; w++) {
        double box[6];
        if (w < 2)
            pf_sweep_box(base, depth, w, box);
        else
            pf_sweep_box_old(base, depth, 1, box); /* the regression box */
        ism_poly_options o;
        pf_options(&o, box, 3, depth);
        o.max_error = 2e-3 * (box[3] - box[0]);
        ism_mesh m;
        ism_poly_stats st;
        pf_run_options(t, &o, &m, &st);
        pf_props p;
        pf_measure(&m, t, &p);
        cr_expect_eq(p.boundary_edges, 0, "placement %d: %zu boundary edges", w, p.boundary_edges);
        cr_expect_eq(p.nonmanifold_edges, 0, "placement %d: %zu non-manifold edges", w,
                     p.nonmanifold_edges);
        cr_expect_eq(p.euler, -2, "placement %d: χ = %ld", w, p.euler);
        cr_expect_eq(p.components, 1, "placement %d: %zu components", w, p.components);
        ism_mesh_free(&m);
    }
    ism_tape_free(t);
}

/* A plate's top poking 0.2 cells through a tile's lower side under a plane 0.4 cells up,
 * whose region holds the tile's centre: max(y − 0.4c, min(0.12c − |x − x_c|, 0.2c − y,
 * 0.47 − |z|)), box ±1 at depth 5 (c = 1/16), x_c the middle of the cell [0, c]. On the z
 * tiles of the cells [0, c]², the − arcs' points are the two corners of the lower side
 * (no straight path: the + bump lies between), the + arcs' path crosses the − band, the
 * gradient scores tie (the bump's sides face each other, the plane's crossings agree) and
 * the centre's + sign joined the bump to the plane: one piece, χ 0. The plane (a disk in the
 * box) and the plate (a box open at y = −1: a disk) are two pieces, χ 2. Also in the
 * sweep's shifted boxes, the surface staying put (the 1e-3 box showed the same fault). */
Test(crease, narrow_bump_under_a_plane)
{
    const pf_surface s = {"max(y - 0.025, min(0.0075 - abs(x - 0.03125), 0.0125 - y, "
                          "0.47 - abs(z)))", NULL, 0, NULL, 0};
    const double base[6] = {-1, -1, -1, 1, 1, 1};
    ism_tape *t = pf_compile(&s);
    for (int w = -1; w < 2; w++) {
        double box[6];
        ism_mesh m;
        pf_props p;
        pf_run_placed(t, base, 5, w, box, &m, &p);
        cr_expect_eq(p.components, 2, "box %d: %zu pieces", w, p.components);
        cr_expect_eq(p.euler, 2, "box %d: χ = %ld", w, p.euler);
        cr_expect_eq(p.nonmanifold_edges, 0, "box %d: %zu non-manifold edges", w,
                     p.nonmanifold_edges);
        ism_mesh_free(&m);
    }
    ism_tape_free(t);
}

/* The cube max(|x|, |y|, |z|) = 1: the exact distance (outside: the length of the excess over
 * the faces; inside: to the nearest face). */
static double cube_dist(const double p[3])
{
    double out = 0, in = INFINITY;
    for (int a = 0; a < 3; a++) {
        double e = fabs(p[a]) - 1;
        out += e > 0 ? e * e : 0;
        in = fmin(in, -e);
    }
    return out > 0 ? sqrt(out) : in;
}

/* Steinmetz's tricylinder, the common part of x² + y², y² + z², z² + x² <= 1: inside, the
 * exact distance is to the nearest cylinder (the boundary lies on the cylinders, and the
 * nearest point of one lies in the others or a nearer boundary point lies between); outside
 * (vertex rounding, 1e-7) the length of the excesses over the cylinders, near enough there. */
static double steinmetz_dist(const double p[3])
{
    double out = 0, in = INFINITY;
    for (int a = 0; a < 3; a++) {
        double e = hypot(p[a], p[(a + 1) % 3]) - 1;
        out += e > 0 ? e * e : 0;
        in = fmin(in, -e);
    }
    return out > 0 ? sqrt(out) : in;
}

/* Crease cells stop as soon as they meet E. At the default bound (1e-3 × the diagonal of the
 * box ±1.3, 0.0045) the nodes along the cube's edges and corners failed the plot test above
 * 4 E across (plot_test.c CREASE_CELL_ERRORS: their corner gradients disagree, and the graph
 * certificate gave up at the max() kink) and split to depth 8 (27,488 triangles) although at
 * depth.max 7 the mesh met E (15,800; closed form 0.0031). The certificate now encloses ∇f on
 * each side of the kink (graph_cert.c): both faces rise along one direction, so the node is
 * one graph and its measured triangles decide. Three placements: depth.max `stop` and 10 give
 * the same mesh, no leaf misses E, and the mesh is within E at every vertex, centroid and edge
 * midpoint by the closed form. Steinmetz, 5: its cylinders meet at most 60° apart (normals
 * (x, y, 0) and (x, 0, z) on the crease y = ±z: cos = x² >= 1/2), an open crease, so its
 * crease nodes are judged by their cut polygons within the same limits as the cube's
 * (plot_test.c CURVED_CREASE_COS): 2,040 triangles; before, at depth.max 5, 3,336 with 224
 * nodes unresolved against 9,024 at 10 (the uncut corner test split to depth 8). The cube, 5:
 * its pieces are planes, so its crease nodes are judged by their polygons cut along the crease
 * (exact) once they are at most 40 E across their smallest side with two pieces, 24 E at a
 * corner (plot_test.c CREASE_PIECES_ERRORS, CREASE_JUNCTION_ERRORS): 40 E = 0.18 takes the
 * depth-4 cells (2.6 / 16 = 0.1625), 24 E = 0.108 the depth-5 ones (0.081), so nothing is
 * split past depth 5 (1,248 triangles at bf994e9); before, the uncut corner test split them
 * to depth 7 (9,608 / 9,624 triangles at d4030da; at depth.max 5, 296 nodes unresolved). */
static void check_crease_stops(const char *expr, double (*dist)(const double *), int stop)
{
    const pf_surface s = {expr, NULL, 0, NULL, 0};
    const double base[6] = {-1.3, -1.3, -1.3, 1.3, 1.3, 1.3};
    ism_tape *t = pf_compile(&s);
    for (int w = pf_first_box() - 1; w < 2; w++) {
        ism_poly_options o;
        pf_options(&o, base, 3, stop);
        pf_sweep_box(base, 10, w, o.box);
        o.max_error = pf_default_error(o.box);
        ism_mesh ms, m10;
        ism_poly_stats ss, s10;
        pf_run_options(t, &o, &ms, &ss);
        o.max_depth = 10;
        pf_run_options(t, &o, &m10, &s10);
        char what[96];
        snprintf(what, sizeof what, "%s placement %d: depth.max %d and 10", expr, w, stop);
        pf_same_mesh(&ms, &m10, what);
        cr_expect_eq(s10.error_missed_nodes, 0, "%s: %llu leaves missed E", what,
                     (unsigned long long)s10.error_missed_nodes);
        double worst = pf_worst_distance(&m10, dist);
        cr_expect_leq(worst, o.max_error, "%s: %g from the surface, E %g", what, worst,
                      o.max_error);
        pf_props p;
        pf_measure(&m10, t, &p);
        cr_expect_eq(p.boundary_edges + p.nonmanifold_edges, 0, "%s: not closed", what);
        cr_expect_eq(p.euler, 2, "%s: χ %ld", what, p.euler);
        ism_mesh_free(&ms);
        ism_mesh_free(&m10);
    }
    ism_tape_free(t);
}

Test(crease, cube_creases_stop_where_the_bound_is_met)
{
    check_crease_stops("max(abs(x), abs(y), abs(z)) - 1", cube_dist, 5);
}

Test(crease, steinmetz_creases_stop_where_the_bound_is_met)
{
    check_crease_stops("max(x^2 + y^2, y^2 + z^2, z^2 + x^2) - 1", steinmetz_dist, 5);
}

/* The three balls' creases at the default bound (1e-3 × the diagonal of the box ±1.5, depth.max
 * 10) in the three placements: every triangle's smallest angle at least THREE_BALLS_FLOOR. The
 * creases, all cut (nested min: each ball a piece), made triangles no raw mesh of a smooth
 * surface has: two copies of one point a rounding error apart where a crease point or the
 * balls' meeting point landed on a vertex (its own box: the crease of the two balls
 * mirrored in y = 0 lies in that lattice plane; the irrational box: the meeting point
 * (0, 0, ±0.374) computed by each triangle round it), zero-area triangles, 4 in the own and
 * the irrational box; and a crease point 3 µm off a cell's corner cut to the 0.0042° / 0.0022°
 * / 0.0046° slivers the own / 1e-3 / irrational boxes had. Folded where the fold meets the
 * bound, a crease through a corner left whole and the meeting point snapped to the vertex it
 * lands on, the smallest are 0.067° / 0.025° / 0.012°, the lattice's own: two edge roots a
 * few millionths of a cell from one grid corner, the marching-cubes sliver (--quality good's to
 * mend). The floor sits under those, above what the cuts made. */
#define THREE_BALLS_FLOOR 0.01

Test(crease, three_balls_no_sliver_where_the_pieces_meet)
{
    const pf_surface s = {"min((x - 0.6)^2 + y^2 + z^2 - 0.5, (x + 0.3)^2 + (y - 0.52)^2 + z^2 - "
                          "0.5, (x + 0.3)^2 + (y + 0.52)^2 + z^2 - 0.5)",
                          NULL, 0, NULL, 0};
    const double base[6] = {-1.5, -1.5, -1.5, 1.5, 1.5, 1.5};
    ism_tape *t = pf_compile(&s);
    for (int w = pf_first_box() - 1; w < 2; w++) {
        ism_poly_options o;
        pf_options(&o, base, 3, 10);
        pf_sweep_box(base, 10, w, o.box);
        o.max_error = pf_default_error(o.box);
        ism_mesh m;
        ism_poly_stats st;
        pf_run_options(t, &o, &m, &st);
        double worst = 180;
        size_t under = 0;
        for (size_t k = 0; k < m.ntris; k++) {
            double a = pf_tri_min_angle(&m, k);
            under += !(a >= THREE_BALLS_FLOOR); /* NaN: two corners at one place */
            worst = a < worst ? a : worst;
        }
        cr_expect_eq(under, 0, "placement %d: %zu triangles under %g° (smallest %g°)", w, under,
                     THREE_BALLS_FLOOR, worst);
        pf_props p;
        pf_measure(&m, t, &p);
        cr_expect_eq(p.euler, 2, "placement %d: χ %ld", w, p.euler);
        ism_mesh_free(&m);
    }
    ism_tape_free(t);
}

/* Vertex positions ordered by x (then y, z), for nearest_pair. */
static int by_x(const void *a, const void *b)
{
    const double *p = *(const double *const *)a, *q = *(const double *const *)b;
    for (int k = 0; k < 3; k++)
        if (p[k] != q[k])
            return p[k] < q[k] ? -1 : 1;
    return 0;
}

/* The distance between the two nearest vertices of m, measured here over the positions alone
 * (sorted by x: a pair nearer than the best so far differs by less in x); INFINITY for fewer
 * than two vertices. */
static double nearest_pair(const ism_mesh *m)
{
    const double **p = malloc((m->nverts ? m->nverts : 1) * sizeof *p);
    cr_assert_not_null(p);
    for (size_t i = 0; i < m->nverts; i++)
        p[i] = m->pos + 3 * i;
    qsort(p, m->nverts, sizeof *p, by_x);
    double best = INFINITY;
    for (size_t i = 0; i < m->nverts; i++)
        for (size_t j = i + 1; j < m->nverts && p[j][0] - p[i][0] < best; j++) {
            double d = hypot(hypot(p[j][0] - p[i][0], p[j][1] - p[i][1]), p[j][2] - p[i][2]);
            best = d < best ? d : best;
        }
    free(p);
    return best;
}

/* Two vertices of a raw mesh nearer than this × the box diagonal are one point written twice:
 * a vertex's rounding is 1e-16 of its coordinates, the copies the crease cut made 1e-16 to
 * 1.4e-14 apart (the double torus's own box), while the nearest distinct vertices of the
 * meshes below are 8.0e-6 / 1.5e-6 / 5.4e-6 of the diagonal apart in the own / 1e-3 / irr
 * boxes (two edge roots beside one grid corner). */
#define ONE_POINT_REL 1e-9

/* A crease in a lattice plane is cut at each crease point once. Under the default bound
 * (1e-3 × the box diagonal) a triangle with corners on both branches of f's top min is cut at
 * its mixed edges' crease points (crease_split.c); where the crease lies in a lattice plane
 * its edge roots there are crease points already, and Newton's crease point on an edge from
 * such a corner landed 1e-16 to 1e-14 beside it: a second vertex the exact weld kept apart,
 * with zero-area triangles between the copies (the double torus in its own box, whose tori
 * meet in x = 1.1, the middle plane: 1.1 − (−1.8) = 5.8 / 2; 392 such pairs, 498 zero-area
 * triangles; in the irrational box 17 pairs where edge roots fell within rounding of the
 * crease). Three placements (own: the crease in a lattice plane by construction; 1e-3, irr:
 * beside it): no two vertices nearer than ONE_POINT_REL × the diagonal, and still closed with
 * the solid's χ. (Two balls meeting in a lattice plane, min((x + 0.2)² + y² + z² − 0.5,
 * (x − 0.8)² + y² + z² − 0.5) in the box x ∈ [−1.2, 1.8], never showed it: Newton's steps
 * from such a corner stay below the rounding of its coordinates there.) */
static void check_one_vertex_per_point(const char *expr, const double base[6], int depth,
                                       long euler)
{
    const pf_surface s = {expr, NULL, 0, NULL, 0};
    ism_tape *t = pf_compile(&s);
    for (int w = pf_first_box() - 1; w < 2; w++) {
        ism_poly_options o;
        pf_options(&o, base, 3, depth);
        pf_sweep_box(base, depth, w, o.box);
        o.max_error = pf_default_error(o.box);
        ism_mesh m;
        ism_poly_stats st;
        pf_run_options(t, &o, &m, &st);
        double near = nearest_pair(&m), diag = ism_box_diagonal(o.box);
        cr_expect_geq(near, ONE_POINT_REL * diag, "%s, placement %d: two vertices %g apart "
                      "(%g of the diagonal)", expr, w, near, near / diag);
        pf_props p;
        pf_measure(&m, t, &p);
        cr_expect_eq(p.boundary_edges + p.nonmanifold_edges, 0, "%s, placement %d: not closed",
                     expr, w);
        cr_expect_eq(p.euler, euler, "%s, placement %d: χ %ld", expr, w, p.euler);
        ism_mesh_free(&m);
    }
    ism_tape_free(t);
}

Test(crease, double_torus_one_vertex_per_crease_point)
{
    const double box[6] = {-1.8, -1.8, -0.8, 4, 1.8, 0.8};
    check_one_vertex_per_point("min((x^2 + y^2 + z^2 + 0.75)^2 - 4*(x^2 + y^2), "
                               "((x - 2.2)^2 + y^2 + z^2 + 0.75)^2 - 4*((x - 2.2)^2 + y^2))",
                               box, 7, -2);
}
