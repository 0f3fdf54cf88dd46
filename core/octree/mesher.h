/* mesher.h — which mesher made a mesh under the polygoniser's options, and when it was not the
 * dual one (dual.h), why: the one table of reasons. The stats (proto/stats.c), the API's
 * documentation (proto/openapi.yaml) and the viewer name a reason by the table's name; the
 * policy that decides the reasons known before meshing (no bound, asked not to, a singular
 * locus, min/max of f) lives here too, so the dual mesher's own check and the stats cannot
 * disagree. */
#ifndef ISM_MESHER_H
#define ISM_MESHER_H

#include <stdbool.h>
#include "core/eval/eval.h"
#include "core/octree/poly_options.h"

enum ism_mesher {
    ISM_MESHER_PRIMAL,   /* the octree's polygons, vertices on cell edges (polygonise.h) */
    ISM_MESHER_STRADDLE, /* the same with vertices moved to straddle the surface (straddle.h) */
    ISM_MESHER_DUAL,     /* one vertex per leaf, quads across crossed edges (dual.h) */
    ISM_MESHER_COUNT
};

/* Why the dual mesher did not make the mesh. In the order they are decided: the first four
 * (and POINT_TYPE, in LOCUS's place) before any meshing (ism_dual_declined_before), the
 * others by the dual mesher itself, which then gives the mesh back to the primal polygons. */
enum ism_dual_reason {
    ISM_DUAL_WHY_NONE = 0,     /* it did: the mesh is the dual one */
    ISM_DUAL_WHY_NO_BOUND,     /* no max_error: the dual cells are sized by the bound */
    ISM_DUAL_WHY_OFF,          /* asked not to ("dual": false, --no-dual) */
    ISM_DUAL_WHY_LOCUS,        /* singular points or curves known from f: they need the primal
                                  polygons' conformance (core/singular) */
    ISM_DUAL_WHY_MIN_MAX,      /* min/max/abs in f: creases, which one vertex per cell rounds
                                  (with o->dual_crease, one min/max at f's top is followed,
                                  dual_crease.h: then its crease not followed at depth.max) */
    ISM_DUAL_WHY_BOX_CUT,      /* the box cuts the surface where the clip cannot apply
                                  (dual_box.h): singular points too, a cut point not settled
                                  onto f = 0 in its plane, a margin leaf's vertex inside */
    ISM_DUAL_WHY_NOT_PLAIN,    /* a cell at depth.max still holds more than one plain sheet
                                  (sheets closer than a cell, an uncertified singular point) */
    ISM_DUAL_WHY_ERROR,        /* a triangle beyond max_error with its cells at depth.max */
    ISM_DUAL_WHY_OPEN_EDGE,    /* a crossed edge without its cells' vertices (not expected:
                                  never a hole) */
    ISM_DUAL_WHY_POINT_TYPE,   /* the locus is points only, but one is not a certified node
                                  or isolated point (a cusp ...): no apex fan for it */
    ISM_DUAL_WHY_POINT_FAN,    /* round a node the ball's sphere did not cut two rim loops,
                                  or a fan triangle stayed beyond max_error at the smallest
                                  ball (dual_balls.h) */
    ISM_DUAL_WHY_COUNT
};

/* The names the stats write ("primal", "straddle", "dual"; "no_bound", "off", ...) and a
 * sentence for readers; NULL / "" outside the enums. */
const char *ism_mesher_name(enum ism_mesher m);
const char *ism_dual_reason_name(enum ism_dual_reason r);
const char *ism_dual_reason_text(enum ism_dual_reason r);

/* The reason known before meshing why f under o does not get the dual mesh (options and
 * tape only), or ISM_DUAL_WHY_NONE when the dual mesher may try. */
enum ism_dual_reason ism_dual_declined_before(const ism_tape *f, const ism_poly_options *o);

/* Does the simplification run after meshing? One policy for every mesher: only when asked
 * ("simplify": true, --simplify) and under an error bound (0: none, never). The mesh any
 * mesher makes under max_error is already within it; the default is that mesh, the cheap one.
 * Simplifying costs 1.3-6.7 times a dual mesh's meshing (callgrind, sphere and torus at
 * 1e-2..1e-3: README, "Under an error bound") and 1.0-1.5 times the primal polygons' CPU
 * (Klein bottle 1e-2, Barth's sextic 3e-3: bench_error mesh S E 10 simplify) for 0.14-0.40
 * of the triangles: asking for E and the fewest triangles is asking for "simplify" too. */
bool ism_simplify_after(bool asked, double max_error);

#endif
