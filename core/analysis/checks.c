/* checks.c — the input checks shared by ism_analyse and ism_analysis_project: sizes the
 * 32-bit indices can hold, finite coordinates, indices in range, options in range. */
#include "core/analysis/checks.h"
#include "core/util/pool.h"

#include <math.h>
#include <stdint.h>

#define MAX_COORD 1e100 /* larger coordinates would overflow squared lengths */
#define MAX_NEWTON_STEPS 100 /* Newton converges in a handful; more is a typo, and costs */

/* Bad input gets a message naming the first offending vertex or triangle. */
bool ism_an_check_mesh(const ism_mesh *m, ism_error *err)
{
    if (m->nverts >= UINT32_MAX)
        return ism_an_fail(err, "analysis: %zu vertices, at most %u allowed", m->nverts,
                           UINT32_MAX - 1);
    if (m->ntris > (UINT32_MAX - 3) / 3)
        return ism_an_fail(err, "analysis: %zu triangles, at most %u allowed", m->ntris,
                           (UINT32_MAX - 3) / 3);
    for (size_t i = 0; i < 3 * m->nverts; i++)
        if (!(fabs(m->pos[i]) <= MAX_COORD))
            return ism_an_fail(err, "analysis: vertex %zu has a coordinate that is not "
                               "a finite number below 1e100", i / 3);
    for (size_t i = 0; i < 3 * m->ntris; i++)
        if (m->tri[i] >= m->nverts)
            return ism_an_fail(err, "analysis: triangle %zu uses vertex %u, but the "
                               "mesh has %zu vertices", i / 3, m->tri[i], m->nverts);
    return true;
}

bool ism_an_check_options(const ism_analysis_options *o, ism_error *err)
{
    if (!(o->singular_rel >= 0 && o->singular_rel < 1))
        return ism_an_fail(err, "analysis: singular_rel must be in [0, 1)");
    if (o->newton_steps < 0 || o->newton_steps > MAX_NEWTON_STEPS)
        return ism_an_fail(err, "analysis: newton_steps must be in 0..%d", MAX_NEWTON_STEPS);
    if (o->threads < 0 || o->threads > ISM_MAX_THREADS)
        return ism_an_fail(err, "analysis: threads must be in 0..%d", ISM_MAX_THREADS);
    if (!(o->max_error >= 0 && isfinite(o->max_error)))
        return ism_an_fail(err, "analysis: max_error must be finite and at least 0");
    return true;
}
