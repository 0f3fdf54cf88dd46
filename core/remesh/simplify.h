/* simplify.h — fewer triangles for the same error (issue 15 item 3): an error-bounded
 * simplification of a finished mesh. Edges are collapsed, shortest first, wherever the mesh
 * after the merge still lies within max_error of f = 0 — measured at every new triangle's
 * centroid and every new edge's midpoint (|f|/|∇f| with a Newton step), the merged vertex put
 * on f = 0 by Newton — and its topology, features, orientation and triangle shape are kept;
 * between rounds of collapses, Lawson flips and tangential relaxation under the same measured
 * bound even the triangles out so the next round can merge more. What the quality pass
 * protects (remesh.h) is protected here too: locked vertices never move or go and locked
 * edges never change. */
#ifndef ISM_SIMPLIFY_H
#define ISM_SIMPLIFY_H

#include "core/remesh/remesh.h"

typedef struct ism_simplify_stats {
    size_t triangles_before, triangles_after;
    size_t collapses, flips, moves;
    size_t rounds;                 /* rounds of collapses run */
    size_t locked_vertices;        /* vertices the pass left where they were */
    double min_angle_before, min_angle_after; /* degrees, over non-degenerate triangles */
    bool stopped;                  /* the cancel flag ended it early (the mesh is valid) */
    double time_ms;
} ism_simplify_stats;

/* Simplifies m in place within o->max_error (required, > 0); o as for the quality pass (f,
 * labels, locked edges and points, cancel). χ, components, non-manifold edges and points,
 * boundary loops and the positions of locked vertices are unchanged; no angle ends below the
 * smaller of the mesh's smallest before and 25°; no triangle turns over. ren (may be NULL) gets
 * the renumbering as ism_remesh_quality's. False with err set when f is missing, max_error is
 * not above 0, or out of memory (m is then still a valid mesh within the bound). */
bool ism_remesh_simplify(ism_mesh *m, const ism_remesh_options *o, ism_simplify_stats *st,
                         ism_remesh_renumber *ren, ism_error *err);

#endif
