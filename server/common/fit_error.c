/* fit_error.c — the max_error that fits the triangle budget (contract in fit_error.h).
 *
 * Under a bound the mesher's cells shrink until their triangles lie within E of the surface;
 * a smooth patch's chord error goes as curvature x h^2, so h^2 ~ E and the triangle count
 * goes as area / h^2 ~ 1 / E. The aborted pass only knows that N(E) > budget (it stops at
 * the first chunk over it), so coarse passes find an E_c whose mesh fits, and the law carries
 * its count N_c to the budget: E_fit = E_c x N_c / budget x ISM_FIT_SAFETY. That E_fit is
 * then meshed once more (and the bracket between what fits and what does not is halved in log
 * a few times when the law missed), so the number suggested is one the same pass was seen to
 * serve.
 * Every pass is itself stopped at the budget, so the search costs a few budget-sized meshes
 * at most. */
#include "server/common/fit_error.h"

#include "core/singular/surface.h"
#include "core/util/vec3.h"
#include "proto/request.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

/* The coarse passes' step: one pass 4x coarser holds about 4x fewer triangles, so the
 * first one fits unless E was more than 4x too fine, and at most a few are needed. */
#define ISM_FIT_STEP 4.0
/* Enough steps to go from the smallest E a request may ask (1e-9 of the diagonal) to the
 * diagonal (4^15 = 1.07e9). */
#define ISM_FIT_STEPS 15
/* The 1/E law is a smooth-patch law: the singular locus's tubes, depth.min and the cells
 * that stop at depth.max do not follow it, and cells come in powers of two. 1.25 leaves a
 * quarter of the budget to those, and the estimate is checked by meshing it anyway. */
#define ISM_FIT_SAFETY 1.25

/* Refinement passes after the coarse ones, and the ratio between the smallest E seen to fit
 * and the largest seen not to at which they stop: the answer is then within 1.5x of the
 * smallest E that fits (the issue asks for within 4x); 3 passes take a ratio of 4 (one
 * coarse step) to 4^(1/8) = 1.19 at most. */
#define ISM_FIT_TRIES 3
#define ISM_FIT_RATIO 1.5

enum fit { FIT_OK, FIT_TOO_BIG, FIT_FAILED };

/* Meshes f under the bound e; *ntris the count when it fits. */
static enum fit try_error(const ism_tape *f, const ism_poly_options *po, bool preview,
                          double e, size_t *ntris)
{
    ism_poly_options o = *po;
    o.max_error = e;
    o.progress = NULL; /* the request's progress bar has finished with the aborted pass */
    ism_mesh mesh;
    ism_mesh_init(&mesh);
    ism_poly_stats ps;
    memset(&ps, 0, sizeof ps);
    ism_error err;
    memset(&err, 0, sizeof err);
    enum ism_poly_status st;
    if (preview) {
        st = ism_polygonise(f, &o, &mesh, &ps, &err);
    } else {
        ism_locus locus;
        ism_locus_init(&locus);
        ism_conform_stats cs;
        memset(&cs, 0, sizeof cs);
        ism_surface_times times;
        st = ism_mesh_surface(f, &o, &mesh, &locus, &ps, &cs, &times, &err);
        ism_locus_free(&locus);
    }
    *ntris = mesh.ntris;
    ism_mesh_free(&mesh);
    return st == ISM_POLY_OK ? FIT_OK : st == ISM_POLY_TOO_BIG ? FIT_TOO_BIG : FIT_FAILED;
}

/* e rounded up to three significant digits, as the message and the JSON show it. */
static double shown(double e)
{
    char buf[32];
    return strtod(ism_three_digits(e, 1, buf), NULL);
}

double ism_fit_error(const ism_tape *f, const ism_poly_options *po, bool preview)
{
    if (!(po->max_error > 0) || !(po->max_triangles > 0))
        return 0;
    double diag = ism_box_diagonal(po->box);
    double fits = 0;                /* the smallest E seen to fit */
    double over = po->max_error;    /* the largest E seen not to */
    size_t n = 0;
    double e = po->max_error;
    for (int i = 0; i < ISM_FIT_STEPS && !fits; i++) {
        e = shown(fmin(e * ISM_FIT_STEP, diag));
        if (e > diag) /* rounded up past the largest E a request may ask */
            e = strtod(ism_three_digits(diag, -1, (char[32]){0}), NULL);
        enum fit r = try_error(f, po, preview, e, &n);
        if (r == FIT_FAILED)
            return 0;
        if (r == FIT_OK)
            fits = e;
        else if (e >= diag * (1 - 1e-3)) /* the diagonal itself does not fit */
            return 0;
        else
            over = e;
    }
    if (!fits)
        return 0;
    /* the law's estimate, then halving the ratio fits / over (in log) while it is above
     * ISM_FIT_RATIO: the count moves in steps (cells halve), so the law alone can land just
     * under a step */
    double next = shown(fits * (double)n / (double)po->max_triangles * ISM_FIT_SAFETY);
    for (int i = 0; i < ISM_FIT_TRIES && fits / over > ISM_FIT_RATIO; i++) {
        if (!(next > over && next < fits))
            next = shown(sqrt(fits * over));
        if (!(next > over && next < fits))
            break;
        size_t m;
        enum fit r = try_error(f, po, preview, next, &m);
        if (r == FIT_FAILED)
            break; /* cancelled or out of memory: fits was still seen to fit */
        if (r == FIT_OK)
            fits = next;
        else
            over = next;
        next = 0;
    }
    return fits;
}
