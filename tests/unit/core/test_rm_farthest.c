/* test_rm_farthest.c — the found mesh's bounds (rm_collapse_bounds, rm_collapse.c's farthest:
 * points gathered and measured a chunk at a time through rm_bound_distances, the midpoints'
 * scan stopped once it reaches max_error) against rm_distance asked of every point one at a
 * time: centroid_bound is the farthest centroid, midpoint_bound the farthest edge midpoint,
 * midpoint_low the farthest midpoint of the ISM_RM_MIDPOINT_LOW_TRIS (256) triangles with the
 * farthest centroids, each at most max_error — bit for bit. A polygonised ring torus of
 * thousands of triangles (dozens of chunks, midpoints left over past a chunk's end), without
 * a bound, with max_error above every midpoint and with it under the farthest (the cap met
 * part way); in the box on the lattice and both shifted ones (placements.h). */
#include <criterion/criterion.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "core/expr/tape.h"
#include "core/remesh/rm_bound.h"
#include "core/remesh/rm_pass.h"
#include "tests/unit/core/poly_fixture.h"

static const double BOX[6] = {-1.5, -1.5, -1.5, 1.5, 1.5, 1.5};
#define DEPTH 5
/* rm_collapse.c's ISM_RM_MIDPOINT_LOW_TRIS: the triangles midpoint_low looks at. */
#define LOW_TRIS 256

static int by_distance_down(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return x < y ? 1 : x > y ? -1 : 0;
}

static double cap_at(double far, double max_error)
{
    return fmin(far, max_error > 0 ? max_error : INFINITY);
}

/* The three figures measured one point at a time, each capped at max_error e (none at 0);
 * *low_known false where ties leave the short list's set open. */
static void expected(rm_pass *p, const ism_mesh *m, double e, double *cen, double *mid,
                     double *low, bool *low_known)
{
    size_t nt = m->ntris;
    double *cd = malloc(nt * sizeof *cd), *sorted = malloc(nt * sizeof *sorted);
    double *md = malloc(nt * sizeof *md); /* per triangle, its farthest edge midpoint */
    cr_assert(cd && sorted && md);
    double cfar = 0, mfar = 0;
    for (size_t t = 0; t < nt; t++) {
        const uint32_t *v = m->tri + 3 * t;
        double c[3], q[3];
        rm_centroid(m->pos + 3 * (size_t)v[0], m->pos + 3 * (size_t)v[1],
                    m->pos + 3 * (size_t)v[2], c);
        cd[t] = sorted[t] = rm_distance(p, c);
        cfar = fmax(cfar, cd[t]);
        md[t] = 0;
        for (int k = 0; k < 3; k++) {
            rm_midpoint(m->pos + 3 * (size_t)v[k], m->pos + 3 * (size_t)v[(k + 1) % 3], q);
            md[t] = fmax(md[t], rm_distance(p, q));
        }
        mfar = fmax(mfar, md[t]); /* (a closed mesh: every edge is some triangle's) */
    }
    qsort(sorted, nt, sizeof *sorted, by_distance_down);
    /* the short list's set is known unless the 256th and 257th centroids tie */
    *low_known = sorted[LOW_TRIS - 1] > sorted[LOW_TRIS];
    double lfar = 0;
    for (size_t t = 0; t < nt; t++)
        if (cd[t] >= sorted[LOW_TRIS - 1])
            lfar = fmax(lfar, md[t]);
    *cen = cap_at(cfar, e);
    *mid = cap_at(mfar, e);
    *low = cap_at(lfar, e);
    free(cd);
    free(sorted);
    free(md);
}

static void check(const ism_tape *t, ism_mesh *m, double e, const char *what)
{
    rm_pass p;
    ism_remesh_options o = {.f = t, .max_error = e};
    cr_assert(rm_pass_open(&p, m, &o, 0));
    p.bounded = e > 0; /* no memo: every measure afresh */
    double cen, mid, low;
    bool low_known;
    expected(&p, m, e, &cen, &mid, &low, &low_known);
    rm_collapse_bounds(&p, m->pos, m->tri, m->ntris);
    rm_collapse_bounds_need(&p);
    cr_expect(memcmp(&p.centroid_bound, &cen, sizeof cen) == 0,
              "%s: centroid_bound %.17g, one by one %.17g", what, p.centroid_bound, cen);
    cr_log_info("%s: %zu triangles, centroid_bound %.6g, midpoint_low %.6g%s, midpoint_bound "
                "%.6g", what, m->ntris, cen, low, low_known ? "" : " (tied)", mid);
    if (low_known)
        cr_expect(memcmp(&p.midpoint_low, &low, sizeof low) == 0,
                  "%s: midpoint_low %.17g, one by one %.17g", what, p.midpoint_low, low);
    rm_midpoint_within(&p, INFINITY); /* past midpoint_low: midpoint_bound measured */
    cr_assert(p.midpoint_known, "%s: midpoint_bound not measured", what);
    cr_expect(memcmp(&p.midpoint_bound, &mid, sizeof mid) == 0,
              "%s: midpoint_bound %.17g, one by one %.17g", what, p.midpoint_bound, mid);
    cr_expect_leq(p.midpoint_low, p.midpoint_bound, "%s", what);
    rm_pass_close(&p, m->nverts, m->ntris, NULL);
}

Test(rm_farthest, the_found_mesh_bounds_are_the_one_by_one_figures)
{
    ism_tape *t = pf_compile(&pf_ring_torus);
    for (int which = pf_first_box() - 1; which < 2; which++) {
        double box[6];
        ism_mesh m;
        pf_props props;
        pf_run_placed(t, BOX, DEPTH, which, box, &m, &props);
        cr_assert_gt(m.ntris, 20 * RM_DISTANCES_CHUNK, "too few triangles for many chunks");
        check(t, &m, 0, "no bound");
        /* the farthest midpoint without a bound sets the two bounded runs' max_error */
        rm_pass p;
        ism_remesh_options o = {.f = t, .max_error = 0};
        cr_assert(rm_pass_open(&p, &m, &o, 0));
        p.bounded = false;
        double cen, mid, low;
        bool known;
        expected(&p, &m, 0, &cen, &mid, &low, &known);
        rm_pass_close(&p, m.nverts, m.ntris, NULL);
        cr_assert(isfinite(mid) && mid > 0);
        check(t, &m, 4 * mid, "bound above every midpoint");
        check(t, &m, 0.5 * mid, "bound under the farthest midpoint");
        ism_mesh_free(&m);
    }
    ism_tape_free(t);
}
