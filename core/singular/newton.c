/* newton.c — pseudo-inverse Newton on ∇f = 0 (newton.h). */
#include "core/singular/newton.h"
#include "core/singular/sym3_lanes.h"
#include "core/util/sym3.h"
#include "core/util/vec3.h"

#include <math.h>
#include <string.h>

static bool inside(const double p[3], const double lo[3], const double hi[3])
{
    _Pragma("GCC unroll 3") for (int k = 0; k < 3; k++)
        if ((lo && !(p[k] >= lo[k])) || (hi && !(p[k] <= hi[k])))
            return false;
    return true;
}

/* The Frobenius norm of a Hessian (xx, xy, xz, yy, yz, zz). */
static double frobenius(const double h[6])
{
    return sqrt(h[0] * h[0] + h[3] * h[3] + h[5] * h[5]
                + 2.0 * (h[1] * h[1] + h[2] * h[2] + h[4] * h[4]));
}

/* Linear convergence: where f vanishes to third order on a curve (the heart's ring z = 0),
 * ∇f vanishes to second order and H with it, and each step only halves the distance (64
 * steps to the tolerance). Steps shrinking by a ratio ρ that holds within NEWTON_STEADY
 * (relative) over two steps, in the same direction within NEWTON_ALIGN (cosine), with ρ in
 * [NEWTON_RHO_MIN, NEWTON_RHO_MAX] (below: quadratic convergence, nothing to gain; above: no
 * convergence to speak of), are stretched by 1/(1 − ρ) — the sum of the steps left — unless
 * that leaves the box; Newton then goes on from there (an overshoot is corrected by the next
 * step), and convergence is judged exactly as without the jump. */
#define NEWTON_STEADY 0.05
#define NEWTON_ALIGN 0.99
#define NEWTON_RHO_MIN 0.2
#define NEWTON_RHO_MAX 0.8

typedef struct steps {
    double prev[3], len, ratio; /* the last step, its length, its ratio to the one before */
} steps;

/* Stretches step (see above) when the last ratios are steady; records it either way. */
static void extrapolate(steps *h, double step[3], const double p[3], const ism_newton_opts *o)
{
    double len = ism_norm3(step), ratio = h->len > 0 ? len / h->len : 0.0;
    double cosine = h->len > 0 && len > 0
                        ? (step[0] * h->prev[0] + step[1] * h->prev[1] + step[2] * h->prev[2]) /
                              (len * h->len)
                        : 0.0;
    bool steady = h->ratio > 0 && fabs(ratio - h->ratio) <= NEWTON_STEADY * h->ratio &&
                  ratio >= NEWTON_RHO_MIN && ratio <= NEWTON_RHO_MAX && cosine >= NEWTON_ALIGN;
    for (int k = 0; k < 3; k++)
        h->prev[k] = step[k];
    h->len = len;
    h->ratio = ratio;
    if (!steady)
        return;
    double q[3];
    for (int k = 0; k < 3; k++)
        q[k] = p[k] + step[k] / (1.0 - ratio);
    if (!inside(q, o->lo, o->hi))
        return;
    for (int k = 0; k < 3; k++)
        step[k] /= 1.0 - ratio;
    h->ratio = 0.0; /* two fresh ratios before the next jump */
}

/* One run between two jets: the scalar loop (ism_sing_newton) and the lanes
 * (ism_sing_newton_lanes) drive the same two steps, so each lane takes the scalar run's
 * operations in its order. */
typedef struct run {
    double *p;
    const ism_newton_opts *o;
    ism_newton_result r; /* r.grad, r.hess: the jet at p, written by the caller's evaluator */
    steps hist;
    double step[3];      /* the step that led to p */
    bool done;           /* ended by the jet at p (not finite, or the step was short) */
} run;

static void run_begin(run *u, double p[3], const ism_newton_opts *o)
{
    *u = (run){ .p = p, .o = o, .r = { false, 0, INFINITY, { 0 }, { 0 }, { 0 } } };
}

/* Whether the run goes on to a step from the jet at u->p: false when it ended on that jet,
 * is out of steps, or (setting u->r.converged) its gradient is exactly 0. */
static bool run_wants_step(run *u)
{
    if (u->done || u->r.iterations >= u->o->max_iter)
        return false;
    if (u->r.grad_norm == 0.0) {
        u->r.converged = true;
        return false;
    }
    return true;
}

/* Moves to the next iterate by u->step (ok: the pseudo-inverse gave one), stretched when the
 * steps shrink steadily: true when it moved and wants its jet. */
static bool run_move(run *u, bool ok)
{
    const ism_newton_opts *o = u->o;
    if (!ok)
        return false;
    if (o->extrapolate)
        extrapolate(&u->hist, u->step, u->p, o);
    double q[3] = { u->p[0] + u->step[0], u->p[1] + u->step[1], u->p[2] + u->step[2] };
    if (!inside(q, o->lo, o->hi))
        return false;
    for (int k = 0; k < 3; k++)
        u->p[k] = q[k];
    u->r.iterations++;
    return true;
}

/* The next iterate into u->p (run_wants_step, the pseudo-inverse step, run_move): true when
 * it moved there and wants its jet; false when the run is over (converged at a zero gradient,
 * out of steps, no step, or the step leaves [lo, hi]: p is then the last point inside). */
static bool run_step(run *u)
{
    return run_wants_step(u)
           && run_move(u, ism_sym3_pinv_step(u->r.grad, u->r.hess, u->o->rel, u->o->trust,
                                              u->step));
}

/* After the jet at p (u->r.grad, u->r.hess): the gradient's norm, and after a step the end
 * of the run when it is not finite or the step was short. */
static void run_took_jet(run *u)
{
    u->r.grad_norm = ism_norm3(u->r.grad);
    if (u->r.iterations == 0) {
        memcpy(u->r.start_hess, u->r.hess, sizeof u->r.start_hess);
        return;
    }
    if (!(u->r.grad_norm < INFINITY)) {
        u->done = true;
        return;
    }
    if (ism_norm3(u->step) < u->o->tol) {
        /* a short step is convergence only with a small gradient: a step truncated to
           directions the gradient does not point along is also short */
        u->r.converged =
            u->r.grad_norm <= ISM_SING_NEWTON_RESID * u->o->tol * frobenius(u->r.hess);
        u->done = true;
    }
}

ism_newton_result ism_sing_newton(const ism_tape *t, ism_eval_ws *ws, double p[3],
                                  const ism_newton_opts *o, uint64_t *evals)
{
    run u;
    run_begin(&u, p, o);
    do {
        ism_eval_hessian(t, ws, p[0], p[1], p[2], u.r.grad, u.r.hess);
        if (evals)
            ++*evals;
        run_took_jet(&u);
    } while (run_step(&u));
    return u.r;
}

/* One block of runs side by side (ism_sing_newton_lanes): the runs, the unfinished ones
 * (live[0..nl), indices into u), and the jets of a pass, compacted with live. */
typedef struct lanes {
    run u[ISM_SING_NEWTON_LANES];
    size_t live[ISM_SING_NEWTON_LANES], nl;
    double g[ISM_SING_NEWTON_LANES][3], h[ISM_SING_NEWTON_LANES][6];
} lanes;

/* The jets at the live runs' points in one batch, each taken by its run (run_took_jet);
 * live keeps, in order, the runs that go on to a step, their jets moved along with them.
 * Returns how many. */
static size_t lanes_take_jets(const ism_tape *t, ism_eval_ws *ws, lanes *l, uint64_t *evals)
{
    double at[ISM_SING_NEWTON_LANES][3], f[ISM_SING_NEWTON_LANES];
    for (size_t j = 0; j < l->nl; j++)
        memcpy(at[j], l->u[l->live[j]].p, sizeof at[j]);
    ism_eval_hessian_batch(t, ws, (const double (*)[3])at, f, l->g, l->h, l->nl);
    if (evals)
        *evals += l->nl;
    size_t keep = 0;
    for (size_t j = 0; j < l->nl; j++) {
        run *v = &l->u[l->live[j]];
        memcpy(v->r.grad, l->g[j], sizeof l->g[j]);
        memcpy(v->r.hess, l->h[j], sizeof l->h[j]);
        run_took_jet(v);
        if (run_wants_step(v)) {
            if (keep != j) {
                memcpy(l->g[keep], l->g[j], sizeof l->g[j]);
                memcpy(l->h[keep], l->h[j], sizeof l->h[j]);
            }
            l->live[keep++] = l->live[j];
        }
    }
    return keep;
}

/* The pseudo-inverse steps of the first n live runs four at a time (sym3_lanes.h), each run
 * moved by its own (run_move); live then holds, in order, those that moved. */
static void lanes_take_steps(lanes *l, size_t n)
{
    double rel[ISM_SING_NEWTON_LANES], trust[ISM_SING_NEWTON_LANES];
    double step[ISM_SING_NEWTON_LANES][3];
    bool ok[ISM_SING_NEWTON_LANES];
    for (size_t j = 0; j < n; j++) {
        rel[j] = l->u[l->live[j]].o->rel;
        trust[j] = l->u[l->live[j]].o->trust;
    }
    ism_sym3_pinv_lanes((const double (*)[3])l->g, (const double (*)[6])l->h, rel, trust, step,
                        ok, n);
    l->nl = 0;
    for (size_t j = 0; j < n; j++) {
        run *v = &l->u[l->live[j]];
        if (ok[j])
            memcpy(v->step, step[j], sizeof step[j]);
        if (run_move(v, ok[j]))
            l->live[l->nl++] = l->live[j];
    }
}

void ism_sing_newton_lanes(const ism_tape *t, ism_eval_ws *ws, double (*p)[3],
                           const ism_newton_opts *o, ism_newton_result *r, size_t n,
                           uint64_t *evals)
{
    lanes l;
    for (size_t a = 0; a < n; a += ISM_SING_NEWTON_LANES) {
        size_t m = n - a < ISM_SING_NEWTON_LANES ? n - a : ISM_SING_NEWTON_LANES;
        for (size_t i = 0; i < m; i++) {
            run_begin(&l.u[i], p[a + i], &o[a + i]);
            l.live[i] = i;
        }
        l.nl = m;
        while (l.nl)
            lanes_take_steps(&l, lanes_take_jets(t, ws, &l, evals));
        for (size_t i = 0; i < m; i++)
            r[a + i] = l.u[i].r;
    }
}
