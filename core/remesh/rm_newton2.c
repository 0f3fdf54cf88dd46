/* rm_newton2.c — Newton onto the common zero of two functions (rm_newton_two): a min/max's
 * two branches at a crease (rm_crease_slide.c) or two of f's pieces at a junction's missing
 * crease (rm_junction_fan.c). Minimum-norm steps (core/util/min_norm.h) until both values are
 * within tol of 0 to first order (|a| / |∇a|), then one step more: from within tol a step
 * lands at rounding, so the test is made before the step and the step is not measured again. */
#include "core/remesh/rm_pass.h"
#include "core/util/min_norm.h"
#include "core/util/vec3.h"

#include <math.h>

bool rm_newton_two(rm_two_eval ev, void *ctx, double x[3], double tol, double g[2][3])
{
    for (int it = 0; it <= ISM_RM_CREASE_NEWTON_STEPS; it++) {
        double val[2], step[3];
        if (!ev(ctx, x, val, g) || !isfinite(val[0]) || !isfinite(val[1]))
            return false;
        bool on = fabs(val[0]) <= tol * ism_norm3(g[0]) && fabs(val[1]) <= tol * ism_norm3(g[1]);
        if (!on && it == ISM_RM_CREASE_NEWTON_STEPS)
            return false;
        /* parallel gradients: no step; on already, x stays where it is */
        if (!ism_min_norm_step(2, (const double(*)[3])g, val, ISM_RM_CREASE_PARALLEL, step))
            return on;
        for (int k = 0; k < 3; k++)
            x[k] += step[k];
        if (on)
            return true;
    }
    return false;
}
