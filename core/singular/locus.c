/* locus.c — the singular locus's containers (growable arrays of points, curves, candidate
 * boxes and double sheets) and the names its enums take in JSON and stats. */
#include "core/singular/locus.h"
#include "core/util/clock.h"
#include "core/util/grow.h"
#include "core/util/vec3.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* First capacity of the growable arrays: a locus has a handful of points and curves; 16 covers most without a second realloc. */
#define LOCUS_FIRST 16

/* Default search budget: candidate boxes kept (each ~80 bytes; a double sheet at depth 9
 * keeps a few hundred thousand). */
#define LOCUS_DEFAULT_MAX_BOXES 2000000

void ism_locus_options_default(ism_locus_options *o)
{
    memset(o, 0, sizeof *o);
    for (int k = 0; k < 3; k++) {
        o->box[k] = -1.0;
        o->box[k + 3] = 1.0;
    }
    o->max_depth = ISM_LOCUS_DEFAULT_DEPTH;
    o->max_boxes = LOCUS_DEFAULT_MAX_BOXES;
}

void ism_locus_init(ism_locus *l)
{
    memset(l, 0, sizeof *l);
}

void ism_locus_free(ism_locus *l)
{
    for (size_t i = 0; i < l->ncurves; i++)
        free(l->curves[i].xyz);
    free(l->points);
    free(l->curves);
    free(l->boxes);
    free(l->sheets);
    memset(l, 0, sizeof *l);
}

bool ism_locus_add_point(ism_locus *l, const ism_sing_point *p)
{
    if (!ism_grow((void **)&l->points, &l->cap_points, l->npoints + 1, sizeof *p, LOCUS_FIRST))
        return false;
    l->points[l->npoints++] = *p;
    return true;
}

bool ism_locus_add_curve(ism_locus *l, const ism_sing_curve *c)
{
    if (!ism_grow((void **)&l->curves, &l->cap_curves, l->ncurves + 1, sizeof *c, LOCUS_FIRST))
        return false;
    l->curves[l->ncurves++] = *c;
    return true;
}

bool ism_locus_add_box(ism_locus *l, const ism_lbox *b)
{
    if (!ism_grow((void **)&l->boxes, &l->cap_boxes, l->nboxes + 1, sizeof *b, LOCUS_FIRST))
        return false;
    l->boxes[l->nboxes++] = *b;
    return true;
}

bool ism_locus_add_sheet(ism_locus *l, const ism_double_sheet *s)
{
    if (!ism_grow((void **)&l->sheets, &l->cap_sheets, l->nsheets + 1, sizeof *s, LOCUS_FIRST))
        return false;
    l->sheets[l->nsheets++] = *s;
    return true;
}

bool ism_locus_out_of_time(const ism_locus_options *o, ism_locus *l, const char *during)
{
    bool cancel = o->cancel && *o->cancel;
    if (!cancel && !(o->deadline_ms > 0 && ism_now_ms() > o->deadline_ms))
        return false;
    if (!l->incomplete) {
        l->incomplete = true;
        snprintf(l->incomplete_why, sizeof l->incomplete_why, "%s during %s",
                 cancel ? "cancelled" : "deadline reached", during);
    }
    return true;
}

uint32_t ism_locus_sheet_of(const ism_locus *l, size_t t)
{
    for (size_t i = 0; i < l->nsheets; i++)
        if (t >= l->sheets[i].first_triangle &&
            t - l->sheets[i].first_triangle < l->sheets[i].triangles)
            return (uint32_t)(i + 1);
    return 0;
}

static const char *name_of(const char *const *names, int n, int i)
{
    return i >= 0 && i < n ? names[i] : "unknown";
}

const char *ism_sing_type_name(int type)
{
    static const char *const names[ISM_SING_TYPES] = {"node",       "isolated", "cusp",
                                                      "degenerate", "pinch",    "triple"};
    return name_of(names, ISM_SING_TYPES, type);
}

const char *ism_cert_kind_name(int kind)
{
    static const char *const names[ISM_CERT_KINDS] = {"none",          "krawczyk",
                                                          "deflation",     "rank-0 system",
                                                          "rank-1 system", "A3 system"};
    return name_of(names, ISM_CERT_KINDS, kind);
}

const char *ism_uncert_why_name(int why)
{
    static const char *const names[ISM_UNCERT_WHYS] = {
        NULL,
        "contact of two sheets (Hessian rank 1, the rank-1 system singular): no regular "
        "system defines such a point and double precision places it only to ~1e-5 of f's "
        "scale - not certifiable in principle",
        "rank 2 with vanishing cubic and quartic terms along the null direction (A4 or "
        "worse): the deflated and A3 systems are singular",
        "Krawczyk did not contract on any box up to 1e-9 x diagonal",
        "Hessian 0 and the rank-0 system singular (the Hessian of f's cubic term vanishes "
        "along some direction)",
        "singular curves cross here (Hessian rank 1 where two or more traced branches end): "
        "the rank-1 system is singular where curves cross, so no regular system defines "
        "the point",
        "a closed singular curve too small to trace at this resolution (the Hessian across "
        "it is below the rank threshold): reported as one of its points, radius bounding "
        "the loop"};
    return why > 0 && why < ISM_UNCERT_WHYS ? names[why] : NULL;
}

const char *ism_curve_kind_name(int kind)
{
    static const char *const names[ISM_CURVE_KINDS] = {"double", "whisker"};
    return name_of(names, ISM_CURVE_KINDS, kind);
}

const char *ism_end_type_name(int type)
{
    static const char *const names[ISM_END_TYPES] = {"box", "pinch", "triple", "point", "lost"};
    return name_of(names, ISM_END_TYPES, type);
}

double ism_locus_clearance(const ism_locus *l, size_t i)
{
    const double *p = l->points[i].p;
    double best = INFINITY;
    for (size_t k = 0; k < l->npoints; k++)
        if (k != i)
            best = fmin(best, ism_sqdist3(p, l->points[k].p));
    for (size_t k = 0; k < l->ncurves; k++) {
        const ism_sing_curve *cu = &l->curves[k];
        if (!cu->closed && (cu->end_point[0] == (int)i || cu->end_point[1] == (int)i))
            continue;
        for (size_t j = 0; j < cu->n; j++)
            best = fmin(best, ism_sqdist3(p, cu->xyz + 3 * j));
    }
    return sqrt(best);
}
