/* tolerances.c — the table of the polygoniser's tunable tolerances (tolerances.h) and the
 * three accessors every caller reads and writes them through. */
#include "core/octree/tolerances.h"

#include <math.h>
#include <string.h>

#define TOL_DOUBLE(f) offsetof(ism_poly_options, f), false
#define TOL_INT(f) offsetof(ism_poly_options, f), true

const ism_tolerance ism_tolerances[ISM_TOLERANCE_COUNT] = {
    /* Balsys & Suffern eq. (1): unit gradients at an edge's two ends with a dot product
     * above this lie on one sheet, so an edge whose ends share a sign holds no root; 0.9
     * (about 26°) is the paper's value. */
    {"gradient_test", "gradient", "gradient-test",
     "paper eq. (1): same sheet when ĝa·ĝb > V", TOL_DOUBLE(gradient_test), 0.9, -1, 1},
    /* |f(c)| below this at the bisection's best point is a double (touching) root: close to
     * what doubles resolve for f of order 1 near its zero set. */
    {"double_root_eps", "double_root_eps", "double-root-eps",
     "|f(c)| < V is a double root", TOL_DOUBLE(double_root_eps), 1e-9, 0, 1},
    /* Bisection steps of the two-root search: 25 halvings reach 3e-8 of a segment; past 60
     * a double holds no more bits of the position. */
    {"double_root_iters", "double_root_iters", "double-root-iters",
     "bisection steps for two roots", TOL_INT(double_root_iters), 25, 1, 60},
    /* Two roots on a segment closer than this fraction of it are one double root (paper
     * Fig. 3b); a quarter of the segment is surely two roots. */
    {"stitch_tol", "stitch", "stitch-tol",
     "roots closer than V × segment are one", TOL_DOUBLE(stitch_tol), 1e-3, 1e-9, 0.25},
    /* Flatness: the smallest cosine between corner gradients of a plotting node (26°
     * apart at most by default, the same angle as the edge test). */
    {"flat_normal", "flat_normal", "flat-normal",
     "flatness: corner gradients within acos(V)", TOL_DOUBLE(flat_normal), 0.9, -1, 1},
    /* Flatness: the largest distance of a node's polygon points from their plane, as a
     * fraction of the node size; 0.05 keeps the sphere's centroid error near 2.7e-3 at depth
     * 7 (measured, issue 15). Below 1e-6 no node is ever flat. */
    {"flat_plane", "flat_plane", "flat-plane",
     "flatness: polygon within V × node size of its plane", TOL_DOUBLE(flat_plane), 0.05,
     1e-6, 1},
};

const ism_tolerance *ism_tolerance_by_key(const char *key)
{
    for (int i = 0; i < ISM_TOLERANCE_COUNT; i++)
        if (strcmp(ism_tolerances[i].key, key) == 0)
            return &ism_tolerances[i];
    return NULL;
}

double ism_tolerance_get(const ism_poly_options *o, const ism_tolerance *t)
{
    const char *p = (const char *)o + t->offset;
    if (t->is_int) {
        int v;
        memcpy(&v, p, sizeof v);
        return v;
    }
    double v;
    memcpy(&v, p, sizeof v);
    return v;
}

void ism_tolerance_set(ism_poly_options *o, const ism_tolerance *t, double v)
{
    char *p = (char *)o + t->offset;
    if (t->is_int) {
        int i = (int)v;
        memcpy(p, &i, sizeof i);
    } else
        memcpy(p, &v, sizeof v);
}

bool ism_tolerance_accepts(const ism_tolerance *t, double v)
{
    return isfinite(v) && v >= t->lo && v <= t->hi && (!t->is_int || v == floor(v));
}
