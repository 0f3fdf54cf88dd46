/* curve_tracer.c — where a point lies against the tracer's box (see curve_tracer.h). */
#include "core/singular/curve_tracer.h"

#include <math.h>

int ism_ctracer_side(const ism_ctracer *tr, int k, double v)
{
    double slack = tr->jet.tol; /* a curve in a face wanders by rounding around it */
    return v < tr->box[k] - slack ? -1 : v > tr->box[k + 3] + slack ? 1 : 0;
}

bool ism_ctracer_inside(const ism_ctracer *tr, const double p[3])
{
    for (int k = 0; k < 3; k++)
        if (ism_ctracer_side(tr, k, p[k]) != 0 || isnan(p[k]))
            return false;
    return true;
}
