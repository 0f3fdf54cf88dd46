/* curve_tracer.h — what the curve stage's tracing shares (curve_trace.c walks a path,
 * curve_events.c handles its ends and marks): the tracer's state, and where a point lies
 * against the box. */
#ifndef ISM_CURVE_TRACER_H
#define ISM_CURVE_TRACER_H

#include <stdbool.h>
#include <stddef.h>
#include "core/singular/curve_index.h"
#include "core/singular/curve_jet.h"
#include "core/singular/locus.h"

/* Everything one call of the curve stage shares. */
typedef struct ism_ctracer {
    ism_cjet jet;
    ism_cindex idx;
    ism_locus *io;
    const ism_locus_options *o;
    double box[6];
    double diag;        /* box diagonal */
    double cell;        /* finest search cell: smallest box side / 2^max_depth */
    double hmax, hmin;  /* step bounds */
    double delta;       /* a box is explained by a segment passing this close to its q */
    double snap;        /* a path ends at an existing point it passes this close to */
    size_t vertices_left, attempts_left;
    unsigned polls;
    bool stop;          /* budget, deadline or cancel: no more tracing */
    bool oom;
    const char *why;    /* reason for stop */
} ism_ctracer;

/* Whether p is in the box, up to Newton's tolerance (a curve lying in a face of the box, as
 * the axes of xyz = 0 in [0, 1]³, stays inside). */
bool ism_ctracer_inside(const ism_ctracer *tr, const double p[3]);

/* -1 / +1 when coordinate k of a point, v, is beyond the box's low / high face (with the
 * same tolerance), else 0. */
int ism_ctracer_side(const ism_ctracer *tr, int k, double v);

#endif
