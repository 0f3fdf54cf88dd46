/* test_rm_verdicts.c — verdicts of the quality pass's mendings (core/remesh) that must not
 * depend on how they were reached: a merge's distance rule (rm_distances_ok) gives the same
 * answer whether or not an earlier merge had the found mesh's farthest midpoint measured
 * (revE 1: a merge along a crease once passed only after one had), and the found mesh's
 * farthest midpoint, whose scan stops at max_error, answers as the whole scan would (revE 6).
 * On a polygonised unit sphere in the box on the lattice and both shifted ones
 * (placements.h). */
#include <criterion/criterion.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "core/remesh/rm_pass.h"
#include "tests/unit/core/poly_fixture.h"

/* The unit sphere in ±1.5 at depths 3..DEPTH. */
static const double BOX[6] = {-1.5, -1.5, -1.5, 1.5, 1.5, 1.5};
#define DEPTH 4

/* The found mesh a pass measures its bounds on: m's triangles and one sliver more, a -> b a
 * chord of the unit circle z = 0 over 0.6 rad (its midpoint 1 - cos 0.3 = 0.0447 inside) and
 * c over the chord's middle, 2 (1 - cos 0.3) outside, so that the sliver's centroid lies on
 * the sphere: the farthest midpoint of the found mesh is then not on a triangle with a far
 * centroid (the polygoniser's meshes have it there: midpoint_low = midpoint_bound), and a
 * midpoint between the two tells measured from unmeasured. */
typedef struct found {
    double *pos;
    uint32_t *tri;
    size_t ntris;
} found;

static void found_with_sliver(const ism_mesh *m, found *f, bool reversed)
{
    size_t nv = m->nverts;
    double h = 1 - cos(0.3), c = 1 + 2 * h;
    double add[9] = {1, 0, 0, cos(0.6), sin(0.6), 0, c * cos(0.3), c * sin(0.3), 0};
    f->pos = malloc((nv + 3) * 3 * sizeof *f->pos);
    f->tri = malloc((m->ntris + 1) * 3 * sizeof *f->tri);
    cr_assert(f->pos && f->tri);
    memcpy(f->pos, m->pos, nv * 3 * sizeof *f->pos);
    memcpy(f->pos + 3 * nv, add, sizeof add);
    memcpy(f->tri, m->tri, m->ntris * 3 * sizeof *f->tri);
    /* reversed: a -> c -> b, the chord b -> a its larger index first (an open mesh's
       boundary edge that a scan of the edges running up from the smaller index misses) */
    for (int k = 0; k < 3; k++)
        f->tri[3 * m->ntris + k] = (uint32_t)(nv + (reversed ? (3 - k) % 3 : k));
    f->ntris = m->ntris + 1;
}

/* The unit sphere t polygonised on one thread at depths 3..DEPTH in sweep box `which`
 * (pf_sweep_box: -1 the box as given, 0 moved by 1e-3, 1 by an irrational fraction of a
 * cell), into m. */
static void sphere_in_box(const ism_tape *t, int which, ism_mesh *m)
{
    double box[6];
    ism_poly_stats st;
    pf_sweep_box(BOX, DEPTH, which, box);
    pf_run(t, box, 3, DEPTH, 1, m, &st);
}

/* A pass over m under the bound e (0: none) with its bounds measured on fd. */
static void open_pass(rm_pass *p, ism_mesh *m, const ism_tape *t, double e, const found *fd)
{
    ism_remesh_options o = {.f = t, .max_error = e};
    cr_assert(rm_pass_open(p, m, &o, 0));
    p->bounded = e > 0;
    rm_collapse_bounds(p, fd->pos, fd->tri, fd->ntris);
}

static void close_pass(rm_pass *p, ism_mesh *m)
{
    rm_pass_close(p, m->nverts, m->ntris, NULL);
}

Test(rm_verdicts, merge_distances_do_not_depend_on_what_was_asked_before)
{
    ism_tape *t = pf_compile(&pf_unit_sphere);
    for (int which = pf_first_box() - 1; which < 2; which++) {
        ism_mesh m;
        sphere_in_box(t, which, &m);
        found fd;
        found_with_sliver(&m, &fd, false);
        /* b has the found mesh's farthest midpoint measured (as an earlier merge off the
           creases would have it), a not */
        rm_pass a, b;
        open_pass(&a, &m, t, 1, &fd);
        open_pass(&b, &m, t, 1, &fd);
        rm_collapse_bounds_need(&a);
        (void)rm_midpoint_within(&b, INFINITY); /* past midpoint_low: measures the mesh */
        cr_assert(b.midpoint_known);
        double low = b.midpoint_low, bound = b.midpoint_bound;
        /* the farthest midpoint is the sliver's chord's, 1 - cos 0.3 inside the sphere (the
           mesh's own, at depth 4, are under a tenth of it); rm_midpoint_distance's measure
           is never below the distance and off it at second order: for f = r² - 1 the first
           step |f|/|∇f| = d (2 - d) / (2 (1 - d)) = d + d²/2 + ..., its landing's as much
           again, so within d² + O(d³) — 2 d² here (revE 6: not the code's own figure) */
        double h = 1 - cos(0.3);
        cr_assert(bound >= h && bound <= h + 2 * h * h,
                  "box %d: the farthest midpoint %.17g, not the chord's %.17g", which, bound, h);
        /* a midpoint beyond the farthest of the triangles with the farthest centroids but
           within the mesh's: where the old rule along a crease said no until measured */
        cr_assert_lt(low, bound, "box %d: no room between %g and %g", which, low, bound);
        double probe[] = {0.5 * low, 0.5 * (low + bound), bound, 1.5 * bound};
        bool want[] = {true, true, true, false};
        for (int i = 0; i < 4; i++) {
            /* a's first ask is the middle one: nothing measured the midpoints before */
            int k = i == 0 ? 1 : i == 1 ? 0 : i;
            bool va = rm_distances_ok(&a, 0, probe[k], 0, 0);
            bool vb = rm_distances_ok(&b, 0, probe[k], 0, 0);
            cr_assert_eq(va, vb, "box %d, midpoint %g: %d unmeasured, %d measured", which,
                         probe[k], va, vb);
            cr_assert_eq(va, want[k], "box %d, midpoint %g against %g", which, probe[k], bound);
        }
        close_pass(&a, &m);
        close_pass(&b, &m);
        free(fd.pos);
        free(fd.tri);
        ism_mesh_free(&m);
    }
    ism_tape_free(t);
}

/* The farthest edge midpoint of the found mesh from f = 0 as pass p measures it, over every
 * edge (no stop). */
static double farthest_midpoint(rm_pass *p, const found *fd)
{
    double far = 0;
    for (size_t t = 0; t < fd->ntris; t++)
        for (int k = 0; k < 3; k++) {
            const uint32_t *v = fd->tri + 3 * t;
            far = fmax(far, rm_midpoint_distance(p, fd->pos + 3 * (size_t)v[k],
                                                 fd->pos + 3 * (size_t)v[(k + 1) % 3]));
        }
    return far;
}

/* The found mesh's farthest midpoint is measured with its scan stopped once a midpoint
 * reaches max_error (rm_collapse.c's farthest: nothing past it can change the figure, which
 * is capped at max_error): under bounds E below, at and above the farthest midpoint, the
 * figure is the whole scan's (farthest_midpoint, with the pass's own measure) capped at E,
 * and every verdict of rm_midpoint_within is the one that figure gives; on the closed mesh
 * and on open ones, whose boundary edges run either way (revE 2). */
Test(rm_verdicts, the_midpoint_scan_stopped_at_the_bound_keeps_every_verdict)
{
    ism_tape *t = pf_compile(&pf_unit_sphere);
    for (int which = pf_first_box() - 1; which < 2; which++) {
        ism_mesh m;
        sphere_in_box(t, which, &m);
        /* as polygonised, and with the sliver last: its midpoint the farthest, after all;
           and the sliver reversed (its chord an open mesh's boundary edge b -> a, b > a) */
        found as_is = {m.pos, m.tri, m.ntris}, sliver, reversed;
        found_with_sliver(&m, &sliver, false);
        found_with_sliver(&m, &reversed, true);
        for (int i = 0; i < 15; i++) {
            const found *fd = i < 5 ? &as_is : i < 10 ? &sliver : &reversed;
            rm_pass whole;
            open_pass(&whole, &m, t, 1e3, fd); /* no midpoint here is 1e3 off */
            double far0 = farthest_midpoint(&whole, fd);
            cr_assert_gt(far0, 0);
            close_pass(&whole, &m);
            static const double scale[] = {0.3, 0.999, 1, 1.001, 3};
            double e = scale[i % 5] * far0;
            rm_pass a;
            open_pass(&a, &m, t, e, fd);
            double want = fmin(farthest_midpoint(&a, fd), e);
            double probe[] = {0.5 * want, nextafter(want, 0), want, nextafter(want, INFINITY),
                              2 * want};
            for (int k = 0; k < 5; k++)
                cr_assert_eq(rm_midpoint_within(&a, probe[k]), probe[k] <= want,
                             "box %d, E %g x the farthest: midpoint %.17g against %.17g", which,
                             scale[i % 5], probe[k], want);
            cr_assert(a.midpoint_known);
            cr_assert_eq(a.midpoint_bound, want, "box %d, E %g x the farthest: %.17g, not %.17g",
                         which, scale[i % 5], a.midpoint_bound, want);
            close_pass(&a, &m);
        }
        free(sliver.pos);
        free(sliver.tri);
        free(reversed.pos);
        free(reversed.tri);
        ism_mesh_free(&m);
    }
    ism_tape_free(t);
}
