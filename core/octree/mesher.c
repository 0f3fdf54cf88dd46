/* mesher.c — the meshers' and the dual mesher's reasons' names (mesher.h), and the reasons
 * decided before meshing. */
#include "core/octree/mesher.h"

#include <stddef.h>

static const char *const mesher_names[ISM_MESHER_COUNT] = {"primal", "straddle", "dual"};

static const struct {
    const char *name, *text;
} reasons[ISM_DUAL_WHY_COUNT] = {
    [ISM_DUAL_WHY_NONE] = {"", "the dual mesh was made"},
    [ISM_DUAL_WHY_NO_BOUND] = {"no_bound", "no max_error: the dual cells are sized by it"},
    [ISM_DUAL_WHY_OFF] = {"off", "asked for the primal polygons (dual: false)"},
    [ISM_DUAL_WHY_LOCUS] = {"singular_locus",
                            "singular points or curves: the primal polygons conform to them"},
    [ISM_DUAL_WHY_MIN_MAX] = {"min_max", "min/max/abs in f: creases one vertex per cell rounds"},
    [ISM_DUAL_WHY_BOX_CUT] = {"box_cut", "the box cuts the surface and the clip at its faces "
                                         "failed (or depth.max leaves no level for the "
                                         "margin)"},
    [ISM_DUAL_WHY_NOT_PLAIN] = {"not_plain", "a cell at depth.max holds more than one plain "
                                             "sheet (close sheets or a singular point)"},
    [ISM_DUAL_WHY_ERROR] = {"error_at_max_depth",
                            "a triangle beyond max_error with its cells at depth.max"},
    [ISM_DUAL_WHY_OPEN_EDGE] = {"open_edge", "a crossed edge without its cells' vertices"},
    [ISM_DUAL_WHY_POINT_TYPE] = {"point_type", "a singular point that is not a certified node "
                                               "or isolated point (a cusp ...)"},
    [ISM_DUAL_WHY_POINT_FAN] = {"point_fan", "no two rim loops round a node, or its apex fan "
                                             "beyond max_error at the smallest ball"},
};

const char *ism_mesher_name(enum ism_mesher m)
{
    return (unsigned)m < ISM_MESHER_COUNT ? mesher_names[m] : NULL;
}

const char *ism_dual_reason_name(enum ism_dual_reason r)
{
    return (unsigned)r < ISM_DUAL_WHY_COUNT ? reasons[r].name : NULL;
}

const char *ism_dual_reason_text(enum ism_dual_reason r)
{
    return (unsigned)r < ISM_DUAL_WHY_COUNT ? reasons[r].text : "";
}

enum ism_dual_reason ism_dual_declined_before(const ism_tape *f, const ism_poly_options *o)
{
    if (!(o->max_error > 0))
        return ISM_DUAL_WHY_NO_BOUND;
    if (!o->dual)
        return ISM_DUAL_WHY_OFF;
    if (o->dual_points_other)
        return ISM_DUAL_WHY_POINT_TYPE;
    /* a locus of nodes and isolated points only is meshed round (dual_balls.h) */
    if ((o->nquiet || o->nnode_balls) && !o->ndual_points)
        return ISM_DUAL_WHY_LOCUS;
    /* one min/max at f's top is a crease the dual mesher can follow when asked
       (dual_crease.h) */
    if (ism_tape_has_min_max(f) && !(o->dual_crease && ism_tape_top_min_max_only(f)))
        return ISM_DUAL_WHY_MIN_MAX;
    return ISM_DUAL_WHY_NONE;
}

bool ism_simplify_after(bool asked, double max_error)
{
    return asked && max_error > 0;
}
