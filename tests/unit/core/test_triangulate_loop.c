/* test_triangulate_loop.c — ism_triangulate_loop (triangulate.c) on polygons round a cap of
 * the unit sphere: loops of more than UNIT_STACK = 32 points (its per-polygon tables on the
 * heap) against ism_triangulate_wound, which works out its unit gradients itself, bit for
 * bit, with the triangle counts of a centre fan (n) and a corner fan (n − 2) and every
 * triangle facing out; and the corner fan's error bound at the bound measured by the scalar
 * path (ism_sample_dist_between at the fan's centroids and diagonals' middles, one point at
 * a time): accepted at that bound, refused one ulp below, for loops of 11 to 40 corners
 * whose fans take two or more batches (corner_fan_error: 2n − 5 points, FAN_POINTS at a
 * time); and the corner the fan starts from, against every corner's fan measured in full here
 * (its triangles' smallest angles by acos). The node in its own box and moved off the lattice
 * (pf_sweep_box), the sphere and the loops' points moved with it (placed_sphere), so that
 * every placement rounds its own positions, gradients and angles. */
#include <criterion/criterion.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "core/octree/sample_dist.h"
#include "core/octree/triangulate.h"
#include "core/util/vec3.h"
#include "poly_fixture.h"

static const double base[6] = {-1.5, -1.5, -1.5, 1.5, 1.5, 1.5};

/* The node box of placement which (pf_sweep_box of base at depth 5) into node, its move off
 * base into centre, and a sampler *s of the unit sphere about centre: the sphere moves with
 * the box (the caller frees s->ws and the tape returned). */
static ism_tape *placed_sphere(int which, double node[6], double centre[3], ism_sampler *s)
{
    pf_sweep_box(base, 5, which, node);
    for (int k = 0; k < 3; k++)
        centre[k] = node[k] - base[k];
    const ism_param prm[] = {{"a", centre[0]}, {"b", centre[1]}, {"c", centre[2]}};
    const pf_surface sphere = {"(x - a)^2 + (y - b)^2 + (z - c)^2 - 1", prm, 3, NULL, 0};
    return pf_build_sampler(&sphere, s);
}

static void sphere_free(ism_sampler *s, ism_tape *tape)
{
    ism_eval_ws_free(s->ws);
    ism_tape_free(tape);
}

/* The point of the unit sphere about o at angle t round the circle of height z (its
   radius r), and g = ∇f there. */
static ism_fpoint on_sphere(ism_sampler *s, const double o[3], double r, double t, double z)
{
    ism_fpoint v = {{o[0] + r * cos(t), o[1] + r * sin(t), o[2] + z}, {0, 0, 0}, 0};
    ism_sample_grad(s, v.p, v.g);
    return v;
}

/* n points round the circle z = z0 of the unit sphere about o, counterclockwise seen from +z
 * (the way ∇f points), their angles jittered by seed; g = ∇f there. */
static void cap_loop(ism_sampler *s, const double o[3], size_t n, double z0, int seed,
                     ism_fpoint *p)
{
    double r = sqrt(1 - z0 * z0), step = 2 * M_PI / (double)n;
    for (size_t i = 0; i < n; i++) {
        double t = step * ((double)i + 0.3 * sin(1.7 * (double)(i + 1) * (seed + 1)));
        p[i] = on_sphere(s, o, r, t, z0);
    }
}

static void reverse(ism_fpoint *p, size_t n)
{
    for (size_t i = 0; i < n / 2; i++) {
        ism_fpoint t = p[i];
        p[i] = p[n - 1 - i], p[n - 1 - i] = t;
    }
}

/* Every triangle of o faces out of the sphere about c (its normal toward its centroid). */
static void all_face_out(const ism_cell_out *o, const double c[3], const char *what)
{
    for (size_t t = 0; t < o->ntris; t++) {
        const double *a = o->verts[o->tris[3 * t]].p, *b = o->verts[o->tris[3 * t + 1]].p,
                     *e = o->verts[o->tris[3 * t + 2]].p;
        double e1[3], e2[3], nrm[3], m[3];
        for (int k = 0; k < 3; k++)
            e1[k] = b[k] - a[k], e2[k] = e[k] - a[k], m[k] = a[k] + b[k] + e[k] - 3 * c[k];
        ism_cross3(e1, e2, nrm);
        cr_assert(ism_dot3(nrm, m) > 0, "%s: triangle %zu turned over", what, t);
    }
}

static void same_out(const ism_cell_out *a, const ism_cell_out *b, const char *what)
{
    cr_assert_eq(a->nverts, b->nverts, "%s: vertices", what);
    cr_assert_eq(a->ntris, b->ntris, "%s: triangles", what);
    for (size_t i = 0; i < a->nverts; i++) /* field by field: the centre's padding is not set */
        cr_assert(!memcmp(a->verts[i].p, b->verts[i].p, sizeof a->verts[i].p) &&
                      !memcmp(a->verts[i].g, b->verts[i].g, sizeof a->verts[i].g) &&
                      a->verts[i].flags == b->verts[i].flags,
                  "%s: point %zu", what, i);
    cr_assert(!memcmp(a->tris, b->tris, 3 * a->ntris * sizeof *a->tris), "%s: indices", what);
}

static void out_free(ism_cell_out *o)
{
    free(o->verts);
    free(o->tris);
    free(o->segs);
    *o = (ism_cell_out){0};
}

Test(triangulate_loop, loops_past_the_stack_as_wound)
{
    enum { N = 40 };
    ism_fpoint p[N];
    for (int which = -1; which <= 1; which++) {
        ism_sampler s;
        double node[6], o[3];
        ism_tape *tape = placed_sphere(which, node, o, &s);
        for (int turned = 0; turned < 2; turned++)
            for (int corner = 0; corner < 2; corner++) {
                cap_loop(&s, o, N, 0.6, which + 1, p);
                if (turned)
                    reverse(p, N);
                double bound = corner ? 1.0 : 0; /* 1: any corner fan passes; 0: the centre */
                ism_cell_out a = {0}, b = {0};
                cr_assert(ism_triangulate_loop(&s, p, N, 1.0, node, bound, &a));
                bool flip = ism_loop_reversed(&s, node, p, N);
                cr_assert_eq(flip, (bool)turned);
                cr_assert(ism_triangulate_wound(&s, p, N, 1.0, node, bound, flip, &b));
                char what[64];
                snprintf(what, sizeof what, "box %d turned %d corner %d", which, turned, corner);
                cr_assert_eq(a.ntris, corner ? N - 2 : N, "%s: %zu triangles", what, a.ntris);
                cr_assert_eq(a.nverts, corner ? N : N + 1, "%s", what);
                if (!corner) /* the centre, projected onto the sphere */
                    cr_assert_float_eq(ism_dist3(a.verts[N].p, o), 1, 1e-9, "%s", what);
                all_face_out(&a, o, what);
                same_out(&a, &b, what);
                out_free(&a);
                out_free(&b);
            }
        sphere_free(&s, tape);
    }
}

/* The largest ism_sample_dist_between over the fan of the emitted polygon q[0..n) from
 * corner c (its centroids, then its diagonals' middles, in the fan's order), and the index
 * of the point that gave it in that order. */
static double scalar_fan_error(ism_sampler *s, const ism_fpoint *q, size_t n, size_t c,
                               size_t *at)
{
    double worst = 0;
    size_t k = 0;
    const double *a = q[c].p;
    for (size_t i = 1; i + 1 < n; i++) {
        const double *b = q[(c + i) % n].p, *e = q[(c + i + 1) % n].p;
        double m[3];
        for (int j = 0; j < 3; j++)
            m[j] = (a[j] + b[j] + e[j]) / 3;
        double d = ism_sample_dist_between(s, m, (const double *[3]){a, b, e}, 3);
        if (d > worst)
            worst = d, *at = k;
        k++;
        if (i + 2 < n) {
            for (int j = 0; j < 3; j++)
                m[j] = 0.5 * (a[j] + e[j]);
            d = ism_sample_dist_between(s, m, (const double *[2]){a, e}, 2);
            if (d > worst)
                worst = d, *at = k;
            k++;
        }
    }
    return worst;
}

Test(triangulate_loop, corner_fan_bound_over_batches)
{
    const size_t sizes[] = {11, 12, 13, 14, 40};
    ism_fpoint p[40];
    size_t later_batch = 0, cases = 0;
    for (int which = -1; which <= 1; which++) {
        ism_sampler s;
        double node[6], o[3];
        ism_tape *tape = placed_sphere(which, node, o, &s);
        for (size_t z = 0; z < sizeof sizes / sizeof *sizes; z++)
            for (int seed = 0; seed < 6; seed++) {
                size_t n = sizes[z];
                cap_loop(&s, o, n, 0.8 - 0.05 * seed, seed, p);
                char what[64];
                snprintf(what, sizeof what, "box %d n %zu seed %d", which, n, seed);
                /* the fan's corner: best_corner's, whatever the bound */
                ism_cell_out loose = {0}, at = {0}, below = {0};
                cr_assert(ism_triangulate_loop(&s, p, n, 1.0, node, 1.0, &loose));
                cr_assert_eq(loose.ntris, n - 2, "%s", what);
                size_t c = loose.tris[0], worst_at = 0;
                for (size_t t = 0; t < loose.ntris; t++)
                    cr_assert_eq(loose.tris[3 * t], c, "%s: a fan from one corner", what);
                double e = scalar_fan_error(&s, loose.verts, n, c, &worst_at);
                cr_assert(e > 0 && e < 1, "%s: %g", what, e);
                later_batch += worst_at >= ISM_GRAD_UNROLLED;
                cases++;
                /* within the bound at e: the same fan; one ulp under: the centre's */
                cr_assert(ism_triangulate_loop(&s, p, n, 1.0, node, e, &at));
                same_out(&loose, &at, what);
                cr_assert(ism_triangulate_loop(&s, p, n, 1.0, node, nextafter(e, 0), &below));
                cr_assert_eq(below.ntris, n, "%s: refused at %.17g, %zu triangles", what,
                             nextafter(e, 0), below.ntris);
                cr_assert_eq(below.nverts, n + 1, "%s", what);
                all_face_out(&loose, o, what);
                all_face_out(&below, o, what);
                out_free(&loose);
                out_free(&at);
                out_free(&below);
            }
        sphere_free(&s, tape);
    }
    /* the test reaches the second batch's reads: some fans are worst there */
    cr_assert(later_batch > 0 && later_batch < cases, "%zu of %zu", later_batch, cases);
}

/* The smallest angle of triangle a, b, c in radians (acos of each corner's cosine: another
 * way than triangulate.c's largest cosine). */
static double smallest_angle(const double *a, const double *b, const double *c)
{
    const double *v[3] = {a, b, c};
    double least = M_PI;
    for (int k = 0; k < 3; k++) {
        const double *o = v[k], *u = v[(k + 1) % 3], *w = v[(k + 2) % 3];
        double du[3], dw[3];
        for (int j = 0; j < 3; j++)
            du[j] = u[j] - o[j], dw[j] = w[j] - o[j];
        double cosv = ism_dot3(du, dw) / (ism_norm3(du) * ism_norm3(dw));
        least = fmin(least, acos(fmax(-1, fmin(1, cosv))));
    }
    return least;
}

/* Does triangle a, b, e of points on the unit sphere about c face inward (its normal against
 * the sum of its corners' moves off c, which are the unit gradients there)? */
static bool turned_on_sphere(const double *a, const double *b, const double *e,
                             const double c[3])
{
    double e1[3], e2[3], nrm[3], m[3];
    for (int k = 0; k < 3; k++)
        e1[k] = b[k] - a[k], e2[k] = e[k] - a[k], m[k] = a[k] + b[k] + e[k] - 3 * c[k];
    ism_cross3(e1, e2, nrm);
    return ism_dot3(nrm, m) < 0;
}

/* The corner whose fan's worst triangle (smallest angle) is best, every fan measured in full,
 * the first of equals: two fans share an ear (q[j - 1], q[j], q[j + 1] ends the fans from
 * q[j + 1] and q[j - 1]), which measures the same in both, so fans whose worst is that ear
 * tie (within 1e-12 here, where acos meets the corners in another order). *margin: how much
 * worse the best fan outside the tie is (near-ties of different triangles are not asked). A
 * fan with a triangle turned over is worse than any without (triangulate.c's fan_folds);
 * the points are on the unit sphere about centre. */
static size_t best_fan_by_hand(const ism_fpoint *q, size_t n, const double centre[3],
                               double *margin)
{
    double worst[16], best_a = -100, second = -100;
    for (size_t c = 0; c < n; c++) {
        worst[c] = M_PI;
        bool folds = false;
        for (size_t i = 1; i + 1 < n; i++) {
            const double *a = q[c].p, *b = q[(c + i) % n].p, *e = q[(c + i + 1) % n].p;
            worst[c] = fmin(worst[c], smallest_angle(a, b, e));
            folds = folds || turned_on_sphere(a, b, e, centre);
        }
        worst[c] -= folds ? 10 : 0; /* a fan turning a triangle over only when all do */
        best_a = fmax(best_a, worst[c]);
    }
    size_t best = n;
    for (size_t c = 0; c < n; c++)
        if (worst[c] >= best_a - 1e-12)
            best = best < c ? best : c;
        else
            second = fmax(second, worst[c]);
    *margin = best_a - second;
    return best;
}

Test(triangulate_loop, corner_fan_from_the_best_corner)
{
    ism_fpoint p[16];
    size_t cases = 0, not_ear_only = 0;
    for (int which = -1; which <= 1; which++) {
        ism_sampler s;
        double node[6], ctr[3];
        ism_tape *tape = placed_sphere(which, node, ctr, &s);
        for (size_t n = 5; n <= 16; n++)
            for (int seed = 0; seed < 12; seed++) {
                /* jittered angles and heights on the sphere (points on one circle would
                   see every chord under one angle: all fans alike) */
                double step = 2 * M_PI / (double)n;
                for (size_t i = 0; i < n; i++) {
                    double t = step * ((double)i + 0.45 * sin(2.3 * (double)(i + 1) * (seed + 1) +
                                                              0.7 * (double)n));
                    double z = 0.6 + 0.08 * cos(1.9 * (double)(i + 2) * (seed + 1));
                    p[i] = on_sphere(&s, ctr, sqrt(1 - z * z), t, z);
                }
                double margin;
                size_t want = best_fan_by_hand(p, n, ctr, &margin);
                if (!(margin > 1e-9))
                    continue;
                ism_cell_out o = {0};
                cr_assert(ism_triangulate_loop(&s, p, n, 1.0, node, 1.0, &o));
                if (o.ntris != n - 2) { /* the corner fan measured beyond 1 or in a face */
                    out_free(&o);
                    continue;
                }
                cr_assert_eq(o.tris[0], (uint32_t)want, "box %d n %zu seed %d: fan from %u, "
                             "by hand %zu", which, n, seed, o.tris[0], want);
                /* the winner's worst triangle is not one of its two ears */
                double ears = fmin(smallest_angle(p[want].p, p[(want + 1) % n].p,
                                                  p[(want + 2) % n].p),
                                   smallest_angle(p[want].p, p[(want + n - 2) % n].p,
                                                  p[(want + n - 1) % n].p));
                double all = M_PI;
                for (size_t i = 1; i + 1 < n; i++)
                    all = fmin(all, smallest_angle(p[want].p, p[(want + i) % n].p,
                                                   p[(want + i + 1) % n].p));
                not_ear_only += all < ears;
                cases++;
                out_free(&o);
            }
        sphere_free(&s, tape);
    }
    cr_assert(cases > 200, "%zu cases", cases);
    cr_assert(not_ear_only > 0, "no winner's fan is worst inside (%zu cases)", cases);
}
