/* test_thin_probe_lanes.c — ism_thin_probe runs its Newton probes (the box's, then its
 * octants' where their interval leaves the other sign possible) side by side where f has a
 * min or max (one by one elsewhere), and must answer as probing them one by one in that
 * order does: the first to reach the other sign gives the point. The reference is
 * ism_thin_probe_one over the box and then each octant in index order (an octant whose
 * interval keeps the corners' sign cannot be hit: a probe stays in its box, so the reference
 * probes it too). Verdict and point compared bit for bit over lattice
 * cells in the three placements (pf_sweep_box) of small balls, as the min of their
 * functions (side by side), two as their product (smooth: one by one), and of Barth's
 * sextic in its ball (a max: side by side, many probes).
 * Each cell's lower x-, y- and z-face (lo == hi on that axis: the octree probes faces too)
 * is compared the same way (the reference then probes twin quadrants twice, which changes
 * nothing in "the first in order").
 * Not vacuous: probes hit, in faces too, octants hit where the box's own probe missed, and in
 * some boxes a later octant's probe hits in fewer steps than the first one to hit in order (so
 * an answer taken from whichever lane hits first in time would differ).
 * Both sides share one probe (probe_start, probe_take), so two tests of their own guard it:
 * a face's probe moves in the face's plane (face_probe_in_plane), and the clamp to the box
 * keeps a zero inside the box as the fmin(fmax()) it replaced did
 * (clamp_signed_zero_as_fmin_fmax). */
#include <criterion/criterion.h>
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "core/octree/thin_search.h"
#include "tests/unit/core/poly_fixture.h"

typedef struct tally {
    int boxes, hits, face_hits, octant_hits, out_of_order;
} tally;

/* The one-by-one answer for the box lo..hi: the index of the first probe to hit (0: the
 * box's, 1 + c: octant c's; -1: none) with its point; *later_sooner: some later probe hits
 * in fewer gradients than that first one. */
static int one_by_one(ism_sampler *s, const double lo[3], const double hi[3], int sign,
                      double found[3], bool *later_sooner)
{
    int first = -1;
    uint64_t first_cost = 0;
    *later_sooner = false;
    for (int i = 0; i < 9; i++) {
        double a[3], b[3], at[3];
        for (int k = 0; k < 3; k++) {
            double m = 0.5 * lo[k] + 0.5 * hi[k];
            bool up = i > 0 && ((i - 1) >> k) & 1;
            a[k] = i == 0 || !up ? lo[k] : m;
            b[k] = i == 0 || up ? hi[k] : m;
        }
        uint64_t before = s->n_gradient;
        bool hit = ism_thin_probe_one(s, a, b, sign, at);
        uint64_t cost = s->n_gradient - before;
        if (hit && first < 0) {
            first = i;
            first_cost = cost;
            memcpy(found, at, sizeof at);
        } else if (hit && cost < first_cost)
            *later_sooner = true;
    }
    return first;
}

/* ism_thin_probe on the box lo..hi (face: the axis it is flat along, -1 none) against the
 * one-by-one reference, the corners' sign taken at lo. */
static void compare_box(ism_sampler *s, const double lo[3], const double hi[3], int which,
                        int c, int face, tally *t)
{
    double g[3];
    double f0 = ism_sample_grad(s, lo, g);
    int sign = f0 < 0 ? -1 : 1;
    double want[3] = { 0 }, got[3] = { 0 };
    bool later_sooner;
    int first = one_by_one(s, lo, hi, sign, want, &later_sooner);
    enum ism_thin_verdict v = ism_thin_probe(s, lo, hi, sign, got);
    t->boxes++;
    cr_assert_eq(v != ISM_THIN_UNDECIDED, first >= 0,
                 "placement %d cell %d face %d: verdict %d, one by one %d", which, c, face,
                 (int)v, first);
    if (first < 0)
        return;
    cr_assert(!memcmp(want, got, sizeof want),
              "placement %d cell %d face %d: found (%.17g %.17g %.17g), one by one probe %d "
              "(%.17g %.17g %.17g)",
              which, c, face, got[0], got[1], got[2], first, want[0], want[1], want[2]);
    t->hits++;
    t->face_hits += face >= 0;
    t->octant_hits += first > 0;
    t->out_of_order += later_sooner;
}

/* Every cell of depth d of the box base placed by which (pf_sweep_box), and its lower x-, y-
 * and z-face. */
static void compare_cells(ism_sampler *s, const double base[6], int d, int which, tally *t)
{
    double box[6];
    pf_sweep_box(base, d, which, box);
    int n = 1 << d;
    for (int c = 0; c < n * n * n; c++) {
        double lo[3], hi[3];
        for (int k = 0; k < 3; k++) {
            int i = (c >> (d * k)) & (n - 1);
            double step = (box[k + 3] - box[k]) / n;
            lo[k] = box[k] + step * i;
            hi[k] = i == n - 1 ? box[k + 3] : box[k] + step * (i + 1);
        }
        compare_box(s, lo, hi, which, c, -1, t);
        for (int k = 0; k < 3; k++) {
            double face_hi[3] = { hi[0], hi[1], hi[2] };
            face_hi[k] = lo[k];
            compare_box(s, lo, face_hi, which, c, k, t);
        }
    }
}

static void sweep(const pf_surface *surf, const double base[6], int d, const char *name)
{
    ism_sampler s;
    ism_tape *tape = pf_build_sampler(surf, &s);
    cr_assert_not_null(tape);
    tally t = { 0 };
    /* all three placements even in the quick runs (ISOMESH_TEST_QUICK, the sanitizer lane:
       pf_first_box): the counts asserted below are over the three together (two balls has
       no octant hit in the irrational placement alone), and a sweep takes a few ms */
    for (int which = -1; which < 2; which++)
        compare_cells(&s, base, d, which, &t);
    cr_log_info("%s: %d boxes, %d hits (%d in faces), %d by an octant, %d out of order", name,
                t.boxes, t.hits, t.face_hits, t.octant_hits, t.out_of_order);
    cr_expect_gt(t.hits, 0, "%s: no probe hit", name);
    cr_expect_gt(t.face_hits, 0, "%s: no probe hit in a face", name);
    cr_expect_gt(t.octant_hits, 0, "%s: no octant hit where the box's probe missed", name);
    cr_expect_gt(t.out_of_order, 0, "%s: the first hit in time always the first in order",
                 name);
    ism_eval_ws_free(s.ws);
    ism_tape_free(tape);
}

Test(thin_probe_lanes, min_of_small_balls_as_one_by_one)
{
    pf_surface s = { "min(min(min((x - 0.3)^2 + (y + 0.2)^2 + (z - 0.1)^2 - 0.0025,"
                     " (x + 0.35)^2 + (y - 0.3)^2 + (z + 0.25)^2 - 0.0016),"
                     " min((x - 0.45)^2 + (y - 0.05)^2 + (z - 0.4)^2 - 0.0036,"
                     " (x + 0.05)^2 + (y + 0.45)^2 + (z - 0.55)^2 - 0.0025)),"
                     " min((x - 0.6)^2 + (y - 0.55)^2 + (z + 0.45)^2 - 0.0016,"
                     " (x + 0.55)^2 + (y + 0.6)^2 + (z + 0.05)^2 - 0.0036))",
                     NULL, 0, NULL, 0 };
    const double base[6] = { -1, -1, -1, 1, 1, 1 };
    sweep(&s, base, 2, "min of small balls");
}

Test(thin_probe_lanes, two_balls_as_one_by_one)
{
    pf_surface s = { "((x - 0.3)^2 + (y + 0.2)^2 + (z - 0.1)^2 - 0.04)"
                     " * ((x + 0.35)^2 + (y - 0.3)^2 + (z + 0.25)^2 - 0.0225)",
                     NULL, 0, NULL, 0 };
    const double base[6] = { -1, -1, -1, 1, 1, 1 };
    sweep(&s, base, 2, "two balls");
}

Test(thin_probe_lanes, barth_as_one_by_one)
{
    const double base[6] = { -1.6, -1.6, -1.6, 1.6, 1.6, 1.6 };
    sweep(&pf_barth_sextic, base, 3, "barth-sextic");
}

/* A face's probe moves in the face's plane (its gradient's normal part left out): the face
 * N = n0 (N each axis in turn: the lower face of the box [-1, 1]^3 in the three placements)
 * of f = (U - 0.3)^2 + (V + 0.2)^2 - 0.01 + 100 (N - n0) holds a disk of f < 0, radius 0.1,
 * about 0.36 from the face's centre; its corners have f > 0. In-plane Newton 1.5 steps past
 * f = 0 reach a distance d from the disk's centre of d/4 + 0.75 r^2/d: within the disk in two
 * or three steps (d <= 0.5). With the normal part kept, |grad f|^2 >= 10^4 and each step moves
 * < 1e-4 in the plane: the probe misses. */
Test(thin_probe_lanes, face_probe_in_plane)
{
    static const char axis[3] = { 'x', 'y', 'z' };
    const double base[6] = { -1, -1, -1, 1, 1, 1 };
    for (int which = pf_first_box() - 1; which < 2; which++)
        for (int k = 0; k < 3; k++) {
            double box[6];
            pf_sweep_box(base, 3, which, box);
            int u = (k + 1) % 3, v = (k + 2) % 3;
            double n0 = box[k];
            char expr[160];
            snprintf(expr, sizeof expr, "(%c - 0.3)^2 + (%c + 0.2)^2 - 0.01 + 100 * (%c - %.17g)",
                     axis[u], axis[v], axis[k], n0);
            pf_surface surf = { expr, NULL, 0, NULL, 0 };
            ism_sampler s;
            ism_tape *tape = pf_build_sampler(&surf, &s);
            double lo[3] = { box[0], box[1], box[2] }, hi[3] = { box[3], box[4], box[5] };
            hi[k] = n0;
            double at[3], got[3];
            cr_assert(ism_thin_probe_one(&s, lo, hi, 1, at),
                      "placement %d face %c = %.17g: the probe missed the disk", which,
                      axis[k], n0);
            double du = at[u] - 0.3, dv = at[v] + 0.2;
            cr_assert(at[k] == n0 && du * du + dv * dv < 0.01,
                      "placement %d face %c: found (%.17g %.17g %.17g) off the disk", which,
                      axis[k], at[0], at[1], at[2]);
            cr_assert_eq(ism_thin_probe(&s, lo, hi, 1, got), ISM_THIN_FOUND);
            cr_assert(!memcmp(at, got, sizeof at));
            ism_eval_ws_free(s.ws);
            ism_tape_free(tape);
        }
}

/* probe_take's clamp to the box gives back a v inside the closed box bit for bit, a zero of
 * the other sign than the bound it equals included, as the library calls it replaced did
 * (fmin(fmax(v, lo), hi), which GCC 12 emitted as fmin(hi, fmax(lo, v)); glibc's x86-64 fmax
 * and fmin give the second operand when equal). A Newton step of f = x - 0.25 from the centre
 * 0.75 of x in [-0.0, 1.5] lands on 0.75 - 0.75 = +0, equal to the bound -0.0; one of
 * f = 0 - x - 0.25 from -0.75 in [-1.5, -0.0] lands on -0.75 + 0.75 = +0 against the bound
 * -0.0; both hit (f = -0.25 there). The found x must be +0, and the library's
 * fmin(hi, fmax(lo, v)) taken here through volatile pointers (no folding, no reordering).
 * Exact zeros only occur at these bounds, so the box is not moved off the lattice. */
Test(thin_probe_lanes, clamp_signed_zero_as_fmin_fmax)
{
#if !defined(__x86_64__) || !defined(__GLIBC__)
    cr_skip_test("the old calls' sign of zero was glibc x86-64's");
#endif
    double (*volatile lib_fmax)(double, double) = fmax;
    double (*volatile lib_fmin)(double, double) = fmin;
    static const struct {
        const char *expr;
        double lo, hi, step_to;
    } c[2] = {
        { "x - 0.25", -0.0, 1.5, 0.75 - 0.75 },
        { "0 - x - 0.25", -1.5, -0.0, -0.75 + 0.75 },
    };
    for (int i = 0; i < 2; i++) {
        pf_surface surf = { c[i].expr, NULL, 0, NULL, 0 };
        ism_sampler s;
        ism_tape *tape = pf_build_sampler(&surf, &s);
        double lo[3] = { c[i].lo, -1, -1 }, hi[3] = { c[i].hi, 1, 1 }, at[3];
        cr_assert(ism_thin_probe_one(&s, lo, hi, 1, at), "%s: the probe missed", c[i].expr);
        double old = lib_fmin(c[i].hi, lib_fmax(c[i].lo, c[i].step_to));
        cr_assert(at[0] == 0 && !signbit(at[0]) && !signbit(old),
                  "%s: found x %g (sign %d), the old calls %g (sign %d)", c[i].expr, at[0],
                  !!signbit(at[0]), old, !!signbit(old));
        ism_eval_ws_free(s.ws);
        ism_tape_free(tape);
    }
}

/* A Newton step whose t = 1.5 f / |g|^2 overflows clamps as the fmax(lo, v) it replaced did:
 * f = 1e-160 x + 1 - 2 y y from the centre 0 of [-1, 1]^3 has f = 1 and g = (1e-160, 0, 0),
 * |g|^2 = 1e-320 (a subnormal, > 0), so t = inf: x goes to -inf and onto -1, y and z get
 * 0 - inf * 0 = NaN, which fmax(lo, NaN) took as lo. The point (-1, -1, -1) has f = -1: the
 * probe hits there. A NaN kept makes the step's move NaN and the probe miss. g must be 0 on
 * an axis exactly, at the centre of a box round 0, so the box is not moved off the lattice. */
Test(thin_probe_lanes, overflowed_step_clamps_nan_to_lo)
{
    pf_surface surf = { "1e-160 * x + 1 - 2 * y * y", NULL, 0, NULL, 0 };
    ism_sampler s;
    ism_tape *tape = pf_build_sampler(&surf, &s);
    const double lo[3] = { -1, -1, -1 }, hi[3] = { 1, 1, 1 };
    double at[3];
    cr_assert(ism_thin_probe_one(&s, lo, hi, 1, at), "the probe missed");
    cr_assert(at[0] == -1 && at[1] == -1 && at[2] == -1, "found (%g %g %g), not the corner",
              at[0], at[1], at[2]);
    ism_eval_ws_free(s.ws);
    ism_tape_free(tape);
}
