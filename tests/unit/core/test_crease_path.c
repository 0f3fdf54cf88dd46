/* test_crease_path.c — the crease path of a cut polygon (crease_split.c crease_path, through
 * ism_crease_cut_loop): where the chord between a polygon's two crease points strays from
 * the crease, points of the crease are put between them. f = max(x² + y² − 1, z): its crease
 * is the unit circle in z = 0, and a polygon in z = 0 has its corners inside the circle on
 * one branch (z) and outside on the other. Newton from a chord's middle moves it radially
 * (both gradients, 2(x, y, 0) and (0, 0, 1), span the radial plane), so a chord between the
 * circle's points at angles α and β has its foot at angle (α + β)/2, 1 − cos((β − α)/2) from
 * the middle: the closed form the path is checked against. Every geometric case is placed
 * as given and moved by PF_OFF_* and by PF_IRR_* (the surface moved with it). */
#include <criterion/criterion.h>
#include <math.h>
#include <stdio.h>
#include <string.h>
#include "poly_fixture.h"
#include "core/eval/eval.h"
#include "core/octree/cell.h"
#include "core/octree/crease_split.h"

#define ON_TOL 1e-9    /* a crease point on the circle (Newton's rounding) */
#define ANGLE_TOL 1e-9 /* a path point at its closed-form angle */

/* A chord of the unit circle over an arc of angle φ sags 1 − cos(φ/2): the path over
 * ARC = 0.6 (ends at ±0.3) under E = 0.02 (sag limit E/2 = 0.01, CREASE_CHORD_SAG) follows
 * the chord (sag 0.0447), its halves (0.0112) and stops at the quarters (0.0028): 3 points,
 * at angles −0.15, 0, 0.15. */
#define ARC 0.6
#define ERROR_BOUND 0.02
#define PATH_POINTS 3

/* f moved by off. */
static ism_tape *circle_crease(const double off[3])
{
    char src[256];
    snprintf(src, sizeof src, "max((x - %.17g)^2 + (y - %.17g)^2 - 1, z - %.17g)", off[0],
             off[1], off[2]);
    pf_surface s = {src, NULL, 0, NULL, 0};
    return pf_compile(&s);
}

static void placements(double offs[3][3])
{
    const double o[3][3] = {{0, 0, 0},
                            {PF_OFF_X, PF_OFF_Y, PF_OFF_Z},
                            {PF_IRR_X * 0.1, PF_IRR_Y * 0.1, PF_IRR_Z * 0.1}};
    memcpy(offs, o, sizeof o);
}

/* pts[i] at radius r[i], angle th[i] in z = 0, moved by off; gradient +z. */
static void polygon(ism_fpoint *pts, size_t n, const double *r, const double *th,
                    const double off[3])
{
    for (size_t i = 0; i < n; i++) {
        ism_fpoint p = {{r[i] * cos(th[i]) + off[0], r[i] * sin(th[i]) + off[1], off[2]},
                        {0, 0, 1},
                        0};
        pts[i] = p;
    }
}

/* The polygon cut by ism_crease_cut_loop under ERROR_BOUND within node (relative to off);
 * out filled. */
static bool cut(ism_tape *t, ism_eval_ws *ws, const ism_fpoint *pts, size_t n,
                const double node_rel[6], const double off[3], ism_cell_out *out)
{
    ism_sampler s = {.tape = t, .ws = ws, .dist_above = ERROR_BOUND};
    double node[6];
    for (int k = 0; k < 6; k++)
        node[k] = node_rel[k] + off[k % 3];
    memset(out, 0, sizeof *out);
    bool done = false;
    cr_assert(ism_crease_cut_loop(&s, pts, n, ism_dist3(node, node + 3), node, ERROR_BOUND,
                                  out, &done));
    return done;
}

/* The angles of out's crease points (ISM_FP_CREASE), each asserted on the circle and inside
 * node_rel; returns how many. */
static size_t crease_angles(const ism_cell_out *out, const double off[3], const double node[6],
                            double *angle, size_t most, int placed)
{
    size_t n = 0;
    for (size_t v = 0; v < out->nverts; v++) {
        if (!(out->verts[v].flags & ISM_FP_CREASE))
            continue;
        double p[3];
        for (int k = 0; k < 3; k++)
            p[k] = out->verts[v].p[k] - off[k];
        cr_expect_leq(fabs(hypot(p[0], p[1]) - 1), ON_TOL, "placement %d: off the circle",
                      placed);
        cr_expect_leq(fabs(p[2]), ON_TOL, "placement %d: off z = 0", placed);
        for (int k = 0; k < 3; k++)
            cr_expect(p[k] > node[k] && p[k] < node[3 + k],
                      "placement %d: a crease point outside the node", placed);
        bool again = false; /* each run's polygon has its own copy (its branch's gradient) */
        for (size_t w = 0; w < v && !again; w++)
            again = (out->verts[w].flags & ISM_FP_CREASE) &&
                    !memcmp(out->verts[w].p, out->verts[v].p, sizeof p);
        if (again)
            continue;
        if (n < most)
            angle[n] = atan2(p[1], p[0]);
        n++;
    }
    return n;
}

/* The polygon of n ≤ 8 corners at radii r, angles th in placement `placed`, cut within node
 * (relative to the placement): the angles of its crease points into angle (at most `most`);
 * returns how many. */
static size_t cut_crease_angles(const double *r, const double *th, size_t n,
                                const double node[6], const double off[3], int placed,
                                double *angle, size_t most)
{
    ism_tape *t = circle_crease(off);
    ism_eval_ws *ws = ism_eval_ws_new(t);
    ism_fpoint pts[8];
    polygon(pts, n, r, th, off);
    ism_cell_out out;
    cr_expect(cut(t, ws, pts, n, node, off, &out), "placement %d: not cut", placed);
    size_t m = crease_angles(&out, off, node, angle, most, placed);
    ism_cell_out_free(&out);
    ism_eval_ws_free(ws);
    ism_tape_free(t);
    return m;
}

/* The same for the quad of corners at radii r, angles ±ARC/2. */
static size_t quad_crease_angles(const double r[4], const double node[6], const double off[3],
                                 int placed, double *angle, size_t most)
{
    const double th[4] = {-ARC / 2, -ARC / 2, ARC / 2, ARC / 2};
    return cut_crease_angles(r, th, 4, node, off, placed, angle, most);
}

/* The quad of corners at radii r cut within node in the three placements: its crease points
 * are the ends at ±ARC/2 and the path's PATH_POINTS at −ARC/4, 0, ARC/4, each at its closed-
 * form angle. */
static void expect_path(const double r[4], const double node[6])
{
    double offs[3][3];
    placements(offs);
    const double want[2 + PATH_POINTS] = {-ARC / 2, -ARC / 4, 0, ARC / 4, ARC / 2};
    for (int placed = 0; placed < 3; placed++) {
        double angle[2 + PATH_POINTS + 4];
        size_t n = quad_crease_angles(r, node, offs[placed], placed, angle, 2 + PATH_POINTS + 4);
        cr_expect_eq(n, 2 + PATH_POINTS, "placement %d: %zu crease points", placed, n);
        for (size_t i = 0; i < n && i < 2 + PATH_POINTS; i++) {
            bool found = false;
            for (int j = 0; j < 2 + PATH_POINTS; j++)
                found |= fabs(angle[i] - want[j]) <= ANGLE_TOL;
            cr_expect(found, "placement %d: a crease point at angle %.12g", placed, angle[i]);
        }
    }
}

/* A quad across the circle over ARC: its two mixed edges meet the circle at ±ARC/2; the path
 * points are the circle's points at −ARC/4, 0, ARC/4 (in order along the chord: their angles
 * are the chord's parameter's order), inside the node. */
Test(crease_path, follows_the_circle_between_the_ends)
{
    const double r[4] = {0.8, 1.2, 1.2, 0.8};
    const double node[6] = {0.5, -0.6, -0.1, 1.3, 0.6, 0.1};
    expect_path(r, node);
}

/* A quad over the same arc, its outer corners at radius 1.03 (x ≤ 1.03 cos 0.3 = 0.984), in a
 * node whose side x < 0.99 holds every corner and both ends (x = cos 0.3 = 0.955) but not the
 * chord's foot (1, 0): the path is dropped and the chord stays (2 crease points). */
Test(crease_path, no_path_where_a_foot_leaves_the_node)
{
    double offs[3][3];
    placements(offs);
    const double r[4] = {0.8, 1.03, 1.03, 0.8};
    const double node[6] = {0.5, -0.6, -0.1, 0.99, 0.6, 0.1};
    for (int placed = 0; placed < 3; placed++) {
        double angle[8];
        size_t n = quad_crease_angles(r, node, offs[placed], placed, angle, 8);
        cr_expect_eq(n, 2, "placement %d: %zu crease points", placed, n);
    }
}

/* The quad of no_path_where_a_foot_leaves_the_node (outer corners at radius 1.03: its outer
 * side, x ≤ 0.984, passes inside the foot (1, 0)) in a node that holds the foot: the path
 * lies past the polygon's outer side, as a curved leaf polygon's may (Barth's at 0.0259 reach
 * 0.20 of their chord past it), but leaves both ends into the polygon (each end's point at
 * ±ARC/4 lies on the quad's side of its radial edge) and is kept: the same 3 points as
 * follows_the_circle_between_the_ends. */
Test(crease_path, a_path_past_a_far_side_is_kept)
{
    const double r[4] = {0.8, 1.03, 1.03, 0.8};
    const double node[6] = {0.5, -0.6, -0.1, 1.3, 0.6, 0.1};
    expect_path(r, node);
}

/* revC 1: a hexagon that holds most of the circle, one corner Q inside it (radius 0.9, angle
 * 135°) between two outside (radius 1.3, angles 95° and 175°): its sides at Q cut the circle
 * at two points near 135° ± 20° whose chord is short, and the crease inside the hexagon is
 * the long arc round the far side. Newton from the chord's middle goes radially out to the
 * short arc (angle 135°, sag 0.02-0.03 > E/2), past the hexagon's sides at Q: a path there
 * put the run polygons' triangles outside the hexagon (over a neighbour's): its point leaves
 * each end 0.105 of the chord outward past the side the end lies on. The chord must stay:
 * the cut's crease points are its two ends only, and none lies on the short arc between them
 * (closed form: its angle strictly between the ends'). */
Test(crease_path, no_path_onto_an_arc_outside_the_polygon)
{
    double offs[3][3];
    placements(offs);
    const double deg = M_PI / 180;
    const double r[6] = {0.9, 1.3, 1.6, 1.6, 1.6, 1.3};
    const double th[6] = {135 * deg, 175 * deg, 250 * deg, 330 * deg, 390 * deg, 455 * deg};
    const double node[6] = {-1.7, -1.7, -0.1, 1.7, 1.7, 0.1};
    for (int placed = 0; placed < 3; placed++) {
        double angle[8];
        size_t n = cut_crease_angles(r, th, 6, node, offs[placed], placed, angle, 8);
        cr_expect_eq(n, 2, "placement %d: %zu crease points", placed, n);
        if (n >= 2 && n <= 8) {
            double a0 = fmin(angle[0], angle[1]), a1 = fmax(angle[0], angle[1]);
            cr_expect(a0 > 90 * deg && a1 < 180 * deg && a1 - a0 < 90 * deg,
                      "placement %d: ends at %g, %g rad", placed, angle[0], angle[1]);
            for (size_t i = 2; i < n; i++)
                cr_expect(!(angle[i] > a0 && angle[i] < a1),
                          "placement %d: a crease point on the arc outside, at %g rad", placed,
                          angle[i]);
        }
    }
}

/* revE 1: each end of the path is checked on its own. A heptagon whose only corner inside
 * the circle is Q (radius 0.93, angle 135°), P_b (1.37, 195°) after it, P_a (1.02, 108°)
 * before it, four more corners at radius 1.5. The side P_a → Q runs nearly along the circle,
 * up to 0.07 inside it, so its crease point (crease_point: the branches' gap interpolated
 * between the corners, then Newton radially onto the circle) lies at 113.7°, 0.07 outside
 * that side; on Q → P_b it lies at 145.0°. Their chord sags 0.037 > E/2 and its foot, the one
 * path point (halves 0.0093), lies at 129.3°: seen from the end on Q → P_b it lies 0.045 on
 * the inner side of that edge, from the end on P_a → Q 0.051 on the outer side of that one
 * (a scratch model of those steps, matched by the code's own figures). So the path leaves one
 * end inward and the other outward (a fold there); the heptagon reflected in the line at 135°
 * (angle a → 270° − a, listed the same way round) swaps which mixed edge's end is which. In
 * both the chord must stay: the cut's crease points are its two ends only, none between
 * them. A check of one end that reads the other's edge, point or path end, or no check of
 * one end, shows in one of the two. */
Test(crease_path, no_path_that_leaves_one_end_outward)
{
    double offs[3][3];
    placements(offs);
    const double deg = M_PI / 180;
    const double r[7] = {0.93, 1.37, 1.5, 1.5, 1.5, 1.5, 1.02};
    const double th[7] = {135, 195, 250, 304, 359, 413, 468};
    const double node[6] = {-1.7, -1.7, -0.1, 1.7, 1.7, 0.1};
    for (int mirrored = 0; mirrored < 2; mirrored++) {
        double rr[7], tt[7];
        for (int i = 0; i < 7; i++) { /* Q first, counter-clockwise */
            int j = mirrored && i > 0 ? 7 - i : i;
            rr[i] = r[j];
            tt[i] = (mirrored ? 270 - th[j] : th[j]) * deg;
        }
        for (int placed = 0; placed < 3; placed++) {
            double angle[8];
            size_t n = cut_crease_angles(rr, tt, 7, node, offs[placed], placed, angle, 8);
            cr_expect_eq(n, 2, "mirrored %d, placement %d: %zu crease points", mirrored, placed,
                         n);
            if (n >= 2 && n <= 8) {
                double a0 = fmin(angle[0], angle[1]), a1 = fmax(angle[0], angle[1]);
                cr_expect(a0 > 90 * deg && a1 < 180 * deg && a1 - a0 > 10 * deg,
                          "mirrored %d, placement %d: ends at %g, %g rad", mirrored, placed,
                          angle[0], angle[1]);
                for (size_t i = 2; i < n; i++)
                    cr_expect(!(angle[i] > a0 && angle[i] < a1),
                              "mirrored %d, placement %d: a crease point between the ends, at "
                              "%g rad", mirrored, placed, angle[i]);
            }
        }
    }
}
