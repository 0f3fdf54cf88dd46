/* conform_artefacts.c — counting invented structure: the non-manifold edges and points of a
 * mesh (from core/analysis) that lie on no point and no curve of the singular locus. */
#include "core/singular/conform_internal.h"

#include <math.h>
#include <stdlib.h>
#include "core/analysis/analysis.h"

/* Grid cells across the box for the curves' segment grids (only cells within the tolerance
 * of a query are visited, so this bounds memory, not the cost of a query). */
#define ARTEFACT_GRID_CELLS 64.0

typedef struct locus_index {
    const ism_locus *l;
    cf_polyline *pl;
    size_t npl;
} locus_index;

static bool on_locus(const locus_index *x, const double q[3], double tol)
{
    for (size_t i = 0; i < x->l->npoints; i++) {
        const double *p = x->l->points[i].p;
        double d0 = q[0] - p[0], d1 = q[1] - p[1], d2 = q[2] - p[2];
        if (d0 * d0 + d1 * d1 + d2 * d2 <= tol * tol)
            return true;
    }
    for (size_t i = 0; i < x->npl; i++)
        if (x->pl[i].n >= 2 && isfinite(cf_polyline_nearest(&x->pl[i], q, tol, NULL, NULL)))
            return true;
    return false;
}

static bool index_curves(locus_index *x, const ism_locus *l, double step)
{
    x->l = l;
    x->npl = 0;
    x->pl = calloc(l->ncurves + 1, sizeof *x->pl);
    if (!x->pl)
        return false;
    for (size_t i = 0; i < l->ncurves; i++, x->npl++) {
        const ism_sing_curve *cu = &l->curves[i];
        if (cu->n >= 2 && !cf_polyline_init(&x->pl[i], cu->xyz, cu->n, cu->closed, step)) {
            x->npl++;
            return false;
        }
    }
    return true;
}

static void index_free(locus_index *x)
{
    for (size_t i = 0; i < x->npl; i++)
        cf_polyline_free(&x->pl[i]);
    free(x->pl);
}

bool cf_count_artefacts(const ism_mesh *m, const ism_locus *l, double tol, size_t *edges,
                        size_t *verts, ism_error *err)
{
    *edges = *verts = 0;
    ism_analysis_options ao;
    ism_analysis_options_default(&ao);
    ao.curvature = ao.accuracy = false;
    ao.threads = 1;
    ism_analysis a;
    if (!ism_analyse(m, NULL, &ao, &a, err))
        return false;
    double lo[3], hi[3], ext = 1;
    if (ism_mesh_bounds(m, lo, hi))
        ext = fmax(hi[0] - lo[0], fmax(hi[1] - lo[1], fmax(hi[2] - lo[2], 1e-300)));
    locus_index x;
    bool ok = index_curves(&x, l, ext / ARTEFACT_GRID_CELLS);
    for (size_t c = 0; ok && c < a.ncurves; c++)
        for (uint32_t i = a.curve_start[c]; i + 1 < a.curve_start[c + 1]; i++) {
            const double *p = m->pos + 3 * (size_t)a.curve_verts[i],
                         *q = m->pos + 3 * (size_t)a.curve_verts[i + 1];
            double mid[3] = {(p[0] + q[0]) / 2, (p[1] + q[1]) / 2, (p[2] + q[2]) / 2};
            if (!on_locus(&x, mid, tol) || !on_locus(&x, p, tol) || !on_locus(&x, q, tol))
                (*edges)++;
        }
    for (size_t v = 0; ok && v < a.nverts; v++)
        if (a.vertex_class[v] == ISM_VERTEX_NONMANIFOLD_POINT && !on_locus(&x, m->pos + 3 * v, tol))
            (*verts)++;
    index_free(&x);
    ism_analysis_free(&a);
    if (!ok)
        return ism_error_set(err, "out of memory indexing the locus's curves");
    return true;
}
