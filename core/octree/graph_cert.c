/* graph_cert.c — f strictly monotone along one direction over a node (graph_cert.h). */
#include "core/octree/graph_cert.h"
#include "core/eval/interval_ops.h"

#include <math.h>

/* The directional derivative must clear 0 by this fraction of the largest |∇f| the box
 * allows: the enclosure is rounded outward, so a bound of exactly 0 is never proof; a
 * thousandth keeps the surface's slope over the plane across d below 1000 — any finite
 * slope proves the graph, this only keeps rounding out of the verdict. */
#define MIN_SLOPE_FRACTION 1e-3

bool ism_graph_from_enclosure(const ism_ivgrad *g)
{
    double d[3], big = 0;
    for (int a = 0; a < 3; a++) {
        if (!isfinite(g->d[a].lo) || !isfinite(g->d[a].hi))
            return false;
        d[a] = 0.5 * g->d[a].lo + 0.5 * g->d[a].hi;
        big += fmax(fabs(g->d[a].lo), fabs(g->d[a].hi)) * fabs(d[a]);
    }
    /* the enclosure of ∇f · d over the box: each term's interval scaled by d[a] */
    double low = 0, high = 0;
    for (int a = 0; a < 3; a++) {
        double p = g->d[a].lo * d[a], q = g->d[a].hi * d[a];
        low += fmin(p, q);
        high += fmax(p, q);
    }
    double margin = MIN_SLOPE_FRACTION * big;
    return big > 0 && (low > margin || high < -margin);
}

bool ism_graph_certified(const ism_tape *t, ism_ivjet_ws *jet, const double lo[3],
                         const double hi[3], uint64_t *intervals)
{
    if (!jet)
        return false;
    ism_interval box[3];
    for (int a = 0; a < 3; a++)
        box[a] = iv(lo[a], hi[a]);
    ism_ivgrad g;
    (*intervals)++;
    if (ism_eval_interval_grad(t, jet, box, NULL, NULL, &g) != 0)
        return false; /* a kink in the box, or a workspace misfit */
    return ism_graph_from_enclosure(&g);
}
