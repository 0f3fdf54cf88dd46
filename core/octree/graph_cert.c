/* graph_cert.c — f strictly monotone along one direction over a node (graph_cert.h). */
#include "core/octree/graph_cert.h"
#include "core/eval/interval_ops.h"
#include "core/expr/scalar_ops.h"
#include "core/expr/tape.h"

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
                      const double hi[3], const uint8_t *force, uint64_t *intervals,
                      size_t *nkinks)
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
    if (nk == 0)
        return ism_graph_from_enclosure(&g);
    if (force || nk > GRAPH_MAX_KINKS || t->len > ISM_GRAPH_MAX_TAPE)
        return false; /* too many kinks (or a workspace misfit: (size_t)-1), a long tape */
    /* one kink, at the top (two solids' min or max: Barth's sextic in its ball): its two
       forced enclosures, A then B as graph_across_kinks takes them, are the operands' the
       pass just left in jet (interval_jet.h), no pass for the kinks' places nor the two
       forced (barth-sextic E 0.0259: 2,168 boxes, 3 passes of ~3,550 instructions each) */
    ism_ivgrad piece[2];
    if (nk == 1 && ism_ivjet_top_pieces(t, jet, box, piece))
        return one_slope(piece, 2);
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
    return certified(t, jet, lo, hi, NULL, intervals, nkinks);
}

bool ism_graph_certified_piece(const ism_tape *t, ism_ivjet_ws *jet, const double lo[3],
                               const double hi[3], const uint8_t *force, uint64_t *intervals)
{
    return certified(t, jet, lo, hi, force, intervals, NULL);
}
