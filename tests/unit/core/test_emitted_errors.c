/* test_emitted_errors.c — several leaves' emitted triangles measured together
 * (refine.h's ism_emitted_errors, what polygonise.c's deferred measuring calls) give bit for
 * bit each leaf's own figure and centroid gradients (ism_emitted_error_kept on the leaf
 * alone, the sampler on its local tape), and as many evaluations. Six leaves, each a fan of
 * triangles on the surface of f = max(|p|² − 1, z − 0.3): five on the unit sphere below the
 * plane, one on the flat cap z = 0.3. Four have their own shortened tape (leaves 0, 2, 4: the
 * sphere's branch; leaf 5: the plane's, each decided over its box), two have none (f's).
 * A leaf's tape is shortened from 2^(k+1)·f, which gives every distance bit for bit as f
 * does but a gradient 2^(k+1) times f's: a point evaluated on another leaf's tape, or on f's
 * where its leaf's should be, shows in its centroid gradient. Leaf 2's box leaves out part
 * of its fan, so its points fall on two tapes (its own inside, f's outside). The bound puts
 * the points in all three bands of the measuring (within E / 2: first order; up to E:
 * Newton's second step; beyond E: the bound through the corners and the search) — the bands
 * asserted from the closed form, which every figure bounds from above. The surface and the
 * fans in the own placement, moved by PF_OFF_* and by PF_IRR_* of the fan's nearer radius. */
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

#define LEAVES 6
#define CAP_LEAF 5     /* the fan on the flat cap; the others on the sphere */
#define SPLIT_LEAF 2   /* the leaf whose box holds only part of its fan */
#define FAN 6          /* rim vertices a fan: FAN triangles, each sharing a side with the last */
/* Radians from the fan's centre to its rim vertices, alternately: a side of length a sags
 * ~a² / 8 below the sphere (0.00045, 0.00245), the centroids between; FAN_FAR shrinks
 * leaf by leaf, so some leaves' worst points lie within E (their second steps count). */
#define FAN_NEAR 0.06
#define FAN_FAR 0.14
#define FAN_Z (-0.35)  /* the centres' height: a box round a fan lies below z = 0, so the
                          sphere's branch is decided there (|p|² − 1 > −0.3 > z − 0.3) */
#define BOX_PAD 0.01   /* a leaf's box: its vertices' bounding box, this much larger */
#define CAP_R 0.5      /* the cap fan's centre's distance from the z axis: its box lies in the
                          sphere, so the plane's branch is decided there (|p|² − 1 < −0.4) */
/* Rounding: the cap's points lie on the plane, their closed form ~1e-17, their figures 0 or
   a few ulps; the sphere's figures are above 1e-4, this far below their bounds. */
#define SLACK 1e-12
/* The bound: the sides' sags on either side of it and of E / 2 (FAN_NEAR, FAN_FAR). */
#define E 0.002

/* The point at longitude lon, angle a from the fan centre's direction (height FAN_Z) on the
 * sphere; on the cap, a from the centre (CAP_R from the z axis) within the plane. */
static void on_fan(bool cap, double lon, double a, double rim_angle, const double off[3],
                   double p[3])
{
    double zc = FAN_Z, rc = sqrt(1 - zc * zc);
    double c[3] = {rc * cos(lon), rc * sin(lon), zc};                /* the centre */
    double e1[3] = {-sin(lon), cos(lon), 0};                         /* east */
    double e2[3] = {-zc * cos(lon), -zc * sin(lon), rc};             /* north: c × e1 */
    if (cap) {
        double cc[3] = {CAP_R * cos(lon), CAP_R * sin(lon), 0.3};
        double out[3] = {cos(lon), sin(lon), 0}; /* away from the z axis */
        for (int k = 0; k < 3; k++)
            p[k] = cc[k] + a * (cos(rim_angle) * e1[k] + sin(rim_angle) * out[k]) + off[k];
        return;
    }
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
        on_fan(k == CAP_LEAF, lon, !i ? 0 : i % 2 ? FAN_NEAR : far, 2 * M_PI * i / FAN, off,
               v.p);
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

/* The distance to the surface beside the leaf's fan: |1 − |p − off|| to the sphere,
 * |z − 0.3| to the cap. */
static double surface_dist(int leaf, const double p[3], const double off[3])
{
    if (leaf == CAP_LEAF)
        return fabs(p[2] - off[2] - 0.3);
    double r2 = 0;
    for (int k = 0; k < 3; k++)
        r2 += (p[k] - off[k]) * (p[k] - off[k]);
    return fabs(1 - sqrt(r2));
}

/* The closed form at the leaf's (span's) centroids and side midpoints: its largest, each
 * band's count (within E / 2, up to E, beyond) added to bands, and how many of them s (on
 * the leaf) evaluates on its local tape and how many on f's added to tapes. */
static double closed_form(int leaf, const ism_cell_out *out, size_t t0, size_t t1,
                          const double off[3], const ism_sampler *s, int bands[3], int tapes[2])
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
            double d = surface_dist(leaf, pts[j], off);
            worst = fmax(worst, d);
            bands[d <= E / 2 ? 0 : d <= E ? 1 : 2]++;
            tapes[ism_sampler_tape_at(s, pts[j]) == s->tape]++;
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
    ism_tape *f = pf_compile(&cut_ball), *scaled[LEAVES] = {NULL};
    for (int k = 0; k < LEAVES; k++) { /* 2^(k+1)·f: the source of leaf k's tape */
        char sexpr[300];
        snprintf(sexpr, sizeof sexpr, "%d*%s", 2 << k, expr);
        const pf_surface sf = {sexpr, NULL, 0, NULL, 0};
        cr_assert((scaled[k] = pf_compile(&sf)));
    }
    /* room for every tape here (each scaled tape's registers at least f's) */
    ism_eval_ws *ws = ism_eval_ws_new(scaled[LEAVES - 1]);
    cr_assert(f && ws && scaled[LEAVES - 1]->nregs >= f->nregs);
    ism_cell_out out;
    memset(&out, 0, sizeof out);
    ism_leaf_span span[LEAVES];
    ism_tape *local[LEAVES] = {NULL};
    for (int k = 0; k < LEAVES; k++) {
        double box[6];
        memset(&span[k], 0, sizeof span[k]);
        fan(k, off, &out, &span[k].t0, &span[k].t1, box);
        if (k == SPLIT_LEAF) /* the box ends at the fan's centre: its east half outside */
            box[3] = out.verts[out.tris[3 * span[k].t0]].p[0];
        if (k % 2 == 0 || k == CAP_LEAF) { /* their own shortened tape, decided */
            local[k] = ism_tape_new_like(scaled[k]);
            cr_assert(local[k] && ism_tape_shorten(scaled[k], ws, (ism_interval){box[0], box[3]},
                                                   (ism_interval){box[1], box[4]},
                                                   (ism_interval){box[2], box[5]}, local[k],
                                                   NULL));
            cr_assert_lt(local[k]->len, scaled[k]->len,
                         "placement %d: leaf %d's tape not shortened", placed, k);
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
        int tapes[2] = {0, 0}; /* points on the leaf's tape, on f's */
        double exact = closed_form(k, &out, span[k].t0, span[k].t1, off, &one, bands, tapes);
        cr_expect_geq(err[k], exact * (1 - 1e-9) - SLACK,
                      "placement %d leaf %d: %.17g below %.17g", placed, k, err[k], exact);
        cr_expect_leq(err[k], 2 * exact + SLACK, "placement %d leaf %d: %.17g far above %.17g",
                      placed, k, err[k], exact);
        if (k == SPLIT_LEAF)
            cr_expect(tapes[0] > 0 && tapes[1] > 0,
                      "placement %d: leaf %d's points %d on its tape, %d on f's", placed, k,
                      tapes[0], tapes[1]);
        /* the first centroid's gradient tells its tape: 2^(k+1) times f's on leaf k's own */
        const uint32_t *tri = &out.tris[3 * span[k].t0];
        double c[3], gf[3];
        for (int a = 0; a < 3; a++)
            c[a] = (out.verts[tri[0]].p[a] + out.verts[tri[1]].p[a] + out.verts[tri[2]].p[a]) / 3;
        (void)ism_eval_gradient(f, ws, c[0], c[1], c[2], gf);
        double scale = ism_sampler_tape_at(&one, c) == f ? 1 : 2 << k;
        cr_expect(local[k] && k != SPLIT_LEAF ? scale > 1 : true,
                  "placement %d leaf %d: first centroid off its tape", placed, k);
        for (int a = 0; a < 3; a++)
            cr_expect_eq(cg[k][0][a], scale * gf[a], "placement %d leaf %d: %.17g, %g × %.17g",
                         placed, k, cg[k][0][a], scale, gf[a]);
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
    for (int k = 0; k < LEAVES; k++) {
        if (local[k])
            ism_tape_free(local[k]);
        ism_tape_free(scaled[k]);
    }
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

/* Triangles with a repeated corner among others, each measured at its centroid and the sides
 * the one before lacks (refine.c's tri_points): (a, a, c) its centroid and three sides (the
 * first: 4); (a, c, d) its centroid, c–d and d–a (a–c the first's: 3); (a, a, d) its
 * centroid and a–a (a, c, d has no side a–a; a–d it has: 2); (a, a, c) its centroid, a–c and
 * c–a (a–a the one before's: 3) — 12 gradients, counted alone and together.
 * On the plane z = 0 (f = z): every figure first order and exactly 0, no second step, no
 * corner or search evaluated. The corners moved in x and y by PF_OFF_* and PF_IRR_*. */
Test(emitted_errors, repeated_corner_then_shared_side)
{
    const pf_surface plane = {"z", NULL, 0, NULL, 0};
    ism_tape *f = pf_compile(&plane);
    ism_eval_ws *ws = ism_eval_ws_new(f);
    cr_assert(f && ws);
    const double offs[3][2] = {{0, 0}, {PF_OFF_X, PF_OFF_Y}, {PF_IRR_X * 0.1, PF_IRR_Y * 0.1}};
    for (int b = 0; b < 3; b++) {
        const double corner[3][2] = {{0, 0}, {0.1, 0}, {0.05, 0.1}}; /* a, c, d */
        ism_cell_out out;
        memset(&out, 0, sizeof out);
        uint32_t idx[3];
        for (int k = 0; k < 3; k++) {
            ism_fpoint v = {{corner[k][0] + offs[b][0], corner[k][1] + offs[b][1], 0},
                            {0, 0, 1}, 0};
            cr_assert(ism_cell_out_vert(&out, &v, &idx[k]));
        }
        cr_assert(ism_cell_out_tri(&out, idx[0], idx[0], idx[1]));
        cr_assert(ism_cell_out_tri(&out, idx[0], idx[1], idx[2]));
        cr_assert(ism_cell_out_tri(&out, idx[0], idx[0], idx[2]));
        cr_assert(ism_cell_out_tri(&out, idx[0], idx[0], idx[1]));
        ism_sampler one = {.tape = f, .ws = ws, .dist_above = 1, .batch = true};
        ism_sampler all = one;
        double cg[4][3];
        cr_expect_eq(ism_emitted_error_kept(&one, &out, 0, INFINITY, cg), 0, "placement %d", b);
        cr_expect_eq(one.n_gradient, 12, "placement %d: %llu gradients alone", b,
                     (unsigned long long)one.n_gradient);
        ism_leaf_span span;
        memset(&span, 0, sizeof span);
        span.t1 = 4;
        ism_measure_scratch w;
        memset(&w, 0, sizeof w);
        cr_assert(ism_emitted_errors(&all, &out, &span, 1, &w));
        cr_expect_eq(span.err, 0, "placement %d", b);
        cr_expect_eq(all.n_gradient, 12, "placement %d: %llu gradients together", b,
                     (unsigned long long)all.n_gradient);
        cr_expect_eq(one.n_point + all.n_point, 0, "placement %d: points evaluated", b);
        ism_measure_scratch_free(&w);
        ism_cell_out_free(&out);
    }
    ism_eval_ws_free(ws);
    ism_tape_free(f);
}
