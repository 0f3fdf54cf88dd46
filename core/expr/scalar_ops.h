/* scalar_ops.h — the meaning of each operation on one double, shared by constant folding
 * in the compiler and by every evaluator, so that all of them compute the same function.
 *
 * Domains are clipped rather than left undefined: sqrt, log and real powers treat an
 * argument below 0 as 0, so f has a value (possibly -inf for log) at every point and the
 * interval evaluator can enclose it. */
#ifndef ISM_SCALAR_OPS_H
#define ISM_SCALAR_OPS_H

#include <math.h>
#include <stddef.h>

static inline double ism_clip0(double a) { return a > 0.0 ? a : 0.0; }

static inline double ism_sqrt_clip(double a) { return sqrt(ism_clip0(a)); }

static inline double ism_log_clip(double a) { return log(ism_clip0(a)); }

/* a^imm for a non-integer constant imm, a clipped to [0, inf). */
static inline double ism_powc(double a, double c) { return pow(ism_clip0(a), c); }

static inline double ism_min(double a, double b) { return a < b ? a : b; }

static inline double ism_max(double a, double b) { return a > b ? a : b; }

/* a^n for n >= 0 by repeated squaring (the same products the interval evaluator bounds). */
static inline double ism_powi(double a, unsigned n)
{
    double r = 1.0;
    double p = a;
    while (n) {
        if (n & 1u)
            r *= p;
        n >>= 1;
        if (n)
            p *= p;
    }
    return r;
}

/* ism_powi on w values at once: out[j] = a[j]^n by the same products lane by lane (the one
 * place besides ism_powi that spells them out: the batched evaluators call this). w at most
 * ISM_POWI_LANES (eval_double.c's group); where it is inlined with a constant w the loops
 * vectorise. out and a distinct (no tape instruction writes a register it reads). */
#define ISM_POWI_LANES 32
static inline __attribute__((always_inline)) void ism_powi_lanes(double *restrict out,
                                                                 const double *restrict a,
                                                                 unsigned n, size_t w)
{
    double p[ISM_POWI_LANES], r[ISM_POWI_LANES];
    for (size_t j = 0; j < w; j++) {
        p[j] = a[j];
        r[j] = 1.0;
    }
    while (n) {
        if (n & 1u)
            for (size_t j = 0; j < w; j++)
                r[j] *= p[j];
        n >>= 1;
        if (n)
            for (size_t j = 0; j < w; j++)
                p[j] *= p[j];
    }
    for (size_t j = 0; j < w; j++)
        out[j] = r[j];
}

#endif
