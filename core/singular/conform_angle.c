/* conform_angle.c — the tube's starting radius from the angle φ at which the two sheets
 * cross along a double curve (crossing_angle.h). A rim point on one sheet at distance s from
 * the curve has the other sheet s |tan φ| away along its normal:
 *
 *          sheet 2
 *            ╲    │ s |tan φ|
 *       ──────●───●──────── sheet 1      the rim is clear once s |tan φ| exceeds
 *            ╱ φ   s                      CF_CLEAR_CELLS cells
 *
 * Two spheres crossing at 29° need 2.7 cells, beyond the cut's first radius (2.5): the cut
 * was made, found unclear and made again 1.4 times wider. Starting at the radius the angle
 * asks for skips that round and a wider tube than needed. */
#include "core/singular/conform_internal.h"
#include "core/singular/crossing_angle.h"

#include <math.h>
#include <stdlib.h>

/* The radius asked for is this much beyond the one the angle gives: the rim's vertices lie
 * just outside the cut, a little off the sheets, on a curved surface. */
#define ANGLE_MARGIN 1.1

static int cmp_double(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return x < y ? -1 : x > y;
}

/* The radius the crossing at p needs (NAN where the Hessian is not that of two sheets
 * crossing: a pinch or triple point, a whisker, rounding). */
static double needed_at(cf_ctx *c, const double p[3])
{
    double tan_phi = ism_crossing_tan_at(c->f, c->ws, p);
    if (isnan(tan_phi))
        return NAN;
    return ANGLE_MARGIN * CF_CLEAR_CELLS * c->cell / tan_phi; /* 0 when tan φ is infinite */
}

double cf_crossing_radius(cf_ctx *c, const cf_polyline *pl, size_t npl)
{
    double *need = malloc((npl * ISM_CROSSING_SAMPLES + 1) * sizeof *need);
    if (!need)
        return 0; /* the cut widens as before */
    size_t n = 0;
    for (size_t k = 0; k < npl; k++) {
        size_t step = pl[k].n > ISM_CROSSING_SAMPLES ? pl[k].n / ISM_CROSSING_SAMPLES : 1;
        for (size_t i = 0, taken = 0; i < pl[k].n && taken < ISM_CROSSING_SAMPLES; i += step, taken++) {
            double r = needed_at(c, pl[k].p + 3 * i);
            if (!isnan(r))
                need[n++] = r;
        }
    }
    double r = 0;
    if (n) {
        qsort(need, n, sizeof *need, cmp_double);
        r = need[n / 2];
    }
    free(need);
    return r;
}
