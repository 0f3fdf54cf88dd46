/* test_stitch.c — ism_stitch on lines whose polygons are known by construction: a closed
 * n-gon around the 32-end line (FEW_ENDS) where the graph leaves the stack for the heap
 * (n = 16: 32 ends, the last kept inline; n = 17: the first allocated), two sheets crossing
 * at one point (four single-polygon ends there, paired by their far gradients), and two
 * sheets closed through copies of one shared (double) line, each below and above 32 ends.
 * Each loop must be closed, hold the expected number of points, and step only along given
 * lines. Then where ends meet: a corner written 0 and -0 (alone, and interleaved in end
 * order at a corner of two triangles), and a corner with a NaN coordinate, each on the
 * stack's graph and the heap's. */
#include <criterion/criterion.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "core/octree/stitch.h"

enum { MAX_LINES = 64 };

typedef struct lineset {
    ism_fline v[MAX_LINES];
    size_t n;
} lineset;

static ism_fpoint fpoint(double x, double y, double z, const double g[3])
{
    ism_fpoint p = { { x, y, z }, { g[0], g[1], g[2] }, 0 };
    return p;
}

static void add_line(lineset *s, ism_fpoint a, ism_fpoint b, uint8_t kind)
{
    cr_assert(s->n < MAX_LINES);
    /* every other line runs backwards: the stitcher must not rely on a line's direction */
    bool flip = s->n & 1;
    s->v[s->n++] = (ism_fline){ flip ? b : a, flip ? a : b, kind };
}

/* Shuffles the lines (a fixed LCG): the stitcher must not rely on their order either. */
static void shuffle(lineset *s, uint32_t seed)
{
    for (size_t i = s->n; i > 1; i--) {
        seed = seed * 1664525u + 1013904223u;
        size_t j = (seed >> 8) % i;
        ism_fline t = s->v[i - 1];
        s->v[i - 1] = s->v[j];
        s->v[j] = t;
    }
}

/* The points of a sheet: pts[0..n) on a circle of radius 1 about `centre` in the plane
 * spanned by axes u and w, starting at angle pi (pts[0] = centre - e_u exactly, the origin
 * for the crossing sheets); g is the sheet's normal. */
static void circle(ism_fpoint *pts, int n, const double centre[3], int u, int w,
                   const double g[3])
{
    for (int i = 0; i < n; i++) {
        double t = M_PI + 2.0 * M_PI * i / n, q[3] = { centre[0], centre[1], centre[2] };
        q[u] += i == 0 ? -1.0 : cos(t);
        q[w] += i == 0 ? 0.0 : sin(t);
        pts[i] = fpoint(q[0], q[1], q[2], g);
    }
}

static bool same_point(const ism_fpoint *a, const ism_fpoint *b)
{
    return memcmp(a->p, b->p, sizeof a->p) == 0;
}

/* Is a–b one of the lines (either direction)? */
static bool is_line(const lineset *s, const ism_fpoint *a, const ism_fpoint *b)
{
    for (size_t k = 0; k < s->n; k++)
        if ((same_point(&s->v[k].a, a) && same_point(&s->v[k].b, b)) ||
            (same_point(&s->v[k].a, b) && same_point(&s->v[k].b, a)))
            return true;
    return false;
}

/* Stitches s and checks: nloops loops, each closed, each of npts points, consecutive
 * points (and last to first) joined by a given line, no point twice in a loop, every point
 * of a loop on one sheet (the same normal). */
static void expect_loops(const char *what, const lineset *s, size_t nloops, size_t npts)
{
    ism_flines l = { (ism_fline *)s->v, s->n, s->n };
    ism_loops out = { 0 };
    cr_assert(ism_stitch(&l, &out), "%s: stitch failed", what);
    cr_assert_eq(out.nloops, nloops, "%s: %zu loops, expected %zu", what, out.nloops, nloops);
    for (size_t i = 0; i < out.nloops; i++) {
        const ism_loop *lp = &out.loops[i];
        cr_expect(lp->closed, "%s: loop %zu open", what, i);
        cr_assert_eq(lp->n, npts, "%s: loop %zu has %zu points, expected %zu", what, i, lp->n,
                     npts);
        const ism_fpoint *p = out.pts + lp->first;
        for (size_t j = 0; j < lp->n; j++) {
            const ism_fpoint *q = &p[(j + 1) % lp->n];
            cr_expect(is_line(s, &p[j], q), "%s: loop %zu steps %zu -> %zu off the lines", what,
                      i, j, (j + 1) % lp->n);
            cr_expect(memcmp(p[j].g, p[0].g, sizeof p[0].g) == 0,
                      "%s: loop %zu leaves its sheet at %zu", what, i, j);
            for (size_t k = j + 1; k < lp->n; k++)
                cr_expect(!same_point(&p[j], &p[k]), "%s: loop %zu repeats a point", what, i);
        }
    }
    ism_loops_free(&out);
}

static const double NZ[3] = { 0, 0, 1 }, NY[3] = { 0, 1, 0 };

/* One n-gon of single-polygon lines. */
static void ngon(int n)
{
    ism_fpoint pts[MAX_LINES];
    const double centre[3] = { 0.25, -0.5, 0.125 };
    circle(pts, n, centre, 0, 1, NZ);
    lineset s = { .n = 0 };
    for (int i = 0; i < n; i++)
        add_line(&s, pts[i], pts[(i + 1) % n], ISM_LINE_REGULAR);
    shuffle(&s, (uint32_t)n);
    char what[32];
    snprintf(what, sizeof what, "%d-gon", n);
    expect_loops(what, &s, 1, (size_t)n);
}

Test(stitch, one_polygon_inline_and_heap)
{
    for (int n = 3; n <= 40; n++)
        ngon(n); /* 16 lines = 32 ends, the last inline graph; 17 the first on the heap */
}

/* Two n-gons through the origin, one in z = 0 (normal z), one in y = 0 (normal y).
 * Crossing (shared false): four single-polygon ends meet at the origin, and pairing by the
 * far ends' gradients keeps each sheet's polygon apart. Shared: the sheets also share the
 * point Q = a[n-1], and each sheet's chain of n - 1 single-polygon lines from the origin to
 * Q is closed by its own copy of the double line Q -> origin (a double line on a face). */
static void two_sheets(int n, bool shared)
{
    ism_fpoint a[MAX_LINES / 2], b[MAX_LINES / 2];
    const double ca[3] = { 1, 0, 0 }, cb[3] = { 0, 0, 1 };
    circle(a, n, ca, 0, 1, NZ); /* z = 0: meets y = 0 at the origin and (2, 0, 0) */
    circle(b, n, cb, 2, 0, NY); /* y = 0: meets z = 0 at the origin only */
    cr_assert(same_point(&a[0], &b[0]) && a[0].p[0] == 0 && a[0].p[1] == 0 && a[0].p[2] == 0);
    if (shared)
        memcpy(b[n - 1].p, a[n - 1].p, sizeof a[n - 1].p);
    lineset s = { .n = 0 };
    for (int i = 0; i < n; i++) {
        uint8_t kind = shared && i == n - 1 ? ISM_LINE_DOUBLE : ISM_LINE_REGULAR;
        add_line(&s, a[i], a[(i + 1) % n], kind);
        add_line(&s, b[i], b[(i + 1) % n], kind);
    }
    shuffle(&s, (shared ? 11u : 7u) + (uint32_t)n);
    char what[64];
    snprintf(what, sizeof what, "%s %d-gons (%d ends)",
             shared ? "sheets sharing a line," : "crossing", n, 4 * n);
    expect_loops(what, &s, 2, (size_t)n);
}

Test(stitch, crossing_sheets_inline_and_heap)
{
    for (int n = 3; n <= 12; n++)
        two_sheets(n, false); /* 8 lines (32 ends) inline; 9 and more (36+ ends) on the heap */
}

Test(stitch, shared_line_closes_each_sheet)
{
    for (int n = 4; n <= 12; n++)
        two_sheets(n, true);
}

/* A square whose corner D = (0, 2, 0.5) is written (-0, 2, 0.5) by its last line: ends
 * meet only where their points are the same bits (every node computes a shared point bit for
 * bit the same, stitch.c), so -0 and 0 are two points and the square is one open chain of 5
 * points (with D written alike: one closed loop of 4). Alone (8 ends, the stack's graph) and
 * beside a 17-gon elsewhere (42 ends, the heap's): both ways group the ends alike. */
static void square_with_zero(double dx, bool beside, size_t want_pts, bool want_closed)
{
    const double pa[4][3] = { { 0.5, 1, 0.5 }, { 1, 1, 0.5 }, { 1, 2, 0.5 }, { 0, 2, 0.5 } };
    ism_fpoint q[4];
    for (int i = 0; i < 4; i++)
        q[i] = fpoint(pa[i][0], pa[i][1], pa[i][2], NZ);
    ism_fpoint d2 = fpoint(dx, 2, 0.5, NZ);
    lineset s = { .n = 0 };
    add_line(&s, q[0], q[1], ISM_LINE_REGULAR);
    add_line(&s, q[1], q[2], ISM_LINE_REGULAR);
    add_line(&s, q[2], q[3], ISM_LINE_REGULAR);
    add_line(&s, d2, q[0], ISM_LINE_REGULAR);
    if (beside) {
        ism_fpoint pts[17];
        const double centre[3] = { 5, 5, 5 };
        circle(pts, 17, centre, 0, 1, NY);
        for (int i = 0; i < 17; i++)
            add_line(&s, pts[i], pts[(i + 1) % 17], ISM_LINE_REGULAR);
    }
    ism_flines l = { s.v, s.n, s.n };
    ism_loops out = { 0 };
    cr_assert(ism_stitch(&l, &out));
    cr_assert_eq(out.nloops, beside ? 2u : 1u);
    size_t found = 0;
    for (size_t i = 0; i < out.nloops; i++) {
        const ism_loop *lp = &out.loops[i];
        if (out.pts[lp->first].g[2] != 1)
            continue; /* the 17-gon (normal y) */
        found++;
        cr_expect_eq(lp->n, want_pts, "dx %g beside %d: %zu points", dx, beside, lp->n);
        cr_expect_eq(lp->closed, want_closed, "dx %g beside %d", dx, beside);
    }
    cr_expect_eq(found, 1u);
    ism_loops_free(&out);
}

Test(stitch, signed_zero_is_another_point)
{
    for (int beside = 0; beside < 2; beside++) {
        square_with_zero(0.0, beside, 4, true);
        square_with_zero(-0.0, beside, 5, false);
    }
}

/* Lines as given (no flip, no shuffle: the end order is part of the case), then k triangles
 * elsewhere (normal x, each closed, 3 points) to take the graph from the stack (k = 3: 15
 * lines, 30 ends) to the heap (k = 4: 18 lines, 36 ends). */
static ism_flines with_triangles(lineset *s, int k)
{
    static const double NX[3] = { 1, 0, 0 };
    for (int i = 0; i < k; i++) {
        double x = 5 + 3 * i;
        ism_fpoint t[3] = { fpoint(x, 5, 5, NX), fpoint(x + 1, 5, 5, NX), fpoint(x, 6, 5, NX) };
        for (int j = 0; j < 3; j++) {
            cr_assert(s->n < MAX_LINES);
            s->v[s->n++] = (ism_fline){ t[j], t[(j + 1) % 3], ISM_LINE_REGULAR };
        }
    }
    return (ism_flines){ s->v, s->n, s->n };
}

/* Checks the k triangles of with_triangles among out's loops and returns how many loops
 * are not theirs. */
static size_t others(const ism_loops *out, int k, const char *what)
{
    size_t tri = 0;
    for (size_t i = 0; i < out->nloops; i++) {
        const ism_loop *lp = &out->loops[i];
        if (out->pts[lp->first].g[0] != 1)
            continue;
        tri++;
        cr_expect(lp->closed && lp->n == 3, "%s: a triangle elsewhere broken", what);
    }
    cr_expect_eq(tri, (size_t)k, "%s: %zu triangles elsewhere, expected %d", what, tri, k);
    return out->nloops - tri;
}

/* Two triangles meeting at the origin, T1 = (P, A, B) in z = 0 and T2 = (P', C, D) in
 * y = 0, where T1 writes the origin P = (0, 0, 0) and T2 writes it P' = (-0, 0, 0), their
 * ends at the origin interleaved in end order: 0 (P, T1), 2 (P', T2), 7 (P, T1), 11 (P', T2).
 * The rule today (stitch.c build_graph): ends grouped by the points' values, ends ascending
 * in a group, then parted into runs of the same bits: four runs of one end each, so by hand
 * each triangle is one open chain of 4 points, from P back to P (T1) and from P' back to P'
 * (T2), its two ends at the origin never meeting though they are the same bits (revV 2: a
 * rule by bits would close both, 3 points each, and this test's expectations change with
 * it). A grouping by bits, or one that kept the groups' ends out of end order, closes them:
 * this fails. Built on the stack's graph and the heap's, with the same chains. */
static void interleaved_zero(int k, ism_fpoint chain[2][4])
{
    ism_fpoint p = fpoint(0, 0, 0, NZ), a = fpoint(1, 0, 0, NZ), b = fpoint(0, 1, 0, NZ);
    ism_fpoint q = fpoint(-0.0, 0, 0, NY), c = fpoint(0, 0, 1, NY), d = fpoint(1, 0, 1, NY);
    lineset s = { .v = { { p, a, 0 }, { q, c, 0 }, { a, b, 0 }, { b, p, 0 }, { c, d, 0 },
                         { d, q, 0 } },
                  .n = 6 };
    for (size_t i = 0; i < s.n; i++)
        s.v[i].kind = ISM_LINE_REGULAR;
    ism_flines l = with_triangles(&s, k);
    char what[48];
    snprintf(what, sizeof what, "interleaved zero, %zu ends", 2 * l.n);
    ism_loops out = { 0 };
    cr_assert(ism_stitch(&l, &out), "%s", what);
    cr_assert_eq(others(&out, k, what), 2u, "%s: %zu loops", what, out.nloops);
    size_t seen = 0;
    for (size_t i = 0; i < out.nloops; i++) {
        const ism_loop *lp = &out.loops[i];
        const ism_fpoint *lpts = out.pts + lp->first;
        if (lpts[0].g[0] == 1)
            continue;
        int t = lpts[0].g[2] == 1 ? 0 : 1;
        cr_assert(!(seen & (1u << t)), "%s: triangle %d twice", what, t + 1);
        seen |= 1u << t;
        cr_expect(!lp->closed, "%s: T%d closed", what, t + 1);
        cr_assert_eq(lp->n, 4u, "%s: T%d has %zu points", what, t + 1, lp->n);
        cr_expect(same_point(&lpts[0], t ? &q : &p) && same_point(&lpts[3], t ? &q : &p),
                  "%s: T%d's chain not from its origin back to it", what, t + 1);
        memcpy(chain[t], lpts, sizeof chain[t]);
    }
    ism_loops_free(&out);
}

Test(stitch, signed_zero_interleaved_at_a_corner)
{
    ism_fpoint stack[2][4], heap[2][4];
    interleaved_zero(3, stack);
    interleaved_zero(4, heap);
    for (int t = 0; t < 2; t++)
        for (int i = 0; i < 4; i++)
            cr_expect(same_point(&stack[t][i], &heap[t][i]) &&
                          memcmp(stack[t][i].g, heap[t][i].g, sizeof stack[t][i].g) == 0,
                      "the stack's and heap's chains differ: T%d at %d", t + 1, i);
}

/* A triangle whose corner A is (NaN, 0, 0), written alike by both its lines: a NaN equals
 * nothing by value, yet the two ends are the same bits, so they meet and the triangle
 * closes (3 points), on the stack's graph (alone: 6 ends; the sort's old insertion order
 * left them apart, an open chain of 4) and the heap's (beside 5 triangles: 36 ends; qsort
 * was given no order there). */
Test(stitch, nan_point_meets_its_bits)
{
    for (int k = 0; k <= 5; k += 5) {
        ism_fpoint a = fpoint(NAN, 0, 0, NZ), b = fpoint(1, 0, 0, NZ), c = fpoint(0, 1, 0, NZ);
        lineset s = { .v = { { a, b, 0 }, { b, c, 0 }, { c, a, 0 } }, .n = 3 };
        for (size_t i = 0; i < s.n; i++)
            s.v[i].kind = ISM_LINE_REGULAR;
        ism_flines l = with_triangles(&s, k);
        ism_loops out = { 0 };
        cr_assert(ism_stitch(&l, &out), "k %d", k);
        cr_assert_eq(others(&out, k, "NaN"), 1u, "k %d: %zu loops", k, out.nloops);
        for (size_t i = 0; i < out.nloops; i++) {
            const ism_loop *lp = &out.loops[i];
            if (out.pts[lp->first].g[0] == 1)
                continue;
            cr_expect(lp->closed, "k %d: the NaN triangle open", k);
            cr_expect_eq(lp->n, 3u, "k %d: the NaN triangle has %zu points", k, lp->n);
        }
        ism_loops_free(&out);
    }
}

/* The plain node (stitch.c plain_pairs: single-polygon lines whose ends meet two by two)
 * stitched on its own, and again beside 6 triangles elsewhere (18 more lines: the heap's
 * graph, which groups every node by the general rule): its loops come first either way, as
 * the second loop of ism_stitch finds them line by line, and must be the same bits — points,
 * gradients, flags, closed. Nodes that look plain but are not, where the general rule
 * leaves an end unpaired: a far gradient too large (its squared norm overflows: far_agreement
 * NaN), or infinite; and a tiny and a zero far gradient (agreement a number: paired). */
static void plain_as_general(const char *what, lineset *s)
{
    cr_assert(s->n <= 16, "%s: not on the stack", what);
    ism_flines alone = { s->v, s->n, s->n };
    ism_loops a = { 0 }, b = { 0 };
    cr_assert(ism_stitch(&alone, &a), "%s", what);
    size_t n = s->n;
    ism_flines beside = with_triangles(s, 6);
    cr_assert(ism_stitch(&beside, &b), "%s", what);
    s->n = n;
    cr_assert_eq(b.nloops, a.nloops + 6, "%s: %zu loops beside, %zu alone", what, b.nloops,
                 a.nloops);
    for (size_t i = 0; i < a.nloops; i++) {
        const ism_loop *la = &a.loops[i], *lb = &b.loops[i];
        cr_expect(la->n == lb->n && la->closed == lb->closed, "%s: loop %zu differs", what, i);
        for (size_t j = 0; j < la->n && la->n == lb->n; j++) {
            const ism_fpoint *p = &a.pts[la->first + j], *q = &b.pts[lb->first + j];
            cr_expect(memcmp(p->p, q->p, sizeof p->p) == 0 && memcmp(p->g, q->g, sizeof p->g) == 0
                          && p->flags == q->flags,
                      "%s: loop %zu point %zu differs", what, i, j);
        }
    }
    ism_loops_free(&a);
    ism_loops_free(&b);
}

/* A pentagon and a square (normal z), flipped and shuffled by add_line and shuffle; the
 * pentagon's corners in `odd` (a bit each) take the gradient g, the far gradient of their
 * neighbours' ends. want_open: the open chains (by hand: the points whose two ends
 * far_agreement leaves unpaired cut the pentagon there, and a chain whose two ends meet at
 * one point is closed there, that point twice); want_pts: the points of all loops. */
static void plain_case(const char *what, unsigned odd, const double g[3], size_t want_open,
                       size_t want_pts)
{
    ism_fpoint pent[5], sq[4];
    const double c1[3] = { 0.25, -0.5, 0.125 }, c2[3] = { 3, 3, 0.125 };
    circle(pent, 5, c1, 0, 1, NZ);
    circle(sq, 4, c2, 0, 1, NZ);
    for (int i = 0; i < 5; i++)
        if (odd >> i & 1)
            memcpy(pent[i].g, g, sizeof pent[i].g);
    lineset s = { .n = 0 };
    for (int i = 0; i < 5; i++)
        add_line(&s, pent[i], pent[(i + 1) % 5], ISM_LINE_REGULAR);
    for (int i = 0; i < 4; i++)
        add_line(&s, sq[i], sq[(i + 1) % 4], ISM_LINE_REGULAR);
    shuffle(&s, 5u);
    ism_flines l = { s.v, s.n, s.n };
    ism_loops out = { 0 };
    cr_assert(ism_stitch(&l, &out), "%s", what);
    size_t open = 0, pts = 0;
    for (size_t i = 0; i < out.nloops; i++)
        open += !out.loops[i].closed, pts += out.loops[i].n;
    cr_expect_eq(open, want_open, "%s: %zu open chains", what, open);
    cr_expect_eq(pts, want_pts, "%s: %zu points", what, pts);
    ism_loops_free(&out);
    plain_as_general(what, &s);
}

Test(stitch, plain_nodes_stitch_as_the_general_graph)
{
    const double big[3] = { 0, 0, 1e200 }, inf[3] = { INFINITY, 0, 0 };
    const double tiny[3] = { 1e-160, 0, 0 }, zero[3] = { 0, 0, 0 };
    plain_case("plain", 0, NZ, 0, 9);
    /* corners 0 and 2 at 1e200 along z: at corner 1 their dot product and norms are
     * infinite, inf / inf: the pentagon one chain from corner 1 round to corner 1 (6) */
    plain_case("far gradients 1e200", 1u << 0 | 1u << 2, big, 0, 10);
    /* corner 2 infinite along x: inf × 0 at corners 1 and 3: two open chains, 1-2-3 and
     * 3-4-0-1 */
    plain_case("far gradient inf", 1u << 2, inf, 2, 11);
    /* squared norms below 2^-900 (agreement_a_number says no) or 0: still paired */
    plain_case("far gradient 1e-160", 1u << 2, tiny, 0, 9);
    plain_case("far gradient 0", 1u << 2, zero, 0, 9);
}
