/* sample_dist.c — the polygoniser's distance from a point to f = 0 (see sample_dist.h). */
#include "core/octree/sample_dist.h"
#include "core/analysis/nearest.h"
#include "core/util/dist_bound.h"

double ism_dist_capped(ism_sampler *s, const double p[3], double d, const double *const *v,
                       int n)
{
    if (d * d > ism_nearest_corner_sq(p, v, n)) {
        double dv[ISM_DIST_CORNERS];
        for (int k = 0; k < n; k++)
            dv[k] = ism_sample_dist(s, v[k]);
        d = ism_dist_through_corners(d, p, v, dv, n);
    }
    /* f's own tape: the search leaves the leaf's box (the local tape holds only inside) */
    if (s->dist_above > 0 && d > s->dist_above) {
        uint64_t counts[2] = {0, 0};
        d = ism_an_nearest_zero(s->tape, s->ws, p, d, s->rays_below, counts);
        s->n_point += counts[0];
        s->n_gradient += counts[1];
    }
    return d;
}

double ism_plain_dist(ism_sampler *s, const double p[3], double f, const double g[3],
                      double e)
{
    double plain = ism_first_order_dist(f, g);
    if (!ism_first_order_unsure(plain, e))
        return plain;
    double x[3], gx[3];
    ism_newton_foot(p, f, g, x);
    double fx = ism_sample_grad(s, x, gx);
    return ism_stepped_dist(plain, fx, gx);
}

void ism_plain_dists(ism_sampler *s, const double (*p)[3], const double *f,
                     const double (*g)[3], double e, double *out, size_t n)
{
    double x[ISM_GRAD_BATCH][3], fx[ISM_GRAD_BATCH], gx[ISM_GRAD_BATCH][3];
    size_t at[ISM_GRAD_BATCH], m = 0;
    for (size_t i = 0; i < n; i++) { /* ism_plain_dist's first half, point by point */
        out[i] = ism_first_order_dist(f[i], g[i]);
        if (ism_first_order_unsure(out[i], e)) {
            ism_newton_foot(p[i], f[i], g[i], x[m]);
            at[m++] = i;
        }
        if (m == ISM_GRAD_BATCH || (i + 1 == n && m)) { /* the second steps, a batch full */
            ism_sample_grad_batch(s, (const double (*)[3])x, fx, gx, m);
            for (size_t k = 0; k < m; k++)
                out[at[k]] = ism_stepped_dist(out[at[k]], fx[k], gx[k]);
            m = 0;
        }
    }
}
