/* edge_roots.c — roots of f on a lattice segment: sign test, gradient test (paper eq. 1-2),
 * regula falsi for a single root, the paper's double-root bisection for two roots or a
 * tangent root, and a check that counts segments likely to hold more than two roots. */
#include "core/octree/edge_roots.h"

#include <assert.h>
#include <math.h>
#include <string.h>

#define FALSI_MAX_ITERS 60
#define FALSI_TOLERANCE 1e-10 /* bracket width, as a fraction of the segment */

static void lerp(const double a[3], const double b[3], double t, double out[3])
{
    for (int k = 0; k < 3; k++)
        out[k] = a[k] + t * (b[k] - a[k]);
}

/* One regula falsi search's bracket: [t0, t1] with f0, f1 (Illinois-scaled) at its ends, the
 * side the last step replaced and the steps taken. ism_regula_falsi runs one, and
 * ism_regula_falsi_lanes many side by side, through the same four functions: each lane's
 * iterates, and its root, are the single search's bit for bit. */
typedef struct falsi {
    double t0, f0, t1, f1;
    int side, it;
} falsi;

static falsi falsi_start(double fa, double fb) { return (falsi){0, fa, 1, fb, 0, 0}; }

static bool falsi_running(const falsi *q)
{
    return q->it < FALSI_MAX_ITERS && q->t1 - q->t0 > FALSI_TOLERANCE;
}

/* The next parameter to evaluate: the secant's, or the middle when it falls outside. */
static double falsi_next(const falsi *q)
{
    double t = (q->t0 * q->f1 - q->t1 * q->f0) / (q->f1 - q->f0);
    if (!(t > q->t0 && t < q->t1))
        t = 0.5 * (q->t0 + q->t1);
    return t;
}

/* Narrows the bracket by f(t) = ft (not 0). */
static void falsi_take(falsi *q, double t, double ft)
{
    if ((ft < 0) == (q->f0 < 0)) {
        q->t0 = t, q->f0 = ft;
        if (q->side == -1)
            q->f1 *= 0.5; /* Illinois: halve the stale end so the bracket keeps shrinking */
        q->side = -1;
    } else {
        q->t1 = t, q->f1 = ft;
        if (q->side == +1)
            q->f0 *= 0.5;
        q->side = +1;
    }
    q->it++;
}

/* The root once the bracket is narrow enough (or the steps ran out). */
static double falsi_root(const falsi *q)
{
    double t = (q->t0 * q->f1 - q->t1 * q->f0) / (q->f1 - q->f0);
    if (!(t >= q->t0 && t <= q->t1))
        t = 0.5 * (q->t0 + q->t1);
    return t;
}

double ism_regula_falsi(ism_sampler *s, const double a[3], const double b[3], double fa,
                        double fb)
{
    falsi q = falsi_start(fa, fb);
    while (falsi_running(&q)) {
        double t = falsi_next(&q), p[3];
        lerp(a, b, t, p);
        double ft = ism_sample_f(s, p);
        if (ft == 0)
            return t;
        falsi_take(&q, t, ft);
    }
    return falsi_root(&q);
}

/* Searches stepped together by ism_regula_falsi_lanes: a step's points in one
 * ism_eval_points call (instructions a point on the Klein bottle's tape: 410 one at a time,
 * 161 / 139 at 16 / 32 points; eval.h). With 64 lanes a call held ~31 points on average, as
 * searches end at different steps (292a171, Klein bottle at E 3.27e-3, callgrind: 60,250
 * searches, 134 instructions a point in lanes against ~310 alone); 64 was not measured
 * against 32 or 128. */
#define FALSI_LANES 64

void ism_regula_falsi_lanes(ism_sampler *s, const double (*a)[3], const double (*b)[3],
                            const double *fa, const double *fb, double *t, size_t n)
{
    assert(!s->local); /* every point on s->tape: a local tape would need tape_at per lane */
    if (!s->batch) { /* the scalar reference path: one search at a time, the same bits */
        for (size_t i = 0; i < n; i++)
            t[i] = ism_regula_falsi(s, a[i], b[i], fa[i], fb[i]);
        return;
    }
    falsi q[FALSI_LANES];
    /* lane j runs search lane[j] from o[j] along d[j] = b − a (lerp's point, bit for bit) */
    double o[FALSI_LANES][3], d[FALSI_LANES][3];
    size_t lane[FALSI_LANES], live = 0, next = 0;
    for (;;) {
        /* free lanes take the next searches (a search starts on [0, 1], wider than
         * FALSI_TOLERANCE, so each takes at least one step) */
        while (live < FALSI_LANES && next < n) {
            size_t i = next++;
            q[live] = falsi_start(fa[i], fb[i]);
            for (int k = 0; k < 3; k++) {
                o[live][k] = a[i][k];
                d[live][k] = b[i][k] - a[i][k];
            }
            lane[live++] = i;
        }
        if (!live)
            return;
        double tj[FALSI_LANES], x[FALSI_LANES], y[FALSI_LANES], z[FALSI_LANES],
            fj[FALSI_LANES];
        for (size_t j = 0; j < live; j++) {
            double u = tj[j] = falsi_next(&q[j]);
            x[j] = o[j][0] + u * d[j][0];
            y[j] = o[j][1] + u * d[j][1];
            z[j] = o[j][2] + u * d[j][2];
        }
        s->n_point += live;
        ism_eval_points(s->tape, s->ws, x, y, z, fj, live);
        size_t still = 0; /* a search that ended gives its lane up */
        for (size_t j = 0; j < live; j++) {
            size_t i = lane[j];
            if (fj[j] == 0) {
                t[i] = tj[j];
                continue;
            }
            falsi_take(&q[j], tj[j], fj[j]);
            if (!falsi_running(&q[j])) {
                t[i] = falsi_root(&q[j]);
                continue;
            }
            if (still != j) { /* lanes before the first ended search stay where they are */
                q[still] = q[j];
                memcpy(o[still], o[j], sizeof o[0]);
                memcpy(d[still], d[j], sizeof d[0]);
                lane[still] = i;
            }
            still++;
        }
        live = still;
    }
}

/* Every this many halvings the double-root search asks one interval over what is left of
 * its bracket (below). Where the search ends without a root — most of its calls: the
 * gradients disagree across a fold of f that stays off 0 — it ran all double_root_iters
 * (25) gradients: 5,610 searches cost 116M instructions of the polygons of Barth's sextic at
 * E = 0.024, ~27 gradients each. An interval over a bracket of 1/8 of the segment is
 * usually tight enough there; at most 8 intervals are added where it never is. */
#define BRACKET_CHECK_EVERY 3

/* Does f keep the sign `side` and stay beyond eps over [a + ta (b - a), a + tb (b - a)]
 * (an interval over the box of those two points)? Every later midpoint of the search lies
 * in that box (the lerp is monotone in t) and its f inside the interval (outward rounded,
 * interval_ops.h: enclosing each double evaluation at a point of the box, which the
 * sampler's tapes give bit for bit), so no later step can see a sign change or |f| < eps:
 * the search's answer is 0 roots, exactly. */
static bool bracket_clear(ism_sampler *s, const double a[3], const double b[3], double ta,
                          double tb, double side, double eps)
{
    double p[3], q[3];
    lerp(a, b, ta, p);
    lerp(a, b, tb, q);
    ism_interval box[3];
    for (int k = 0; k < 3; k++) {
        box[k].lo = p[k] < q[k] ? p[k] : q[k];
        box[k].hi = p[k] < q[k] ? q[k] : p[k];
    }
    s->n_interval++;
    ism_interval r = ism_eval_interval(s->tape, s->ws, box[0], box[1], box[2]);
    return side > 0 ? r.lo > eps : r.hi < -eps;
}

int ism_double_root_search(ism_sampler *s, const ism_root_params *prm, const double a[3],
                           const double b[3], double fa, double fb, double *t)
{
    /* The paper halves [A, B] toward the end with the smaller |f|; that picks the wrong half
     * whenever the double root sits near the middle (|f| at the ends says nothing about
     * which side of c it is on). Here the half is chosen by the slope of f at c instead:
     * |f| falls toward the double root, so the root lies on the side where |f| decreases.
     * The paper's tests on f(c) are kept: a sign change means two roots, |f(c)| < eps one
     * double root. */
    double d[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]};
    double side = fa < 0 ? -1 : 1; /* sign of f at both ends */
    double ta = 0, tb = 1;
    (void)fb;
    for (int k = 0; k < prm->iters; k++) {
        if (k > 0 && k % BRACKET_CHECK_EVERY == 0 && bracket_clear(s, a, b, ta, tb, side, prm->eps))
            return 0; /* what the remaining halvings would answer, for one interval */
        double tc = 0.5 * (ta + tb), p[3], g[3];
        lerp(a, b, tc, p);
        double fc = ism_sample_grad(s, p, g);
        if (side * fc < 0) {
            *t = tc;
            return 2;
        }
        if (fabs(fc) < prm->eps) {
            *t = tc;
            return 1;
        }
        if (side * ism_dot3(g, d) > 0)
            tb = tc; /* |f| grows toward b: the minimum is in [ta, tc] */
        else
            ta = tc;
    }
    return 0;
}

static void make_root(ism_sampler *s, const double a[3], const double b[3], double t,
                      enum ism_root_kind kind, ism_root *r)
{
    r->t = t;
    r->kind = kind;
    lerp(a, b, t, r->p);
    ism_sample_grad(s, r->p, r->g);
}

static double gradient_agreement(const double ga[3], const double gb[3])
{
    return ism_agreement_normed(ga, gb, ism_norm3(ga), ism_norm3(gb));
}

bool ism_segment_may_reach(ism_sampler *s, const double a[3], const double b[3], double eps)
{
    ism_interval box[3];
    for (int k = 0; k < 3; k++) {
        box[k].lo = a[k] < b[k] ? a[k] : b[k];
        box[k].hi = a[k] < b[k] ? b[k] : a[k];
    }
    s->n_interval++;
    ism_interval r = ism_eval_interval(s->tape, s->ws, box[0], box[1], box[2]);
    return r.lo <= eps && r.hi >= -eps;
}

/* A root whose gradient turns against an end point's hints at further roots between them. */
static int suspect_more(const double g_end[3], const double g_root[3])
{
    return gradient_agreement(g_end, g_root) < -0.5;
}

bool ism_segment_rootless_normed(const ism_root_params *prm, const double a[3],
                                 const double b[3], double fa, double fb, const double ga[3],
                                 const double gb[3], double na, double nb)
{
    if (ism_rootless_ends(fa, fb))
        return true;
    if (!ism_one_sheet(prm, fa, fb, ga, gb, na, nb))
        return false;
    double d[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]};
    return !ism_pocket_by_slopes(fa, fb, ism_dot3(ga, d), ism_dot3(gb, d), prm->crease);
}

bool ism_segment_rootless(const ism_root_params *prm, const double a[3], const double b[3],
                          double fa, double fb, const double ga[3], const double gb[3])
{
    return ism_segment_rootless_normed(prm, a, b, fa, fb, ga, gb, ism_norm3(ga), ism_norm3(gb));
}

void ism_segment_roots(ism_sampler *s, const ism_root_params *prm, const double a[3],
                       const double b[3], double fa, double fb, const double ga[3],
                       const double gb[3], const double *known, ism_seg_roots *out)
{
    out->n = 0;
    out->flags = 0;
    if (ism_segment_rootless(prm, a, b, fa, fb, ga, gb))
        return;
    if ((fa < 0) != (fb < 0)) {
        make_root(s, a, b, known ? *known : ism_regula_falsi(s, a, b, fa, fb), ISM_ROOT_CROSS,
                  &out->r[0]);
        out->n = 1;
        /* Sign test says one root; if the gradient swings against both ends on the way,
         * an odd number of three or more is possible. */
        if (suspect_more(ga, out->r[0].g) && suspect_more(gb, out->r[0].g))
            out->flags |= ISM_SEG_MANY_ROOTS;
        return;
    }
    if (!ism_segment_may_reach(s, a, b, 0))
        return; /* the interval over the segment proves it: no root to search for */
    out->flags |= ISM_SEG_SEARCHED;
    double tc;
    int found = ism_double_root_search(s, prm, a, b, fa, fb, &tc);
    if (found == 1) {
        make_root(s, a, b, tc, ISM_ROOT_TOUCH, &out->r[0]);
        out->n = 1;
    } else if (found == 2) {
        double c[3];
        lerp(a, b, tc, c);
        double fc = ism_sample_f(s, c);
        double t1 = ism_regula_falsi(s, a, c, fa, fc) * tc;
        double t2 = tc + ism_regula_falsi(s, c, b, fc, fb) * (1 - tc);
        make_root(s, a, b, t1, ISM_ROOT_CROSS, &out->r[0]);
        make_root(s, a, b, t2, ISM_ROOT_CROSS, &out->r[1]);
        out->n = 2;
        if (suspect_more(ga, out->r[0].g) || suspect_more(gb, out->r[1].g))
            out->flags |= ISM_SEG_MANY_ROOTS;
    }
}
