/* curvature.c — curvature of an implicit surface at a point from the gradient g and Hessian
 * H of f (Goldman 2005, "Curvature formulas for implicit curves and surfaces"):
 *   Gaussian  K = -det([[H, gᵀ], [g, 0]]) / |g|⁴ = g adj(H) gᵀ / |g|⁴
 *   mean      M = (|g|² tr H - g H gᵀ) / (2 |g|³)
 * with M's sign chosen so that x²+y²+z²-r² has M = +1/r; principal curvatures from M ± √(M²-K).
 * Computed with the unit normal n = g/|g| so that neither |g|⁴ nor |g|³ under- or overflows
 * before the division. */
#include "core/analysis/curvature.h"

#include <math.h>

enum { XX, XY, XZ, YY, YZ, ZZ };

static bool all_finite(const double *v, int n)
{
    for (int i = 0; i < n; i++)
        if (!isfinite(v[i]))
            return false;
    return true;
}

/* n adj(H) nᵀ for symmetric H. */
static double adjugate_form(const double n[3], const double h[6])
{
    double a11 = h[YY] * h[ZZ] - h[YZ] * h[YZ];
    double a22 = h[XX] * h[ZZ] - h[XZ] * h[XZ];
    double a33 = h[XX] * h[YY] - h[XY] * h[XY];
    double a12 = h[XZ] * h[YZ] - h[XY] * h[ZZ];
    double a13 = h[XY] * h[YZ] - h[XZ] * h[YY];
    double a23 = h[XY] * h[XZ] - h[XX] * h[YZ];
    return n[0] * n[0] * a11 + n[1] * n[1] * a22 + n[2] * n[2] * a33 +
           2 * (n[0] * n[1] * a12 + n[0] * n[2] * a13 + n[1] * n[2] * a23);
}

/* n H nᵀ for symmetric H. */
static double hessian_form(const double n[3], const double h[6])
{
    return n[0] * (h[XX] * n[0] + h[XY] * n[1] + h[XZ] * n[2]) +
           n[1] * (h[XY] * n[0] + h[YY] * n[1] + h[YZ] * n[2]) +
           n[2] * (h[XZ] * n[0] + h[YZ] * n[1] + h[ZZ] * n[2]);
}

bool ism_curvature_from_derivatives(const double g[3], const double h[6], double *mean,
                                    double *gauss, double *k1, double *k2)
{
    double m = 0, k = 0, p1 = 0, p2 = 0;
    double len = sqrt(g[0] * g[0] + g[1] * g[1] + g[2] * g[2]);
    bool ok = all_finite(g, 3) && all_finite(h, 6) && len > 0 && isfinite(len);
    if (ok) {
        double n[3] = {g[0] / len, g[1] / len, g[2] / len};
        m = (h[XX] + h[YY] + h[ZZ] - hessian_form(n, h)) / (2 * len);
        k = adjugate_form(n, h) / len / len;
        double s = sqrt(fmax(m * m - k, 0));
        p1 = m + s;
        p2 = m - s;
        ok = isfinite(m) && isfinite(k) && isfinite(p1) && isfinite(p2);
        if (!ok)
            m = k = p1 = p2 = 0;
    }
    if (mean)
        *mean = m;
    if (gauss)
        *gauss = k;
    if (k1)
        *k1 = p1;
    if (k2)
        *k2 = p2;
    return ok;
}
