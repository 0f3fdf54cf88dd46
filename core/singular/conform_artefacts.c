/* conform_artefacts.c — counting invented structure after the pass: the non-manifold edges
 * and points of the mesh (core/analysis) that lie on no point and no curve of the singular
 * locus, by the same rule the pipeline's check applies (core/singular/check.h). */
#include "core/singular/conform_internal.h"

#include "core/analysis/analysis.h"
#include "core/singular/check.h"

bool cf_count_artefacts(const ism_mesh *m, const ism_locus *l, const double box[6],
                        size_t *edges, size_t *verts, ism_error *err)
{
    *edges = *verts = 0;
    ism_analysis_options ao;
    ism_analysis_options_default(&ao);
    ao.curvature = ao.accuracy = false;
    ao.threads = 1;
    ism_analysis a;
    if (!ism_analyse(m, NULL, &ao, &a, err))
        return false;
    ism_locus_check chk;
    bool ok = ism_locus_check_mesh(l, box, m, &a, &chk, err);
    if (ok) {
        *edges = chk.nonmanifold_edges_off;
        *verts = chk.nonmanifold_points_off;
        ism_locus_check_free(&chk);
    }
    ism_analysis_free(&a);
    return ok;
}
