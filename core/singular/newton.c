/* newton.c — pseudo-inverse Newton on ∇f = 0 (newton.h). */
#include "core/singular/newton.h"
#include "core/util/sym3.h"
#include "core/util/vec3.h"

#include <math.h>

static bool inside(const double p[3], const double lo[3], const double hi[3])
{
    _Pragma("GCC unroll 3") for (int k = 0; k < 3; k++)
        if ((lo && !(p[k] >= lo[k])) || (hi && !(p[k] <= hi[k])))
            return false;
    return true;
}

static double jet_at(const ism_tape *t, ism_eval_ws *ws, const double p[3], double g[3],
                     double h[6], uint64_t *evals)
{
    ism_eval_hessian(t, ws, p[0], p[1], p[2], g, h);
    if (evals)
        ++*evals;
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

ism_newton_result ism_sing_newton(const ism_tape *t, ism_eval_ws *ws, double p[3],
                                  const ism_newton_opts *o, uint64_t *evals)
{
    ism_newton_result r = { false, 0, INFINITY, { 0 }, { 0 } };
    double *g = r.grad, *h = r.hess, step[3]; /* every exit leaves the jet of the final p */
    jet_at(t, ws, p, g, h, evals);
    r.grad_norm = ism_norm3(g);
    steps hist = { { 0 }, 0.0, 0.0 };
    while (r.iterations < o->max_iter) {
        if (r.grad_norm == 0.0) {
            r.converged = true;
            return r;
        }
        if (!ism_sym3_pinv_step(g, h, o->rel, o->trust, step))
            return r;
        if (o->extrapolate)
            extrapolate(&hist, step, p, o);
        double q[3] = { p[0] + step[0], p[1] + step[1], p[2] + step[2] };
        if (!inside(q, o->lo, o->hi))
            return r;
        for (int k = 0; k < 3; k++)
            p[k] = q[k];
        r.iterations++;
        double hnorm = jet_at(t, ws, p, g, h, evals);
        r.grad_norm = ism_norm3(g);
        if (!(r.grad_norm < INFINITY))
            return r;
        if (ism_norm3(step) < o->tol) {
            /* a short step is convergence only with a small gradient: a step truncated to
               directions the gradient does not point along is also short */
            r.converged = r.grad_norm <= ISM_SING_NEWTON_RESID * o->tol * hnorm;
            return r;
        }
    }
    return r;
}
