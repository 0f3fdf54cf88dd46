/* curve_trace.c — the predictor–corrector walk along one singular curve, with its step
 * control and the checks that end it. See curve_trace.h.
 *
 * Step: p̃ = p + h t; Newton on ∇f = 0 in the plane through p̃ normal to t (2×2, the
 * normal-plane Hessian). Accepted when Newton converges in few iterations, the tangent turns
 * by less than CTRACE_TURN_MAX and the normal-plane Hessian does not collapse. Near a point
 * where it does (a triple point: every branch's Hessian → 0 linearly), its largest
 * eigenvalue σ extrapolates linearly to 0 at distance d; steps are capped at d/2, so the
 * walk closes in geometrically and stops when d is below CTRACE_DEG_STOP_REL × diagonal. The
 * smaller eigenvalue is approached the same way, then stepped across: a sign change of the
 * determinant is a pinch point; none (it touched 0: two whiskers crossing, z² + x²y²) is a
 * point where the Hessian degenerates, ended at like a collapse. */
#include "core/singular/curve_trace.h"

#include <stdlib.h>
#include <string.h>
#include "core/singular/curve_events.h"
#include "core/util/clock.h"

/* Largest tangent turn per step (radians): the chord then strays at most h·0.2/8 = h/40
 * from the curve, well inside the box-marking distance (a sixteenth of a cell, h ≤ half a
 * cell). */
#define CTRACE_TURN_MAX 0.2

/* Newton's corrector may move at most this × the step from the predictor: farther means it
 * is heading to another branch. */
#define CTRACE_CORR_MOVE 0.25

/* Corrector iterations per step; a step needing more is retried at half length. Quadratic
 * convergence from a predictor O(h²) off the curve takes 3–4. */
#define CTRACE_NEWTON_IT 8
#define CTRACE_EASY_IT 3     /* converged this fast: grow the step */
#define CTRACE_HARD_IT 6     /* this slow: shrink it */
#define CTRACE_GROW 1.5
#define CTRACE_SHRINK 0.7

/* A step whose normal-plane Hessian scale drops below this fraction of the previous one is
 * retried shorter: a collapse is approached, not jumped over. */
#define CTRACE_SIGMA_DROP 0.25

/* The approach to a collapse stops when the extrapolated distance is below this × box
 * diagonal (a tenth of the promised 1e-9), and the point is placed there. */
#define CTRACE_DEG_STOP_REL 1e-10

/* The normal Hessian's smaller eigenvalue μ is approached until it is below this fraction of
 * the larger (or its zero extrapolates within the stop distance), then stepped across: D
 * changes sign (a pinch, located by regula falsi) or not (μ touched 0: where branches meet,
 * as two whiskers crossing in z² + x²y², or where the curve's transversal structure
 * degenerates). 1e-12 keeps 10⁴ above μ's rounding noise (~1e-16 of the Hessian), and a
 * touch (μ ~ s²) is then 1e-6 of the curve's scale away, where extrapolating √μ errs by
 * ~1e-12. */
#define CTRACE_MU_BAND 1e-12

/* When steps keep failing this close (× diagonal) to an extrapolated collapse, rounding has
 * won: the collapse point is placed at the extrapolation, its radius the distance. */
#define CTRACE_DEG_GIVEUP_REL 1e-6

/* A located pinch whose other normal eigenvalue fell below this fraction of its neighbours'
 * is no pinch: the whole normal Hessian collapses there (a triple or degenerate point). */
#define CTRACE_PINCH_SIGMA 0.1

/* Deadline and cancel are polled every this many step attempts (each a few Hessians). */
#define CTRACE_POLL 16

static void stop(ism_ctracer *tr, const char *why)
{
    if (!tr->stop)
        tr->why = why;
    tr->stop = true;
}

bool ism_ctracer_go(ism_ctracer *tr)
{
    if (tr->stop || tr->oom)
        return false;
    if (tr->attempts_left == 0 || tr->vertices_left == 0) {
        stop(tr, "singular curves: tracing budget exhausted");
        return false;
    }
    tr->attempts_left--;
    if (tr->polls++ % CTRACE_POLL == 0) { /* the first attempt polls too */
        if (tr->o->cancel && *tr->o->cancel) {
            stop(tr, "singular curves: cancelled");
            return false;
        }
        if (tr->o->deadline_ms > 0 && ism_now_ms() > tr->o->deadline_ms) {
            stop(tr, "singular curves: deadline");
            return false;
        }
    }
    return true;
}

static bool push(ism_ctracer *tr, ism_cpath *path, const double p[3], double D, int point)
{
    if (path->n == path->cap) {
        size_t cap = path->cap ? 2 * path->cap : 64;
        void *v = realloc(path->v, cap * sizeof *path->v);
        if (!v) {
            tr->oom = true;
            return false;
        }
        path->v = v;
        path->cap = cap;
    }
    ism_cvert *v = &path->v[path->n++];
    memcpy(v->p, p, sizeof v->p);
    v->D = D;
    v->point = point;
    if (tr->vertices_left)
        tr->vertices_left--;
    return true;
}

/* Appends p and records the segment from the previous vertex (boxes explained). */
static bool extend(ism_ctracer *tr, ism_cpath *path, const double p[3], double D, int point)
{
    if (path->n && !ism_cindex_add_segment(&tr->idx, path->v[path->n - 1].p, p, tr->delta)) {
        tr->oom = true;
        return false;
    }
    return push(tr, path, p, D, point);
}

static void end_at(ism_ctracer *tr, ism_cpath *path, int j)
{
    if (j < 0)
        return; /* out of memory (tr->oom is set) */
    const ism_sing_point *p = &tr->io->points[j];
    if (ism_dist3(path->v[path->n - 1].p, p->p) > 0.0)
        extend(tr, path, p->p, 0.0, -1);
    path->end_type = ISM_END_POINT;
    path->end_point = j;
}

/* Ends the path at the point where the normal-plane Hessian collapses, d ahead of c. */
static void end_at_collapse(ism_ctracer *tr, ism_cpath *path, const ism_cpoint *c, double d)
{
    double e[3];
    for (int k = 0; k < 3; k++)
        e[k] = c->p[k] + d * c->t[k];
    ism_cpoint m;
    ism_cjet_frame(&tr->jet, e, c->t, &m);
    end_at(tr, path, ism_cevent_point(tr, &m, ISM_SING_DEGENERATE, fmax(d, tr->jet.tol)));
}

/* Did the step cur→nxt come back across the start's normal plane, near the start? */
static bool closes(const ism_ctracer *tr, const ism_cpath *path, const ism_cpoint *start,
                   const ism_cpoint *cur, const ism_cpoint *nxt)
{
    const double *s = path->v[0].p;
    double a[3], b[3];
    for (int k = 0; k < 3; k++) {
        a[k] = cur->p[k] - s[k];
        b[k] = nxt->p[k] - s[k];
    }
    return path->n >= 4 && ism_dot3(a, start->t) < 0 && ism_dot3(b, start->t) >= 0 &&
           ism_dist3(nxt->p, s) <= 2.0 * tr->hmax;
}

/* One predictor–corrector attempt of length h from cur. */
static bool attempt(ism_ctracer *tr, const ism_cpoint *cur, double h, ism_cpoint *nxt,
                    int *iters)
{
    double pred[3], q[3];
    for (int k = 0; k < 3; k++)
        pred[k] = cur->p[k] + h * cur->t[k];
    if (!ism_cjet_correct(&tr->jet, pred, cur->n, cur->n, CTRACE_CORR_MOVE * h + tr->jet.tol,
                          CTRACE_NEWTON_IT, q, iters))
        return false;
    ism_cjet_frame(&tr->jet, q, cur->t, nxt);
    if (!(nxt->grad <= ISM_CURVE_GRAD_REL * nxt->hnorm * tr->diag))
        return false;
    if (ism_dot3(cur->t, nxt->t) < cos(CTRACE_TURN_MAX))
        return false;
    if (ism_cjet_normal_dot(cur, nxt) < 0) /* stepped over a collapse: approach it instead */
        return false;
    return !(nxt->sigma < CTRACE_SIGMA_DROP * cur->sigma) || cur->D * nxt->D < 0;
}

/* Handles a sign change of the determinant on cur→nxt. Returns false when the path ended
 * (the "pinch" is a collapse of the whole normal Hessian). */
static bool pinch(ism_ctracer *tr, ism_cpath *path, const ism_cpoint *cur, ism_cpoint *nxt,
                  int *ignore, bool *nxt_done)
{
    ism_cpoint pin;
    double radius;
    ism_cevent_locate_pinch(tr, cur, nxt, &pin, &radius);
    if (pin.sigma < CTRACE_PINCH_SIGMA * fmax(cur->sigma, nxt->sigma)) {
        end_at(tr, path, ism_cevent_point(tr, &pin, ISM_SING_DEGENERATE, radius));
        return false;
    }
    int j = ism_cevent_point(tr, &pin, ISM_SING_PINCH, radius);
    if (j < 0 || !extend(tr, path, pin.p, pin.D, j))
        return false;
    *ignore = j;
    *nxt_done = ism_dist3(pin.p, nxt->p) == 0.0; /* nxt itself was the pinch */
    return true;
}

/* Where a quantity falling from a to b over a step extrapolates linearly to 0 (∞ when it
 * does not fall). */
static double zero_ahead(double a, double b, double step)
{
    return b < a ? b * step / (a - b) : INFINITY;
}

/* The smaller eigenvalue of the normal-plane Hessian, in magnitude. */
static double mu_small(const ism_cpoint *c)
{
    return c->sigma > 0 ? fabs(c->D) / c->sigma : 0.0;
}

/* The step control's state: the next step; the extrapolated distances to a collapse of the
 * normal Hessian and to a zero of its smaller eigenvalue; probing: the next step crosses that
 * zero (dprobe ahead) to see whether D changes sign. */
typedef struct ctrace_plan {
    double h, dcol, dmin, dprobe;
    bool probing;
} ctrace_plan;

/* Plans the step after the accepted one cur→nxt (Newton took iters). */
static void plan_step(const ism_ctracer *tr, ctrace_plan *pl, const ism_cpoint *cur,
                      const ism_cpoint *nxt, bool pinched, int iters)
{
    double step = ism_dist3(cur->p, nxt->p), mc = mu_small(cur), mn = mu_small(nxt);
    pl->dcol = zero_ahead(cur->sigma, nxt->sigma, step);
    pl->dmin = pinched ? INFINITY : zero_ahead(mc, mn, step);
    double h = pl->h;
    h = iters <= CTRACE_EASY_IT ? h * CTRACE_GROW : iters >= CTRACE_HARD_IT ? h * CTRACE_SHRINK : h;
    pl->h = fmin(fmin(h, tr->hmax), 0.5 * fmin(pl->dcol, pl->dmin));
    pl->probing = false;
    if (!pinched && mn < mc &&
        (mn <= CTRACE_MU_BAND * nxt->sigma || pl->dmin <= CTRACE_DEG_STOP_REL * tr->diag)) {
        /* a pinch (D changes sign) or a touch (it does not)? √μ extrapolates to the zero
         * exactly where μ is quadratic (a touch), to twice its distance where linear (a
         * pinch): stepping 2× that lands beyond it either way, out of the noise */
        pl->probing = true;
        pl->dprobe = zero_ahead(sqrt(mc), sqrt(mn), step);
        pl->h = 2.0 * pl->dprobe + tr->jet.tol;
    }
}

void ism_ctrace(ism_ctracer *tr, const ism_cpoint *start, int ignore, bool closable,
                ism_cpath *path)
{
    ism_cpoint cur = *start, nxt;
    path->n = 0;
    path->closed = false;
    path->end_type = ISM_END_LOST;
    path->end_point = -1;
    if (!push(tr, path, cur.p, cur.D, -1))
        return;
    ctrace_plan pl = {tr->hmax, INFINITY, INFINITY, 0.0, false};
    while (ism_ctracer_go(tr)) {
        int iters = CTRACE_NEWTON_IT;
        if (!attempt(tr, &cur, pl.h, &nxt, &iters)) {
            if (pl.probing) { /* cannot step past it: the Hessian degenerates there */
                end_at_collapse(tr, path, &cur, pl.dprobe);
                return;
            }
            pl.h *= 0.5;
            if (pl.h >= tr->hmin)
                continue;
            if (fmin(pl.dcol, pl.dmin) <= CTRACE_DEG_GIVEUP_REL * tr->diag)
                end_at_collapse(tr, path, &cur, fmin(pl.dcol, pl.dmin));
            return; /* else: lost (no convergence) */
        }
        bool leaving = !ism_ctracer_inside(tr, nxt.p);
        if (leaving && !ism_cevent_clip(tr, &cur, &nxt)) {
            path->end_type = ISM_END_BOX; /* runs along the face: ends at its last point inside */
            return;
        }
        bool nxt_done = false, pinched = cur.D * nxt.D < 0 || (nxt.D == 0.0 && cur.D != 0.0);
        if (pinched && !pinch(tr, path, &cur, &nxt, &ignore, &nxt_done))
            return;
        if (pl.probing && !pinched) { /* the eigenvalue touched 0 and came back: no pinch */
            end_at_collapse(tr, path, &cur, pl.dprobe);
            return;
        }
        int j = ism_cevent_hit_point(tr, path->v[path->n - 1].p, nxt.p, ignore);
        if (j >= 0) {
            end_at(tr, path, j);
            return;
        }
        if (closable && closes(tr, path, start, &cur, &nxt)) {
            if (!ism_cindex_add_segment(&tr->idx, path->v[path->n - 1].p, path->v[0].p,
                                        tr->delta))
                tr->oom = true;
            path->closed = true;
            return;
        }
        if (!nxt_done && !extend(tr, path, nxt.p, nxt.D, -1))
            return;
        if (leaving) {
            path->end_type = ISM_END_BOX;
            return;
        }
        plan_step(tr, &pl, &cur, &nxt, pinched, iters);
        if (pl.dcol <= CTRACE_DEG_STOP_REL * tr->diag) {
            end_at_collapse(tr, path, &nxt, pl.dcol);
            return;
        }
        cur = nxt;
    }
}
