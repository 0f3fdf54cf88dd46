/* sampler.h — one thread's access to f during polygonisation: the compiled tape, that
 * thread's evaluation workspace, and counters of every kind of evaluation (the statistics
 * report them). Also the small vector helpers the octree code shares. */
#ifndef ISM_SAMPLER_H
#define ISM_SAMPLER_H

#include <stdint.h>
#include <math.h>
#include "core/eval/eval.h"

typedef struct ism_sampler {
    const ism_tape *tape;
    ism_eval_ws *ws;
    uint64_t n_point, n_gradient, n_interval;
} ism_sampler;

static inline double ism_sample_f(ism_sampler *s, const double p[3])
{
    s->n_point++;
    return ism_eval_point(s->tape, s->ws, p[0], p[1], p[2]);
}

static inline double ism_sample_grad(ism_sampler *s, const double p[3], double g[3])
{
    s->n_gradient++;
    return ism_eval_gradient(s->tape, s->ws, p[0], p[1], p[2], g);
}

static inline double ism_dot3(const double a[3], const double b[3])
{
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}

static inline double ism_norm3(const double a[3]) { return sqrt(ism_dot3(a, a)); }

/* Normalises a in place; returns its former length (a is left unchanged when it is 0). */
static inline double ism_normalise3(double a[3])
{
    double n = ism_norm3(a);
    if (n > 0 && isfinite(n))
        for (int k = 0; k < 3; k++)
            a[k] /= n;
    return n;
}

static inline double ism_dist3(const double a[3], const double b[3])
{
    double d[3] = {a[0] - b[0], a[1] - b[1], a[2] - b[2]};
    return ism_norm3(d);
}

/* |f| / |∇f| at p: the first-order distance to f = 0. 0 where f is exactly 0 (on the surface,
 * even where ∇f vanishes: a cone's apex); +inf where there is no estimate: f or ∇f not
 * finite, or ∇f vanishing where f is not 0 (a critical point of f off the surface is not on
 * it, however small f). */
static inline double ism_sample_dist(ism_sampler *s, const double p[3])
{
    double g[3];
    double f = ism_sample_grad(s, p, g);
    if (f == 0)
        return 0;
    double gl = ism_norm3(g);
    if (!isfinite(f) || !isfinite(gl) || !(gl > 0))
        return INFINITY;
    return fabs(f) / gl;
}

/* -1, 0 or +1. */
static inline int ism_sign(double v) { return (v > 0) - (v < 0); }

#endif
