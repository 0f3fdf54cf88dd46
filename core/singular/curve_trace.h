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
#include "core/singular/curve_tracer.h"

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

#endif
