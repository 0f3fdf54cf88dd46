/* rm_bound.c — distances to f = 0 measured with a Newton step, and the bound checks built on
 * them (rm_bound.h). */
#include "core/remesh/rm_bound.h"
#include "core/remesh/rm_hcell.h"
#include "core/remesh/rm_memo.h"
#include "core/util/vec3.h"

#include "core/eval/eval.h"
#include "core/expr/tape.h"

#include <math.h>
#include <string.h>

/* Points of a fan whose first steps fan_first_steps takes in one batch: two chunks of the
 * batched evaluator (ISM_GRAD_BATCH), room for a fan of 31 triangles (x, and a centroid and
 * a midpoint each); a larger fan's last points are measured one by one. */
#define RM_FAN_BATCH (2 * ISM_GRAD_BATCH)
/* The batch pays where an evaluation costs more than its bookkeeping: a tape this long or
 * longer. Measured with the batch for every tape (threshold 1) against without it below 7,
 * callgrind --threads 1 --quality good, own box, ism_quality_pass instructions (s24, the
 * batch computing powers and exp in its lanes, each point's memo slot found once): tapes of
 * 6 gain, cube -0.87% (327.14M -> 324.28M), sphere -0.57% (6.70M -> 6.66M),
 * x^2+y^2-z^2-0.1 -0.84% (41.10M -> 40.75M), helicoid +0.06% (39.25M -> 39.27M); shorter
 * ones lose, x^2+y^2+z-0.5 (5) +0.15%, x^2+y^2-0.49 (4) +0.82%, x*x+y-z (3) +1.17%: one
 * evaluation there costs about what a lane's bookkeeping does. Tapes of 7 to 11 measured
 * with 7 against 12 (s23, 819d8fa): ding-dong (7) -2.7%, ellipsoid (8) -2.5%, steinmetz
 * (9) -3.8%, torus (10) -4.8%, steiner-roman (11) -8.2%. Every PLY byte-identical. A fan's
 * threshold only: rm_bound_distances, with no memo slots to find, batches every tape
 * (measured at distances_chunk). */
#define RM_FAN_BATCH_MIN_TAPE 6

/* e's first step from f's value fv and gradient e->g at x (first_step evaluates them;
 * fan_first_steps takes them from a batch). */
static inline void first_step_from(rm_pass *p, const double x[3], double fv, rm_memo_entry *e)
{
    const double *g = e->g;
    double g2 = ism_dot3(g, g);
    if (!rm_bound_first_step(p, fv, sqrt(g2), &e->s1)) {
        e->state = RM_MEMO_FAIL1;
        return;
    }
    double s = fv / g2;
    for (int k = 0; k < 3; k++)
        e->y[k] = x[k] - s * g[k];
    e->state = RM_MEMO_S1;
}

/* The Newton step at x into e: s1 = f/|∇f|, ∇f and y, where the step lands (state S1), or
 * FAIL1 where ∇f vanishes or f is not finite. */
static void first_step(rm_pass *p, const double x[3], rm_memo_entry *e)
{
    first_step_from(p, x, ism_eval_gradient(p->f, p->ws, x[0], x[1], x[2], e->g), e);
}

/* f/|∇f| where the step lands into e->s2 (state S2), or FAIL2, from f's value fy and
 * gradient h there (second_step evaluates them; rm_bound_distances takes them from a
 * batch). (f alone over |∇f| at x would cost half as much, but |∇f| changes along the step
 * as much as the term itself is worth: the torus at E 3e-3 then ends 7e-6 E beyond the
 * bound.) */
static inline void second_step_from(rm_pass *p, double fy, const double h[3], rm_memo_entry *e)
{
    double hn = sqrt(ism_dot3(h, h));
    if (!isfinite(fy) || !(hn > p->gthresh)) {
        e->state = RM_MEMO_FAIL2;
        return;
    }
    e->s2 = fy / hn;
    e->state = RM_MEMO_S2;
}

static void second_step(rm_pass *p, rm_memo_entry *e)
{
    double h[3], fy = ism_eval_gradient(p->f, p->ws, e->y[0], e->y[1], e->y[2], h);
    second_step_from(p, fy, h, e);
}

/* x's memo entry (own when the pass keeps no memo) with its first step taken. */
static rm_memo_entry *stepped(rm_pass *p, const double x[3], rm_memo_entry *own)
{
    rm_memo_entry *e = p->memo ? rm_memo_slot(p->memo, x) : own;
    if (e == own)
        own->state = RM_MEMO_EMPTY;
    if (e->state == RM_MEMO_EMPTY)
        first_step(p, x, e);
    return e;
}

bool rm_bound_gradient(rm_pass *p, const double x[3], double g[3])
{
    rm_memo_entry own; /* stepped empties it when it is used: no 92-byte clear per measure */
    rm_memo_entry *e = stepped(p, x, &own);
    if (e->state == RM_MEMO_FAIL1)
        return false;
    for (int k = 0; k < 3; k++)
        g[k] = e->g[k];
    return true;
}

/* RM_BOUND_ONE_STEP_SHARE (rm_bound.h): a first step within that share of the limit is the
 * measure. */

/* With a finite limit and the pass's Hessian cells (rm_hcell.h), a second step not yet taken
 * at x (first step e, |s1| at most max_error: the cell's grown box holds the step's segment)
 * is bounded instead when s1 and the bound on its term stay within limit: into *s2 that
 * bound, which is at least the step's term, so the sum is within limit exactly when the
 * measured one would be — a caller comparing with the limit decides as it would have.
 * False (the step is taken) otherwise. */
static bool residual_within(rm_pass *p, const rm_memo_entry *e, const double x[3], double limit,
                            double *s2)
{
    double a = fabs(e->s1);
    if (!p->hcell || !isfinite(limit) || !(a <= p->max_error))
        return false;
    double r = rm_hcell_residual(p, x, e->s1, sqrt(ism_dot3(e->g, e->g)));
    if (!(a + r <= limit))
        return false;
    rm_hcell_spared(p);
    *s2 = r;
    return true;
}

/* f/|∇f| at x into *s1 and, unless |*s1| is above limit or within its one-step share, where
 * the Newton step from x lands into *s2 (0 otherwise; with bounded, where residual_within
 * allows, a bound on it). False where ∇f vanishes or f is not finite. Each step is taken
 * once per point while the pass's memo (rm_memo.h) remembers it. */
static bool steps_at(rm_pass *p, rm_memo_entry *e, const double x[3], double limit,
                     bool bounded, double *s1, double *s2);

static bool two_steps(rm_pass *p, const double x[3], double limit, bool bounded, double *s1,
                      double *s2)
{
    rm_memo_entry own; /* stepped empties it when it is used: no 92-byte clear per measure */
    return steps_at(p, stepped(p, x, &own), x, limit, bounded, s1, s2);
}

/* two_steps with x's entry e, its first step taken (stepped's). */
static bool steps_at(rm_pass *p, rm_memo_entry *e, const double x[3], double limit,
                     bool bounded, double *s1, double *s2)
{
    *s2 = 0;
    if (e->state == RM_MEMO_FAIL1)
        return false;
    *s1 = e->s1;
    double scale = isfinite(limit) ? limit : p->max_error;
    if (fabs(*s1) > limit || fabs(*s1) <= RM_BOUND_ONE_STEP_SHARE * scale)
        return true;
    if (e->state == RM_MEMO_S1 && bounded && residual_within(p, e, x, limit, s2))
        return true;
    if (e->state == RM_MEMO_S1)
        second_step(p, e);
    if (e->state == RM_MEMO_FAIL2)
        return false;
    *s2 = e->s2;
    return true;
}

double rm_bound_distance(rm_pass *p, const double x[3], double limit)
{
    double s1, s2;
    return two_steps(p, x, limit, true, &s1, &s2) ? fabs(s1) + fabs(s2) : INFINITY;
}

/* rm_bound_distances for at most RM_DISTANCES_CHUNK points: their first steps in one batch,
 * then the second steps those need (|s1| above RM_BOUND_ONE_STEP_SHARE × max_error, as
 * steps_at asks with an infinite limit) in another. Every tape and every count, one point
 * included, goes through the batch: without a memo to look up, the batch beats
 * ism_eval_gradient point by point even below RM_FAN_BATCH_MIN_TAPE. Measured against the
 * point-by-point evaluation for tapes under 6 and for chunks of one point (revB 1; callgrind
 * --quality good --threads 1, -e EXPR in the default box, ism_quality_pass inclusive,
 * batched / point by point, meshes byte-identical): x*x+y-z (3), --max-error off, 13.51M /
 * 13.72M (+1.6%); x^2+y^2-0.49 (4) 23.75M / 24.17M (+1.8%), off 78.34M / 79.18M (+1.1%);
 * x^2+y^2+z-0.5 (5), off, 46.93M / 47.61M (+1.4%); one point point by point, cube +12.9k,
 * helicoid -1.5k, sphere off +3.5k. */
static void distances_chunk(rm_pass *p, const double (*x)[3], size_t n, double *d, double *gn)
{
    double px[RM_DISTANCES_CHUNK], py[RM_DISTANCES_CHUNK], pz[RM_DISTANCES_CHUNK];
    double fv[RM_DISTANCES_CHUNK], g[RM_DISTANCES_CHUNK][3];
    for (size_t i = 0; i < n; i++)
        px[i] = x[i][0], py[i] = x[i][1], pz[i] = x[i][2];
    ism_eval_gradient_batch(p->f, p->ws, px, py, pz, fv, g, n);
    if (!p->bounded) { /* rm_distance without a bound: one step's length */
        for (size_t i = 0; i < n; i++) {
            double len;
            d[i] = rm_unbounded_distance(p, fv[i], g[i], &len);
            if (gn)
                gn[i] = len;
        }
        return;
    }
    rm_memo_entry e[RM_DISTANCES_CHUNK];
    size_t m = 0, at[RM_DISTANCES_CHUNK];
    for (size_t i = 0; i < n; i++) {
        memcpy(e[i].g, g[i], sizeof e[i].g);
        first_step_from(p, x[i], fv[i], &e[i]);
        if (gn)
            gn[i] = 0;
        if (e[i].state == RM_MEMO_S1 && fabs(e[i].s1) > RM_BOUND_ONE_STEP_SHARE * p->max_error)
            at[m] = i, px[m] = e[i].y[0], py[m] = e[i].y[1], pz[m] = e[i].y[2], m++;
    }
    if (m)
        ism_eval_gradient_batch(p->f, p->ws, px, py, pz, fv, g, m);
    for (size_t j = 0; j < m; j++)
        second_step_from(p, fv[j], g[j], &e[at[j]]);
    for (size_t i = 0; i < n; i++) {
        double s1, s2;
        d[i] = steps_at(p, &e[i], x[i], INFINITY, true, &s1, &s2) ? fabs(s1) + fabs(s2)
                                                                   : INFINITY;
    }
}

void rm_bound_distances(rm_pass *p, const double (*x)[3], size_t n, double *d, double *gn)
{
    for (size_t i = 0; i < n; i += RM_DISTANCES_CHUNK) {
        size_t k = n - i < RM_DISTANCES_CHUNK ? n - i : RM_DISTANCES_CHUNK;
        distances_chunk(p, x + i, k, d + i, gn ? gn + i : NULL);
    }
}

/* The residual of a first step of length s1 bends by at most κ s1² / 2; the one-step rule
 * holds for κ × max_error up to 2 (1 - share) / share² (above), so the step's residual is
 * at most that over 2 max_error, times s1². */
#define RM_BOUND_RESIDUAL_REL \
    ((1 - RM_BOUND_ONE_STEP_SHARE) / (RM_BOUND_ONE_STEP_SHARE * RM_BOUND_ONE_STEP_SHARE))

double rm_bound_upper(rm_pass *p, const double x[3])
{
    double s1, s2, e = p->max_error;
    if (!two_steps(p, x, e, false, &s1, &s2))
        return INFINITY;
    double a = fabs(s1);
    return a <= RM_BOUND_ONE_STEP_SHARE * e ? a + RM_BOUND_RESIDUAL_REL * a * a / e
                                            : a + fabs(s2);
}

double rm_bound_signed(rm_pass *p, const double x[3])
{
    double s1, s2;
    return two_steps(p, x, -1, false, &s1, &s2) ? s1 : INFINITY;
}

bool rm_bound_edge(rm_pass *p, const double *a, const double *b)
{
    double m[3];
    rm_midpoint(a, b, m);
    return rm_bound_distance(p, m, p->max_error) <= p->max_error;
}

/* a + b + c with the two smallest added first: symmetric in its arguments. */
static double sum3(double a, double b, double c)
{
    double lo = a < b ? a : b, hi = a < b ? b : a;
    return c < hi ? (lo < c ? lo + c : c + lo) + hi : (lo + hi) + c;
}

void rm_centroid(const double *a, const double *b, const double *c, double m[3])
{
    for (int k = 0; k < 3; k++)
        m[k] = sum3(a[k], b[k], c[k]) / 3;
}

bool rm_bound_triangle(rm_pass *p, const double *a, const double *b, const double *c)
{
    double m[3];
    rm_centroid(a, b, c, m);
    return rm_bound_distance(p, m, p->max_error) <= p->max_error;
}

/* The points rm_bound_fan_worst measures, in its order: x, then each triangle's centroid
 * and the midpoint of its edge from v to the next corner; at most room of them (a fan of
 * more than (room - 1) / 2 triangles: the rest are worked out as they are measured).
 * Returns how many. */
static size_t fan_points(const rm_pass *p, uint32_t v, const double *x, double (*q)[3],
                         size_t room)
{
    memcpy(q[0], x, sizeof q[0]);
    size_t n = 1;
    for (uint32_t i = 0; i < p->r.count[v] && n + 2 <= room; i++, n += 2) {
        uint32_t t;
        int k;
        rm_fan_point(p, v, i, x, &t, &k, q[n], q[n + 1]);
    }
    return n;
}

/* The first steps of the fan's points q[0..n) that the memo does not know, taken in one
 * batch (ism_eval_gradient_batch: bit for bit ism_eval_gradient's values, a NaN's sign
 * aside, which first_step_from's tests ignore; one pass over the tape for all of them) and kept in the memo, where rm_bound_fan_worst's measures find
 * them: the same measures at a third of the cost. A fan's check almost always measures
 * every point (chmutov-quartic, own box: 8 in 1,000 relaxation checks stop early), so
 * taking all first steps at once spares more than the points a stop leaves unmeasured
 * cost. Points that share a memo slot are kept as the measures would keep them: the last.
 * Each point's slot into slot[j] (found once: the measures read them, point_measure). */
static void fan_first_steps(rm_pass *p, const double (*q)[3], size_t n, rm_memo_entry **slot)
{
    double px[RM_FAN_BATCH], py[RM_FAN_BATCH], pz[RM_FAN_BATCH], fv[RM_FAN_BATCH];
    double g[RM_FAN_BATCH][3];
    size_t m = 0, at[RM_FAN_BATCH];
    for (size_t j = 0; j < n; j++) {
        slot[j] = rm_memo_peek(p->memo, q[j]);
        if (!rm_memo_holds(slot[j], q[j]))
            at[m] = j, px[m] = q[j][0], py[m] = q[j][1], pz[m] = q[j][2], m++;
    }
    if (m < 2)
        return; /* one point: the measure's own evaluation costs no more */
    ism_eval_gradient_batch(p->f, p->ws, px, py, pz, fv, g, m);
    for (size_t i = 0; i < m; i++) {
        rm_memo_entry *e = rm_memo_claim(slot[at[i]], q[at[i]]);
        if (e->state == RM_MEMO_EMPTY) {
            memcpy(e->g, g[i], sizeof e->g);
            first_step_from(p, q[at[i]], fv[i], e);
        }
    }
}

/* rm_bound_distance at x, whose memo slot is e (rm_memo_peek's): read there while it holds
 * x (what rm_bound_distance's lookup would find), else measured through that lookup. */
static double point_measure(rm_pass *p, rm_memo_entry *e, const double x[3], double limit)
{
    double s1, s2;
    if (!rm_memo_holds(e, x))
        return rm_bound_distance(p, x, limit);
    return steps_at(p, e, x, limit, true, &s1, &s2) ? fabs(s1) + fabs(s2) : INFINITY;
}

double rm_bound_fan_worst(rm_pass *p, uint32_t v, const double *x, double limit, double stop)
{
    /* the points worked out once, for the batch and the measures; without a batch, each
       as it is measured (a stop leaves the rest unworked) */
    bool batch = p->memo && p->f->len >= RM_FAN_BATCH_MIN_TAPE;
    double q[RM_FAN_BATCH][3];
    rm_memo_entry *slot[RM_FAN_BATCH];
    size_t n = fan_points(p, v, x, q, batch ? RM_FAN_BATCH : 1);
    if (batch)
        fan_first_steps(p, (const double (*)[3])q, n, slot);
    double worst = -INFINITY;
    for (size_t j = 0; j < n && worst <= stop; j++) {
        double d = batch ? point_measure(p, slot[j], q[j], limit)
                         : rm_bound_distance(p, q[j], limit); /* never NaN: no fmax call */
        worst = d > worst ? d : worst;
    }
    for (uint32_t i = (uint32_t)(n - 1) / 2; i < p->r.count[v] && worst <= stop; i++) {
        uint32_t t;
        int k;
        double g[3], m[3];
        rm_fan_point(p, v, i, x, &t, &k, g, m);
        double dg = rm_bound_distance(p, g, limit);
        worst = dg > worst ? dg : worst;
        if (worst <= stop) {
            double dm = rm_bound_distance(p, m, limit);
            worst = dm > worst ? dm : worst;
        }
    }
    return worst;
}
