/* curve_trace.h — tracing one singular curve in one direction from a point on it: predictor
 * along the tangent, Newton's corrector in the plane normal to it, an adaptive step, and the
 * events that end or mark the path — the box's face (clipped exactly), a pinch point (the
 * normal-plane Hessian changes sign of determinant: located and recorded, the path goes on),
 * a collapse of the Hessian (a triple or degenerate point), an existing singular point, the
 * start again (a loop), or no convergence / budget / deadline. */
#ifndef ISM_CURVE_TRACE_H
#define ISM_CURVE_TRACE_H

#include <stdbool.h>
#include <stddef.h>
#include "core/singular/curve_index.h"
#include "core/singular/curve_jet.h"
#include "core/singular/locus.h"

/* A vertex of a traced path: point index ≥ 0 when it is a pinch point (the curve changes
 * kind there). */
typedef struct ism_cvert {
    double p[3];
    double D;     /* determinant of the normal-plane Hessian: < 0 double, > 0 whisker */
    int point;    /* index into ism_locus.points, or -1 */
} ism_cvert;

/* One direction of a trace. */
typedef struct ism_cpath {
    ism_cvert *v;
    size_t n, cap;
    int end_type;   /* ISM_END_BOX, ISM_END_POINT (at end_point: typed later) or ISM_END_LOST */
    int end_point;  /* index into ism_locus.points, or -1 */
    bool closed;    /* came back to its first vertex (not repeated) */
} ism_cpath;

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

/* Traces from start (a converged curve point whose frame points the way to go) until an
 * end, appending vertices to path (start first). closable: watch for a return to start.
 * ignore_point: a point of the locus not to end at (-1 for none). Boxes the path explains
 * are marked ISM_LBOX_USED; pinch and collapse points found are added to tr->io->points.
 * Sets tr->oom when out of memory, tr->stop when the budget or deadline ran out. */
void ism_ctrace(ism_ctracer *tr, const ism_cpoint *start, int ignore_point, bool closable,
                ism_cpath *path);

/* Spends one unit of work (a step attempt, a seed): false, and tr->stop set with a reason,
 * when the budget is spent, the deadline passed or the caller cancelled. */
bool ism_ctracer_go(ism_ctracer *tr);

/* Whether p is in the box, up to Newton's tolerance (a curve lying in a face of the box, as
 * the axes of xyz = 0 in [0, 1]³, stays inside). */
bool ism_ctracer_inside(const ism_ctracer *tr, const double p[3]);

/* -1 / +1 when coordinate k of a point, v, is beyond the box's low / high face (with the
 * same tolerance), else 0. */
int ism_ctracer_side(const ism_ctracer *tr, int k, double v);

#endif
