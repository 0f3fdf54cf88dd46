/* locus.c — the singular locus's containers (growable arrays of points, curves, candidate
 * boxes and double sheets) and the names its enums take in JSON and stats. */
#include "core/singular/locus.h"

#include <stdlib.h>
#include <string.h>

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
    o->max_depth = 7;
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

/* Makes room for one more element of size sz in *v (n used, *cap allocated). */
static bool grow(void **v, size_t n, size_t *cap, size_t sz)
{
    if (n < *cap)
        return true;
    size_t c = *cap ? 2 * *cap : 16;
    void *p = realloc(*v, c * sz);
    if (!p)
        return false;
    *v = p;
    *cap = c;
    return true;
}

bool ism_locus_add_point(ism_locus *l, const ism_sing_point *p)
{
    if (!grow((void **)&l->points, l->npoints, &l->cap_points, sizeof *p))
        return false;
    l->points[l->npoints++] = *p;
    return true;
}

bool ism_locus_add_curve(ism_locus *l, const ism_sing_curve *c)
{
    if (!grow((void **)&l->curves, l->ncurves, &l->cap_curves, sizeof *c))
        return false;
    l->curves[l->ncurves++] = *c;
    return true;
}

bool ism_locus_add_box(ism_locus *l, const ism_lbox *b)
{
    if (!grow((void **)&l->boxes, l->nboxes, &l->cap_boxes, sizeof *b))
        return false;
    l->boxes[l->nboxes++] = *b;
    return true;
}

bool ism_locus_add_sheet(ism_locus *l, const ism_double_sheet *s)
{
    if (!grow((void **)&l->sheets, l->nsheets, &l->cap_sheets, sizeof *s))
        return false;
    l->sheets[l->nsheets++] = *s;
    return true;
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
