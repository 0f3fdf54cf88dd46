/* deriv_rules.h — first and second derivatives of the one-argument operations, shared by
 * the gradient and Hessian evaluators: for out = g(u), gives g(u), g'(u) and g''(u). Where
 * the domain is clipped (sqrt, log, real powers below 0) the function is constant, so both
 * derivatives are 0 there. */
#ifndef ISM_DERIV_RULES_H
#define ISM_DERIV_RULES_H

#include <math.h>
#include "core/eval/sincos.h"
#include "core/eval/top_branch.h"
#include "core/expr/scalar_ops.h"
#include "core/expr/tape.h"

typedef struct ism_chain {
    double g, g1, g2;
} ism_chain;

/* u^n into *g and u^(n - 2) into *p2 (n >= 2) by ism_powi's products; with them g' = n (p2 u)
 * and g'' = n (n - 1) p2. x^4 and x^3, the powers presets use, are written out — (u²)² and
 * u (u²), ism_powi's own products (its final 1 × p exact) — where the squaring loop ran once
 * for g and once for p2. Every evaluator's integer power and its derivatives come from here
 * (ism_unary_chain, eval_gradient.c's dual_step) or from ism_powi_chain_lanes below. */
static inline void ism_powi_chain(double u, unsigned n, double *g, double *p2)
{
    if (n == 4) {
        *p2 = u * u;
        *g = *p2 * *p2;
    } else if (n == 3) {
        *p2 = u;
        *g = u * (u * u);
    } else {
        *p2 = ism_powi(u, n - 2);
        *g = ism_powi(u, n);
    }
}

/* ism_powi_chain on w values at once (w at most ISM_POWI_LANES, a constant where inlined):
 * g[j], p2[j] for u[j], the same products lane by lane (eval_gradient_batch.c). */
static inline __attribute__((always_inline)) void
ism_powi_chain_lanes(const double *restrict u, unsigned n, double *restrict g,
                     double *restrict p2, size_t w)
{
    if (n == 4) {
        for (size_t j = 0; j < w; j++) {
            p2[j] = u[j] * u[j];
            g[j] = p2[j] * p2[j];
        }
    } else if (n == 3) {
        for (size_t j = 0; j < w; j++) {
            p2[j] = u[j];
            g[j] = u[j] * (u[j] * u[j]);
        }
    } else {
        ism_powi_lanes(p2, u, n - 2, w);
        ism_powi_lanes(g, u, n, w);
    }
}

static inline ism_chain ism_unary_chain(const ism_instr *in, double u)
{
    ism_chain r = { 0.0, 0.0, 0.0 };
    double c = in->imm;
    switch (in->op) {
    case ISM_OP_COPY: r.g = u; r.g1 = 1.0; break;
    case ISM_OP_ADD_RC: r.g = u + c; r.g1 = 1.0; break;
    case ISM_OP_SUB_CR: r.g = c - u; r.g1 = -1.0; break;
    case ISM_OP_MUL_RC: r.g = u * c; r.g1 = c; break;
    case ISM_OP_DIV_RC: r.g = u / c; r.g1 = 1.0 / c; break;
    case ISM_OP_DIV_CR:
        r.g = c / u;
        r.g1 = -r.g / u;
        r.g2 = -2.0 * r.g1 / u;
        break;
    case ISM_OP_MIN_RC: /* the constant is operand b: top_branch.h's rule */
        r.g = ism_min(u, c);
        r.g1 = ism_minmax_gradient_operand(true, u, c) ? 0.0 : 1.0;
        break;
    case ISM_OP_MAX_RC:
        r.g = ism_max(u, c);
        r.g1 = ism_minmax_gradient_operand(false, u, c) ? 0.0 : 1.0;
        break;
    case ISM_OP_NEG: r.g = -u; r.g1 = -1.0; break;
    case ISM_OP_SQUARE: r.g = u * u; r.g1 = 2.0 * u; r.g2 = 2.0; break;
    case ISM_OP_POWI: {
        unsigned n = in->b;
        double p2;
        ism_powi_chain(u, n, &r.g, &p2);
        r.g1 = n * (p2 * u);
        r.g2 = (double)n * (n - 1) * p2;
        break;
    }
    case ISM_OP_POWC:
        r.g = ism_powc(u, c);
        if (u > 0.0) {
            r.g1 = c * pow(u, c - 1.0);
            r.g2 = c * (c - 1.0) * pow(u, c - 2.0);
        }
        break;
    case ISM_OP_SQRT:
        r.g = ism_sqrt_clip(u);
        if (u > 0.0) {
            r.g1 = 0.5 / r.g;
            r.g2 = -0.5 * r.g1 / u;
        }
        break;
    /* sin and cos through sincos.h: the other paths' bits */
    case ISM_OP_SIN: ism_sincos(u, &r.g, &r.g1); r.g2 = -r.g; break;
    case ISM_OP_COS: ism_sincos(u, &r.g1, &r.g); r.g1 = -r.g1; r.g2 = -r.g; break;
    case ISM_OP_TAN:
        r.g = tan(u);
        r.g1 = 1.0 + r.g * r.g;
        r.g2 = 2.0 * r.g * r.g1;
        break;
    case ISM_OP_EXP: r.g = exp(u); r.g1 = r.g; r.g2 = r.g; break;
    case ISM_OP_LOG:
        r.g = ism_log_clip(u);
        if (u > 0.0) {
            r.g1 = 1.0 / u;
            r.g2 = -r.g1 * r.g1;
        }
        break;
    case ISM_OP_ABS: r.g = fabs(u); r.g1 = u < 0.0 ? -1.0 : u > 0.0 ? 1.0 : 0.0; break;
    default: r.g = NAN; break;
    }
    return r;
}

#endif
