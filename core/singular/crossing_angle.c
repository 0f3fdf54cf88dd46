/* crossing_angle.c — the angle two sheets cross at along a double curve (crossing_angle.h).
 * Across the curve f ≈ ½ (λ₊ a² + λ₋ b²) in the Hessian's eigenframe (a, b normal to the
 * curve, λ₊ > 0 > λ₋), so the sheets are the lines b = ±u a with u = √(λ₊ / −λ₋) and cross
 * at the angle φ, |tan φ| = 2u / |1 − u²|. For two surfaces g = 0, h = 0 whose normals meet
 * at θ, f = g h gives u = cot(θ/2) and |tan φ| = |tan θ|. */
#include "core/singular/crossing_angle.h"
#include "core/util/sym3.h"

#include <math.h>

double ism_crossing_tan_at(const ism_tape *f, ism_eval_ws *ws, const double p[3])
{
    double g[3], h[6], eig[3];
    ism_eval_hessian(f, ws, p[0], p[1], p[2], g, h);
    ism_sym3_eigen(h, eig, NULL);
    if (!(eig[2] > 0 && eig[0] < 0))
        return NAN;
    double u = sqrt(eig[2] / -eig[0]);
    if (!isfinite(u))
        return NAN;
    return 2 * u / fabs(1 - u * u);
}

double ism_curve_crossing_tan(const ism_tape *f, ism_eval_ws *ws, const double *xyz, size_t n)
{
    double t[ISM_CROSSING_SAMPLES];
    size_t m = 0, step = n > ISM_CROSSING_SAMPLES ? n / ISM_CROSSING_SAMPLES : 1;
    for (size_t i = 0; i < n && m < ISM_CROSSING_SAMPLES; i += step) {
        double v = ism_crossing_tan_at(f, ws, xyz + 3 * i);
        if (isnan(v))
            continue;
        size_t k = m++; /* insertion sort: at most ISM_CROSSING_SAMPLES values */
        for (; k > 0 && t[k - 1] > v; k--)
            t[k] = t[k - 1];
        t[k] = v;
    }
    return m ? t[m / 2] : NAN;
}
