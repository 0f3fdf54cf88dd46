/* test_sheet_groups.c — one normal per half-sheet at a vertex on the singular locus
 * (proto/sheet_groups.h, issue 13), on meshes built here, with expected values from their
 * construction:
 * - two planes z = 0 and y = 0 crossing on the x axis (meshes_for_tests.h, n = 4), every
 *   corner at an axis vertex marked, each triangle's normal its plane's tilted about the x
 *   axis by ±15° by side of the axis and ±6° by triangle parity: each of the 5 axis vertices
 *   has 4 half-sheets (2 planes × 2 sides; the sides' normals 18–42° apart, so the whole-sheet
 *   angle alone could join them: the axis edges must keep them apart, also when the other
 *   plane's corners are unmarked, as a crease side's), each half-sheet's corners one float
 *   triple, the normalised sum of its own (its members up to 12° apart: wider than the fan
 *   angle, so only the whole-sheet rule joins them);
 * - a double cone z² = x² + y² (a node's two nappes, 72 triangles each, outward normals
 *   45° from the axis, neighbours 3.5° apart): every joined normal within the fan angle of
 *   each member's own; the number of fans per nappe at least n / m, m the most consecutive
 *   members whose sum serves them all (computed here from the closed form), at most twice
 *   that (the nappe is joined, not left per triangle), and never one fan (the tip not
 *   rounded into the axis). */
#include <criterion/criterion.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "core/util/vec3.h"
#include "proto/sheet_groups.h"
#include "tests/unit/proto/meshes_for_tests.h"

#define N 4 /* quads per side of each plane */
#define DEG (M_PI / 180)

static bool on_axis(const ism_mesh *m, uint32_t v)
{
    return m->pos[3 * v + 1] == 0 && m->pos[3 * v + 2] == 0;
}

/* Plane (0: z = 0, 1: y = 0) and side (-1, +1 of the axis) of triangle t. */
static void plane_side(const ism_mesh *m, size_t t, int *plane, int *side)
{
    double c[3] = {0, 0, 0};
    for (int k = 0; k < 3; k++)
        for (int d = 0; d < 3; d++)
            c[d] += m->pos[3 * m->tri[3 * t + k] + d];
    *plane = c[2] == 0 ? 0 : 1;
    *side = (*plane ? c[2] : c[1]) > 0 ? 1 : -1;
}

static double angle_f(const float *a, const float *b)
{
    double d = (double)a[0] * b[0] + (double)a[1] * b[1] + (double)a[2] * b[2];
    double la = sqrt((double)a[0] * a[0] + (double)a[1] * a[1] + (double)a[2] * a[2]);
    double lb = sqrt((double)b[0] * b[0] + (double)b[1] * b[1] + (double)b[2] * b[2]);
    return acos(fmin(1, fmax(-1, d / (la * lb))));
}

/* mark_z: whether the z plane's axis corners are marked too (else they are as a crease
 * side's, left alone, and the y plane's two sides meet at the axis edges as the only marked
 * triangles there: only the rule that an edge to a marked vertex is not inside a sheet keeps
 * them apart). */
static void crossing_planes(bool mark_z)
{
    ism_mesh m;
    test_mesh_crossing_planes(&m, N);
    size_t nc = 3 * m.ntris;
    uint8_t *mark = calloc(nc, 1);
    float *cn = malloc(3 * nc * sizeof *cn), *in = malloc(3 * nc * sizeof *in);
    for (size_t c = 0; c < nc; c++) {
        int plane, side;
        plane_side(&m, c / 3, &plane, &side);
        double a = side * 15 * DEG + ((c / 3) % 2 ? 6 : -6) * DEG; /* tilt about the x axis */
        double n[3] = {0, plane ? cos(a) : -sin(a), plane ? sin(a) : cos(a)};
        for (int d = 0; d < 3; d++)
            cn[3 * c + d] = (float)n[d];
        mark[c] = on_axis(&m, m.tri[c]) && (plane || mark_z);
    }
    memcpy(in, cn, 3 * nc * sizeof *cn);
    cr_assert(ism_sheet_groups_join(&m, mark, cn));
    size_t axis = 0;
    for (uint32_t v = 0; v < m.nverts; v++) {
        if (!on_axis(&m, v))
            continue;
        axis++;
        for (int plane = mark_z ? 0 : 1; plane < 2; plane++)
            for (int side = -1; side <= 1; side += 2) {
                double sum[3] = {0, 0, 0};
                size_t members = 0;
                const float *first = NULL, *first_in = NULL;
                for (size_t c = 0; c < nc; c++) {
                    int p, s;
                    plane_side(&m, c / 3, &p, &s);
                    if (m.tri[c] != v || p != plane || s != side)
                        continue;
                    for (int d = 0; d < 3; d++)
                        sum[d] += in[3 * c + d];
                    if (!members++)
                        first = cn + 3 * c, first_in = in + 3 * c;
                    cr_expect_eq(memcmp(cn + 3 * c, first, 3 * sizeof *cn), 0,
                                 "vertex %u plane %d side %d: one normal", v, plane, side);
                }
                cr_assert_gt(members, 0);
                double len = ism_norm3(sum);
                float want[3];
                for (int d = 0; d < 3; d++)
                    want[d] = members > 1 ? (float)(sum[d] / len) : first_in[d];
                cr_expect_eq(memcmp(first, want, sizeof want), 0,
                             "vertex %u plane %d side %d: (%g %g %g), the members' sum (%g %g "
                             "%g)", v, plane, side, (double)first[0], (double)first[1],
                             (double)first[2], (double)want[0], (double)want[1],
                             (double)want[2]);
            }
    }
    cr_expect_eq(axis, N + 1);
    for (size_t c = 0; c < nc; c++)
        if (!mark[c])
            cr_expect_eq(memcmp(cn + 3 * c, in + 3 * c, 3 * sizeof *cn), 0,
                         "unmarked corner %zu untouched", c);
    free(mark);
    free(cn);
    free(in);
    ism_mesh_free(&m);
}

Test(sheet_groups, crossing_planes_keep_four_half_sheets_per_axis_vertex)
{
    crossing_planes(true);
}

Test(sheet_groups, a_sheets_two_sides_stay_apart_without_the_other_sheet)
{
    crossing_planes(false);
}

#define RING 72 /* triangles per nappe: neighbours' normals 3.5° apart, under the fan angle */

/* The outward unit normal of the cone z = s r (s = ±1) at azimuth phi. */
static void cone_normal(int s, double phi, double *n)
{
    n[0] = cos(phi) / sqrt(2);
    n[1] = sin(phi) / sqrt(2);
    n[2] = -s / sqrt(2);
}

/* The most consecutive members (normals at azimuths k 2π/RING) whose normalised sum is within
 * the fan angle of each: from the closed form, not from the code. */
static int most_per_fan(void)
{
    int best = 1;
    for (int k = 2; k <= RING; k++) {
        double sum[3] = {0, 0, 0}, n[3];
        for (int i = 0; i < k; i++) {
            cone_normal(1, 2 * M_PI * i / RING, n);
            for (int d = 0; d < 3; d++)
                sum[d] += n[d];
        }
        double len = ism_norm3(sum), worst = 0;
        for (int i = 0; i < k; i++) {
            cone_normal(1, 2 * M_PI * i / RING, n);
            worst = fmax(worst, acos(fmin(1, (n[0] * sum[0] + n[1] * sum[1] + n[2] * sum[2]) /
                                                 len)));
        }
        if (worst <= ISM_SHEET_FAN_MAX_ANGLE)
            best = k;
    }
    return best;
}

Test(sheet_groups, a_nodes_nappes_are_cut_into_fans_within_the_angle)
{
    ism_mesh m;
    ism_mesh_init(&m);
    double o[3] = {0, 0, 0};
    uint32_t apex = ism_mesh_add_vertex(&m, o, NULL);
    uint32_t ring[2][RING];
    for (int s = 0; s < 2; s++)
        for (int i = 0; i < RING; i++) {
            double phi = 2 * M_PI * (i + 0.5) / RING; /* vertices between the face azimuths */
            double p[3] = {cos(phi), sin(phi), s ? -1 : 1};
            ring[s][i] = ism_mesh_add_vertex(&m, p, NULL);
        }
    for (int s = 0; s < 2; s++)
        for (int i = 0; i < RING; i++) {
            uint32_t a = ring[s][(i + RING - 1) % RING], b = ring[s][i];
            if (s)
                ism_mesh_add_triangle(&m, apex, b, a);
            else
                ism_mesh_add_triangle(&m, apex, a, b);
        }
    size_t nc = 3 * m.ntris;
    uint8_t *mark = calloc(nc, 1);
    float *cn = calloc(3 * nc, sizeof *cn), *in = malloc(3 * nc * sizeof *in);
    for (size_t t = 0; t < m.ntris; t++) {
        int s = t < RING ? 1 : -1;
        double n[3];
        cone_normal(s, 2 * M_PI * (double)(t % RING) / RING, n); /* face t's azimuth */
        for (int k = 0; k < 3; k++)
            for (int d = 0; d < 3; d++)
                cn[9 * t + 3 * k + d] = (float)n[d];
        mark[3 * t] = 1; /* the apex corner */
    }
    memcpy(in, cn, 3 * nc * sizeof *cn);
    cr_assert(ism_sheet_groups_join(&m, mark, cn));
    int per = most_per_fan();
    int lower = (RING + per - 1) / per;
    for (int s = 0; s < 2; s++) {
        int fans = 0;
        for (int i = 0; i < RING; i++) {
            size_t c = 3 * ((size_t)s * RING + (size_t)i);
            cr_expect_leq(angle_f(cn + 3 * c, in + 3 * c), ISM_SHEET_FAN_MAX_ANGLE + 1e-6,
                          "nappe %d face %d: %g°", s, i, angle_f(cn + 3 * c, in + 3 * c) / DEG);
            bool seen = false; /* a normal met before on this nappe: the same fan */
            for (int j = 0; j < i && !seen; j++)
                seen = !memcmp(cn + 3 * c, cn + 9 * ((size_t)s * RING + (size_t)j),
                               3 * sizeof *cn);
            fans += !seen;
        }
        cr_expect_geq(fans, lower, "nappe %d: %d fans, at most %d faces a fan", s, fans, per);
        cr_expect_leq(fans, 2 * lower, "nappe %d: %d fans (%d needed): joined", s, fans, lower);
        cr_expect_geq(fans, 2, "the tip is not one averaged normal");
    }
    for (size_t c = 0; c < nc; c++)
        if (!mark[c])
            cr_expect_eq(memcmp(cn + 3 * c, in + 3 * c, 3 * sizeof *cn), 0);
    free(mark);
    free(cn);
    free(in);
    ism_mesh_free(&m);
}
