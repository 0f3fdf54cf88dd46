/* find.c — the singular-locus driver (find.h): search, then each stage on what the previous
 * ones left in out->boxes. */
#include "core/singular/find.h"
#include "core/singular/curve_cert.h"
#include "core/singular/curves.h"
#include "core/singular/point_cert.h"
#include "core/singular/points.h"
#include "core/singular/search.h"

bool ism_locus_find(const ism_tape *f, const ism_locus_options *o, ism_locus *out,
                    ism_error *err)
{
    if (!ism_sing_search(f, o, out, err))
        return false;
    if (!ism_sing_points(f, o, out, err))
        return false;
    /* Each later stage works on the boxes not flagged ISM_LBOX_USED; one cut short by the
     * deadline or cancel sets out->incomplete itself. Double sheets (rank-1 boxes) need the
     * mesh: core/singular/surface.c meshes them after the polygoniser. */
    if (!ism_sing_trace_curves(f, o, out, err) || !ism_sing_certify_curve_points(f, o, out, err)
        || !ism_sing_certify_curves(f, o, out, err))
        return false;
    if (!ism_sing_name_crossings(out))
        return ism_error_set(err, "singular curves: out of memory");
    return true;
}
