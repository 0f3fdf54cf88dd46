/* curves.c — the curves stage: evaluation state for f and the cut functions, the cut at the
 * issue's precision (ISM_CURVE_TOL_REL of the diagonal), then the arrangement. */
#include "core/curves/curves.h"
#include <math.h>
#include <string.h>
#include "core/util/vec3.h"

bool ism_curves_cut_mesh(const ism_tape *f, const ism_cut_fn *fns, size_t n,
                         const double box[6], ism_mesh *mesh, ism_cut *cut, ism_error *err)
{
    memset(cut, 0, sizeof *cut);
    ism_cut_eval ev;
    if (!ism_cut_eval_init(&ev, f, fns, n))
        return ism_error_set(err, "out of memory cutting the mesh along the curves");
    ev.box = box;
    /* Newton is asked for a thousandth of the tolerance: it converges quadratically, so the
     * last step lands far below it, and the reported residuals show the margin. */
    bool ok = ism_cut_mesh(&ev, 1e-3 * ISM_CURVE_TOL_REL * ism_box_diagonal(box), mesh, cut);
    ism_cut_eval_free(&ev);
    if (!ok) {
        ism_cut_free(cut);
        return ism_error_set(err, "out of memory cutting the mesh along the curves");
    }
    return true;
}

bool ism_curves_cut(const ism_tape *f, const ism_cut_fn *fns, size_t n, const double box[6],
                    ism_mesh *mesh, ism_cut *cut, ism_arrangement *arr, ism_error *err)
{
    memset(arr, 0, sizeof *arr);
    if (!ism_curves_cut_mesh(f, fns, n, box, mesh, cut, err))
        return false;
    if (!ism_arrangement_build(mesh, cut, NULL, 0, arr)) {
        ism_cut_free(cut);
        return ism_error_set(err, "out of memory building the curves' arrangement");
    }
    return true;
}
