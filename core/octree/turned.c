/* turned.c — the corner-gradient turn and the critical radius of a feature about a cell
 * across (turned.h). */
#include "core/octree/turned.h"

#include <math.h>
#include "core/util/sym3.h"
#include "core/util/vec3.h"

bool ism_corners_turned(const double g[8][3], double cos_max)
{
    double len2[8], cos2 = cos_max * cos_max;
    for (int c = 0; c < 8; c++) {
        len2[c] = ism_dot3(g[c], g[c]);
        if (!isfinite(len2[c]))
            return false;
        if (!(len2[c] > 0))
            return true; /* a critical point of f at the corner: the tube's axis on a lattice
                            line (own box, depth 8) gave an inscribed square, −9.97% */
    }
    /* cos < cos_max < 0 as dot < 0 and dot² > cos_max² |a|² |b|² */
    for (int c = 0; c < 8; c++)
        for (int d = c + 1; d < 8; d++) {
            double dot = ism_dot3(g[c], g[d]);
            if (dot < 0 && dot * dot > cos2 * len2[c] * len2[d])
                return true;
        }
    return false;
}

/* The corner of k with the smallest gradient: the nearest to f's critical point. */
static int least_gradient(const ism_corners *k)
{
    int c0 = 0;
    double best = INFINITY;
    for (int c = 0; c < 8; c++) {
        double l2 = ism_dot3(k->g[c], k->g[c]);
        if (l2 < best)
            best = l2, c0 = c;
    }
    return c0;
}

double ism_critical_radius(const ism_tape *t, ism_eval_ws *ws, const ism_corners *k, double size,
                           int steps, double pinv_rel, double reach)
{
    int c0 = least_gradient(k);
    double x[3] = {k->p[c0][0], k->p[c0][1], k->p[c0][2]}, g[3], h[6];
    double f = ism_eval_hessian(t, ws, x[0], x[1], x[2], g, h);
    for (int it = 0; it < steps; it++) {
        double step[3];
        if (!ism_sym3_pinv_step(g, h, pinv_rel, INFINITY, step))
            return 0;
        for (int a = 0; a < 3; a++)
            x[a] += step[a];
        double d[3] = {x[0] - k->p[c0][0], x[1] - k->p[c0][1], x[2] - k->p[c0][2]};
        if (!(ism_dot3(d, d) <= reach * reach * size * size))
            return 0;
        f = ism_eval_hessian(t, ws, x[0], x[1], x[2], g, h);
    }
    double eig[3];
    ism_sym3_eigen(h, eig, NULL);
    double lmax = fmax(fabs(eig[0]), fabs(eig[2]));
    if (!(lmax > 0) || !isfinite(lmax) || !isfinite(f))
        return 0;
    return sqrt(2 * fabs(f) / lmax) / size;
}
