/* graph_cert.c — f = 0 one graph over a node: f strictly monotone along one direction over
 * it, or over each of its halves where f may vanish (graph_cert.h). */
#include "core/octree/graph_cert.h"
#include "core/eval/interval_ops.h"
#include "core/expr/scalar_ops.h"
#include "core/expr/tape.h"
#include "core/util/vec3.h"

#include <math.h>
#include <string.h>

/* Kinks (min, max or abs whose both branches the box allows) a box is certified across: each
 * combination of their branches is one enclosure, 2^3 = 8 at most. The cube's corner holds
 * two (max(max(|x|, |y|), |z|)), a crease of two solids one; more is a node that splits. */
#define GRAPH_MAX_KINKS 3

/* The directional derivative must clear 0 by this fraction of the largest |∇f| the box
 * allows: the enclosure is rounded outward, so a bound of exactly 0 is never proof; a
 * thousandth keeps the surface's slope over the plane across d below 1000 — any finite
 * slope proves the graph, this only keeps rounding out of the verdict. */
#define MIN_SLOPE_FRACTION 1e-3

/* The sign (+1 or −1) with which ∇f · d clears 0 over the enclosure g of ∇f, 0 when it does
 * not (or g is not finite). */
static int slope_sign(const ism_ivgrad *g, const double d[3])
{
    double big = 0, low = 0, high = 0;
    for (int a = 0; a < 3; a++) {
        if (!isfinite(g->d[a].lo) || !isfinite(g->d[a].hi))
            return 0;
        /* ism_min / ism_max (comparisons), not libm's fmin / fmax (calls: 1,536 of fmax on
           the sphere at E 0.0141). They differ only on NaN and a zero's sign; the sign
           cannot change a sum's comparison, and a NaN p or q comes only from d: g is finite
           here, but d (one_slope: the sum of every enclosure's midpoint) is not checked and
           may be ±inf or NaN. Then that axis's term of big is inf or NaN (a bound >= 0 times
           |d[a]|), so big is inf (margin inf: neither low > margin nor high < -margin) or
           NaN (!(big > 0)): 0 either way, whatever p and q picked. */
        double al = fabs(g->d[a].lo), ah = fabs(g->d[a].hi);
        big += ism_max(al, ah) * fabs(d[a]);
        /* the enclosure of ∇f · d over the box: each term's interval scaled by d[a] */
        double p = g->d[a].lo * d[a], q = g->d[a].hi * d[a];
        low += ism_min(p, q);
        high += ism_max(p, q);
    }
    double margin = MIN_SLOPE_FRACTION * big;
    return !(big > 0) ? 0 : low > margin ? 1 : high < -margin ? -1 : 0;
}

/* d += the midpoint of g's gradient enclosure. */
static void add_midpoint(const ism_ivgrad *g, double d[3])
{
    for (int a = 0; a < 3; a++)
        d[a] += 0.5 * g->d[a].lo + 0.5 * g->d[a].hi;
}

bool ism_graph_from_enclosure(const ism_ivgrad *g)
{
    double d[3] = {0, 0, 0};
    add_midpoint(g, d);
    return slope_sign(g, d) != 0;
}

/* Whether the enclosure g of ∇f holds 0 (along every axis): then no direction clears it. */
static bool holds_zero(const ism_ivgrad *g)
{
    for (int a = 0; a < 3; a++)
        if (!(g->d[a].lo <= 0 && g->d[a].hi >= 0))
            return false;
    return true;
}

/* Steps of the search for a shared direction (shared_direction): each moves d toward the
 * point of the enclosures' hull nearest 0, which is reached (or shown absent) in a few steps
 * where the boxes lie well clear of 0 — the nodes worth certifying. Barth's sextic at E
 * 0.0259: of the searches that succeeded, 1,112 of 1,504 within 3 steps, 1,424 within 12;
 * 2,719 ran out at 24, and 24 -> 12 steps took 666.4M -> 658.1M instructions of
 * ism_mesh_surface for 24,056 -> 24,344 triangles. */
#define DIRECTION_STEPS 12

/* A direction d along which every enclosure g[0..m) of ∇f clears 0 (slope_sign +1 on each):
 * some d does exactly when 0 lies outside the convex hull of the boxes, and the point of that
 * hull nearest 0 is the best one (each box's slope along it at least its squared length).
 * Found by Frank–Wolfe steps from the sum of the midpoints (one_slope's d): each takes the
 * box corner least along d (the hull's support point) and moves d to the point nearest 0 on
 * the segment toward it. Only the verdict of slope_sign on the final d is trusted: the steps
 * pick a candidate, the test proves it. */
static bool shared_direction(const ism_ivgrad *g, int m, double d[3])
{
    for (int c = 0; c < m; c++)
        if (holds_zero(&g[c]))
            return false; /* 0 in one box is in the hull: no step can help (most refusals) */
    d[0] = d[1] = d[2] = 0;
    for (int c = 0; c < m; c++)
        add_midpoint(&g[c], d);
    for (int step = 0;; step++) {
        int c = 0;
        while (c < m && slope_sign(&g[c], d) == 1)
            c++;
        if (c == m)
            return true;
        if (step == DIRECTION_STEPS)
            return false;
        double least = INFINITY, s[3] = {0, 0, 0};
        for (c = 0; c < m; c++) { /* the corner of the boxes least along d */
            double v[3], along = 0;
            for (int a = 0; a < 3; a++) {
                v[a] = d[a] >= 0 ? g[c].d[a].lo : g[c].d[a].hi;
                along += v[a] * d[a];
            }
            if (along < least) {
                least = along;
                memcpy(s, v, sizeof s);
            }
        }
        double u[3] = {s[0] - d[0], s[1] - d[1], s[2] - d[2]};
        double uu = ism_dot3(u, u), t = -ism_dot3(d, u) / uu;
        if (!(uu > 0) || !(t > 0))
            return false; /* d is already the hull's point nearest 0: 0 in the hull */
        t = t < 1 ? t : 1;
        for (int a = 0; a < 3; a++)
            d[a] += t * u[a];
    }
}

/* One direction d (the sum of the midpoints of g[0..m)) along which every enclosure g[c]
 * clears 0 with the same sign. */
static bool one_slope(const ism_ivgrad *g, int m)
{
    double d[3] = {0, 0, 0};
    for (int c = 0; c < m; c++)
        add_midpoint(&g[c], d);
    int sign = slope_sign(&g[0], d);
    for (int c = 1; c < m && sign != 0; c++)
        if (slope_sign(&g[c], d) != sign)
            return false;
    return sign != 0;
}

/* Of the two pieces of f's top min/max over a box (ism_ivjet_top_pieces), appends to g[*m]
 * those whose gradients decide where f = 0 lies: both, unless one's value keeps f's sign
 * to the other's (max with b < 0 over the box: f = 0 exactly where a = 0 and f has a's sign,
 * so a alone must be monotone; min with b > 0 likewise). Where both count, f is the max (or
 * min) of two functions strictly monotone along d, itself strictly monotone. */
static void deciding_pieces(const ism_tape *t, const ism_ivgrad piece[2], ism_ivgrad *g,
                            int *m)
{
    bool is_max = ism_tape_top_minmax(t)->op == ISM_OP_MAX_RR;
    int only = -1;
    for (int p = 0; p < 2 && only < 0; p++) {
        ism_interval other = piece[1 - p].v;
        if (is_max ? other.hi < 0 : other.lo > 0)
            only = p;
    }
    for (int p = 0; p < 2; p++)
        if (only < 0 || p == only)
            g[(*m)++] = piece[p];
}

/* What sub-box sub (f's enclosure there *f, with nk free kinks) asks of the shared
 * direction: nothing where f keeps one sign over it, else f's gradient enclosure (no kink)
 * or its top pieces' (deciding_pieces), appended to g[*m]. False where it holds a kink not
 * at the top or more than one. */
static bool sub_box_slopes(const ism_tape *t, const ism_ivjet_ws *jet,
                           const ism_interval sub[3], const ism_ivgrad *f, size_t nk,
                           ism_ivgrad *g, int *m)
{
    if (f->v.lo > 0 || f->v.hi < 0)
        return true;
    if (nk == 0) {
        g[(*m)++] = *f;
        return true;
    }
    ism_ivgrad piece[2];
    if (nk != 1 || !ism_ivjet_top_pieces(t, jet, sub, piece))
        return false;
    deciding_pieces(t, piece, g, m);
    return true;
}

/* Halves evaluated in one pass of the lanes: their group width (interval_jet.h, four boxes
 * a group), so that a proof a half of the first group ends pays no second pass. Barth's
 * sextic at E 0.0259: 8 a pass 647.1M instructions, 4 a pass 645.9M (same mesh). */
#define HALVES_GROUP 4

/* The box halved along each axis: sub-box k takes the upper half along a where bit a of k
 * is set. */
static void halve(const ism_interval box[3], ism_interval sub[8][3])
{
    for (int a = 0; a < 3; a++) {
        double mid = 0.5 * box[a].lo + 0.5 * box[a].hi;
        for (int k = 0; k < 8; k++)
            sub[k][a] = k >> a & 1 ? iv(mid, box[a].hi) : iv(box[a].lo, mid);
    }
}

/* f = 0 one graph over the box by its eight halves: one direction d along which, on each
 * half where f may vanish, f's gradient enclosure (or its deciding top pieces') clears 0.
 * Then along any line parallel to d, on each half f either keeps one sign or its sign only
 * rises through one zero; f is continuous, so once past 0 it stays positive in the halves
 * after (a one-signed half must take the sign f brings into it): the line meets f = 0 at
 * most once in the box, and nowhere there ∇f = 0 on f = 0. The halves' enclosures are each
 * about half as wide as the box's (the natural enclosure's excess shrinks with the box),
 * and halves away from the surface drop out. */
static bool graph_on_halves(const ism_tape *t, ism_ivjet_ws *jet, const ism_interval box[3],
                            uint64_t *intervals)
{
    ism_interval sub[8][3];
    ism_ivgrad f[8], g[16];
    uint32_t nk[8];
    int m = 0;
    halve(box, sub);
    /* four halves a pass (the lanes' group), each group's pieces read before the next pass;
       a half whose enclosure holds 0 ends the proof before the second group is evaluated */
    for (int q = 0; q < 8; q += HALVES_GROUP) {
        *intervals += HALVES_GROUP;
        bool lanes = ism_eval_interval_grad_lanes(t, jet, (const ism_interval (*)[3])(sub + q),
                                                  HALVES_GROUP, f + q, nk + q);
        for (int k = q; k < q + HALVES_GROUP; k++) {
            /* one by one (a tape the lanes do not take), each box's pass right before its
               pieces are read */
            size_t n = lanes ? (nk[k] == UINT32_MAX ? (size_t)-1 : nk[k])
                             : ism_eval_interval_grad(t, jet, sub[k], NULL, NULL, &f[k]);
            int had = m;
            if (n == (size_t)-1 || !sub_box_slopes(t, jet, sub[k], &f[k], n, g, &m))
                return false;
            for (int c = had; c < m; c++)
                if (holds_zero(&g[c]))
                    return false; /* as shared_direction would answer */
        }
    }
    double d[3];
    return m == 0 || shared_direction(g, m, d);
}

/* Across the n kinks at tape positions at[0..n): ∇f's enclosure with every combination of
 * their branches forced (interval_jet.h: each holds ∇f wherever those branches are the active
 * ones, so together they hold it at every point of the box where f is differentiable), and
 * one direction d (the sum of their midpoints) along which each clears 0 with the same sign.
 * f is continuous and, along any line, piecewise smooth with its slopes in those enclosures:
 * strictly monotone along d, one graph. */
static bool graph_across_kinks(const ism_tape *t, ism_ivjet_ws *jet, const ism_interval box[3],
                               const size_t *at, int n, uint64_t *intervals)
{
    uint8_t force[ISM_GRAPH_MAX_TAPE];
    ism_ivgrad g[1 << GRAPH_MAX_KINKS];
    memset(force, ISM_BRANCH_FREE, t->len);
    for (int c = 0; c < 1 << n; c++) {
        for (int k = 0; k < n; k++)
            force[at[k]] = (uint8_t)(c >> k & 1 ? ISM_BRANCH_B : ISM_BRANCH_A);
        (*intervals)++;
        if (ism_eval_interval_grad(t, jet, box, force, NULL, &g[c]) != 0)
            return false; /* a kink left free: the forcing did not take (or a misfit) */
    }
    return one_slope(g, 1 << n);
}

/* ism_graph_certified with the branches in force (NULL: none) taken over the whole box;
 * with force, kinks it leaves free are not certified across. */
static bool certified(const ism_tape *t, ism_ivjet_ws *jet, const double lo[3],
                      const double hi[3], const uint8_t *force, bool halves,
                      uint64_t *intervals, size_t *nkinks)
{
    if (nkinks)
        *nkinks = (size_t)-1;
    if (!jet)
        return false;
    ism_interval box[3];
    for (int a = 0; a < 3; a++)
        box[a] = iv(lo[a], hi[a]);
    ism_ivgrad g;
    (*intervals)++;
    size_t nk = ism_eval_interval_grad(t, jet, box, force, NULL, &g);
    if (nkinks)
        *nkinks = nk;
    double d[3];
    if (nk == 0) /* the midpoint's d first: what most boxes pass by */
        return ism_graph_from_enclosure(&g) || shared_direction(&g, 1, d) ||
               (halves && graph_on_halves(t, jet, box, intervals));
    if (force || nk > GRAPH_MAX_KINKS || t->len > ISM_GRAPH_MAX_TAPE)
        return false; /* too many kinks (or a workspace misfit: (size_t)-1), a long tape */
    /* one kink, at the top (two solids' min or max: Barth's sextic in its ball): its two
       forced enclosures, A then B as graph_across_kinks takes them, are the operands' the
       pass just left in jet (interval_jet.h), no pass for the kinks' places nor the two
       forced (barth-sextic E 0.0259: 2,168 boxes, 3 passes of ~3,550 instructions each) */
    ism_ivgrad piece[2], deciding[2];
    if (nk == 1 && ism_ivjet_top_pieces(t, jet, box, piece)) {
        if (one_slope(piece, 2))
            return true;
        int m = 0;
        deciding_pieces(t, piece, deciding, &m);
        return shared_direction(deciding, m, d) ||
               (halves && graph_on_halves(t, jet, box, intervals));
    }
    /* where the kinks are: asked again, only of such a box (the bytes cost every box) */
    uint8_t kinks[ISM_GRAPH_MAX_TAPE];
    (*intervals)++;
    ism_eval_interval_grad(t, jet, box, NULL, kinks, &g);
    size_t at[GRAPH_MAX_KINKS];
    int n = 0;
    for (size_t i = 0; i < t->len && n < (int)nk; i++)
        if (kinks[i])
            at[n++] = i;
    return graph_across_kinks(t, jet, box, at, n, intervals);
}

bool ism_graph_certified(const ism_tape *t, ism_ivjet_ws *jet, const double lo[3],
                         const double hi[3], uint64_t *intervals, size_t *nkinks)
{
    return certified(t, jet, lo, hi, NULL, true, intervals, nkinks);
}

bool ism_graph_certified_piece(const ism_tape *t, ism_ivjet_ws *jet, const double lo[3],
                               const double hi[3], const uint8_t *force, uint64_t *intervals)
{
    return certified(t, jet, lo, hi, force, true, intervals, NULL);
}

bool ism_graph_certified_whole(const ism_tape *t, ism_ivjet_ws *jet, const double lo[3],
                               const double hi[3], uint64_t *intervals)
{
    return certified(t, jet, lo, hi, NULL, false, intervals, NULL);
}
