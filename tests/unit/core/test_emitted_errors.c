/* test_emitted_errors.c — several leaves' emitted triangles measured together
 * (refine.h's ism_emitted_errors, what polygonise.c's deferred measuring calls) give bit for
 * bit each leaf's own figure and centroid gradients (ism_emitted_error_kept on the leaf
 * alone, the sampler on its local tape), and as many evaluations. Five leaves, each a fan of
 * triangles on the unit sphere of f = max(|p|² − 1, z − 0.3) below the plane, three of them
 * with their own shortened tape (the sphere's branch, decided over their boxes) and two with
 * none, at a bound that puts their points in all three bands of the measuring (within E / 2:
 * first order; up to E: Newton's second step; beyond E: the bound through the corners and
 * the search) — the bands asserted from the closed form, which every figure bounds from
 * above. The surface and the fans in the own placement, moved by PF_OFF_* and by PF_IRR_*
 * of the fan's nearer radius. */
#include <criterion/criterion.h>
#include <math.h>
#include <stdio.h>
#include <string.h>
#include "poly_fixture.h"
#include "core/eval/eval.h"
#include "core/octree/cell.h"
#include "core/expr/tape.h"
#include "core/octree/refine.h"
#include "core/octree/triangulate.h"

#define LEAVES 5
#define FAN 6          /* rim vertices a fan: FAN triangles, each sharing a side with the last */
/* Radians from the fan's centre to its rim vertices, alternately: a side of length a sags
 * ~a² / 8 below the sphere (0.00045, 0.00245), the centroids between; FAN_FAR shrinks
 * leaf by leaf, so some leaves' worst points lie within E (their second steps count). */
#define FAN_NEAR 0.06
#define FAN_FAR 0.14
#define FAN_Z (-0.35)  /* the centres' height: a box round a fan lies below z = 0, so the
                          sphere's branch is decided there (|p|² − 1 > −0.3 > z − 0.3) */
#define BOX_PAD 0.01   /* a leaf's box: its vertices' bounding box, this much larger */
/* The bound: the sides' sags on either side of it and of E / 2 (FAN_NEAR, FAN_FAR). */
#define E 0.002

/* The point at longitude lon, angle a from the fan centre's direction (height FAN_Z). */
static void on_sphere(double lon, double a, double rim_angle, const double off[3], double p[3])
{
    double zc = FAN_Z, rc = sqrt(1 - zc * zc);
    double c[3] = {rc * cos(lon), rc * sin(lon), zc};                /* the centre */
    double e1[3] = {-sin(lon), cos(lon), 0};                         /* east */
    double e2[3] = {-zc * cos(lon), -zc * sin(lon), rc};             /* north: c × e1 */
    for (int k = 0; k < 3; k++)
        p[k] = cos(a) * c[k] + sin(a) * (cos(rim_angle) * e1[k] + sin(rim_angle) * e2[k]) +
               off[k];
}

/* Leaf k's fan appended to out (its triangles from *t0 to *t1), its box into box. */
static void fan(int k, const double off[3], ism_cell_out *out, size_t *t0, size_t *t1,
                double box[6])
{
    double lon = 0.5 * k;
    uint32_t idx[FAN + 1];
    for (int a = 0; a < 3; a++)
        box[a] = INFINITY, box[3 + a] = -INFINITY;
    for (int i = 0; i <= FAN; i++) {
        ism_fpoint v = {{0}, {0, 0, 1}, 0};
        double far = FAN_FAR * (1 - 0.15 * k); /* later leaves' worst in the lower bands */
        on_sphere(lon, !i ? 0 : i % 2 ? FAN_NEAR : far, 2 * M_PI * i / FAN, off, v.p);
        cr_assert(ism_cell_out_vert(out, &v, &idx[i]));
        for (int a = 0; a < 3; a++) {
            box[a] = fmin(box[a], v.p[a] - BOX_PAD);
            box[3 + a] = fmax(box[3 + a], v.p[a] + BOX_PAD);
        }
    }
    *t0 = out->ntris;
    for (int i = 1; i <= FAN; i++)
        cr_assert(ism_cell_out_tri(out, idx[0], idx[i], idx[i % FAN + 1]));
    *t1 = out->ntris;
}

/* |1 − |p − off||: the distance to the sphere, the surface beside the fans. */
static double sphere_dist(const double p[3], const double off[3])
{
    double r2 = 0;
    for (int k = 0; k < 3; k++)
        r2 += (p[k] - off[k]) * (p[k] - off[k]);
    return fabs(1 - sqrt(r2));
}

/* The closed form at leaf span's centroids and side midpoints: its largest, and each band's
 * count (within E / 2, up to E, beyond) added to bands. */
static double closed_form(const ism_cell_out *out, size_t t0, size_t t1, const double off[3],
                          int bands[3])
{
    double worst = 0;
    for (size_t t = t0; t < t1; t++) {
        const double *v[3];
        for (int k = 0; k < 3; k++)
            v[k] = out->verts[out->tris[3 * t + k]].p;
        double pts[4][3];
        for (int a = 0; a < 3; a++) {
            pts[0][a] = (v[0][a] + v[1][a] + v[2][a]) / 3;
            for (int k = 0; k < 3; k++)
                pts[1 + k][a] = (v[k][a] + v[(k + 1) % 3][a]) / 2;
        }
        for (int j = 0; j < 4; j++) {
            double d = sphere_dist(pts[j], off);
            worst = fmax(worst, d);
            bands[d <= E / 2 ? 0 : d <= E ? 1 : 2]++;
        }
    }
    return worst;
}

static void check_placement(const double off[3], int placed)
{
    char expr[256]; /* f moved by off */
    snprintf(expr, sizeof expr,
             "max((x - %.17g)^2 + (y - %.17g)^2 + (z - %.17g)^2 - 1, z - %.17g - 0.3)", off[0],
             off[1], off[2], off[2]);
    const pf_surface cut_ball = {expr, NULL, 0, NULL, 0};
    ism_tape *f = pf_compile(&cut_ball);
    ism_eval_ws *ws = ism_eval_ws_new(f);
    cr_assert(f && ws);
    ism_cell_out out;
    memset(&out, 0, sizeof out);
    ism_leaf_span span[LEAVES];
    ism_tape *local[LEAVES] = {NULL};
    for (int k = 0; k < LEAVES; k++) {
        double box[6];
        memset(&span[k], 0, sizeof span[k]);
        fan(k, off, &out, &span[k].t0, &span[k].t1, box);
        if (k % 2 == 0) { /* leaves 0, 2, 4: their own shortened tape, decided */
            local[k] = ism_tape_new_like(f);
            cr_assert(local[k] && ism_tape_shorten(f, ws, (ism_interval){box[0], box[3]},
                                                   (ism_interval){box[1], box[4]},
                                                   (ism_interval){box[2], box[5]}, local[k],
                                                   NULL));
            cr_assert_lt(local[k]->len, f->len, "placement %d: leaf %d's tape not shortened",
                         placed, k);
        }
        span[k].leaf.local = local[k];
        memcpy(span[k].leaf.box, box, sizeof box);
    }
    ism_sampler one = {.tape = f, .ws = ws, .dist_above = E, .batch = true};
    ism_sampler all = one;
    /* each leaf alone: the figure, its centroid gradients, the evaluations */
    double err[LEAVES], cg[LEAVES][FAN][3];
    int bands[3] = {0, 0, 0};
    for (int k = 0; k < LEAVES; k++) {
        ism_sampler_leaf_set(&one, &span[k].leaf);
        ism_cell_out view = out;
        view.ntris = span[k].t1;
        err[k] = ism_emitted_error_kept(&one, &view, span[k].t0, INFINITY, cg[k]);
        double exact = closed_form(&out, span[k].t0, span[k].t1, off, bands);
        cr_expect_geq(err[k], exact * (1 - 1e-9), "placement %d leaf %d: %.17g below %.17g",
                      placed, k, err[k], exact);
        cr_expect_leq(err[k], 2 * exact, "placement %d leaf %d: %.17g far above %.17g",
                      placed, k, err[k], exact);
    }
    for (int b = 0; b < 3; b++)
        cr_expect_gt(bands[b], 0, "placement %d: no point in band %d", placed, b);
    /* all leaves together */
    ism_measure_scratch w;
    memset(&w, 0, sizeof w);
    cr_assert(ism_emitted_errors(&all, &out, span, LEAVES, &w));
    for (int k = 0; k < LEAVES; k++) {
        cr_expect(!memcmp(&span[k].err, &err[k], sizeof err[k]),
                  "placement %d leaf %d: %.17g together, %.17g alone", placed, k, span[k].err,
                  err[k]);
        cr_expect(!memcmp(w.cg[span[k].cg0], cg[k], sizeof cg[k]),
                  "placement %d leaf %d: centroid gradients differ", placed, k);
    }
    cr_expect_eq(all.n_gradient, one.n_gradient, "placement %d: %llu gradients, %llu alone",
                 placed, (unsigned long long)all.n_gradient,
                 (unsigned long long)one.n_gradient);
    cr_expect_eq(all.n_point, one.n_point, "placement %d", placed);
    ism_measure_scratch_free(&w);
    for (int k = 0; k < LEAVES; k++)
        if (local[k])
            ism_tape_free(local[k]);
    ism_cell_out_free(&out);
    ism_eval_ws_free(ws);
    ism_tape_free(f);
}

Test(emitted_errors, leaves_together_as_each_alone_in_three_placements)
{
    const double s = FAN_NEAR;
    const double offs[3][3] = {{0, 0, 0},
                               {PF_OFF_X, PF_OFF_Y, PF_OFF_Z},
                               {PF_IRR_X * s, PF_IRR_Y * s, PF_IRR_Z * s}};
    for (int b = 0; b < 3; b++)
        check_placement(offs[b], b);
}
