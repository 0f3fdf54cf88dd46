/* analysis.h — what a mesh says about its surface: manifold / boundary / non-manifold edges
 * and vertices (cones of faces, Pérez-Aquila & Aguilera 2003), non-manifold curves and points,
 * topology, curvature from the implicit function, triangle quality and distance to f = 0.
 * The calls are here; the data they fill is in analysis_types.h.
 *
 * Conventions (all of them deterministic: the same mesh and options give the same analysis,
 * whatever the number of threads, including the order of curves, points and components):
 * - A triangle with a repeated vertex index is "collapsed": it has no edges, takes no part in
 *   the topology or the cones of faces, and is counted in collapsed_triangles (and in
 *   degenerate_triangles).
 * - Edges are the distinct unordered vertex pairs of the other triangles, numbered in order
 *   of (smaller index, larger index).
 * - Cost: O(T + V) for the edge table (bucketed by smaller vertex, each bucket sorted;
 *   O(T log T) only for a vertex of huge degree), near-linear union-find for cones and
 *   components, one Hessian (curvature) or gradient (accuracy) evaluation per vertex plus
 *   Newton steps and one gradient per triangle centroid, spread over threads. Memory at the
 *   peak about 14 bytes per half-edge and 40 per vertex besides the outputs: about twice the
 *   mesh's own size. Measured by tests/bench/analysis_torus.c on a 1M-triangle torus grid:
 *   ~0.2 s for connectivity and quality, ~0.1 s more (one thread) for a quartic's curvature
 *   and distances. */
#ifndef ISM_ANALYSIS_H
#define ISM_ANALYSIS_H

#include <stddef.h>
#include <stdint.h>
#include <stdbool.h>
#include "core/mesh/mesh.h"
#include "core/expr/expr.h"
#include "core/analysis/analysis_types.h"
#include "core/analysis/options.h"
#include "core/analysis/curvature.h"
#include "core/analysis/project.h"

/* Analyses m. f may be NULL (then curvature and accuracy are skipped); o may be NULL for
 * the defaults. Returns false on bad input (a vertex index out of range, a non-finite or
 * absurdly large coordinate, more than 2^32-2 vertices or 1.4e9 triangles) or allocation
 * failure (err says which); a is then empty. a must be released with ism_analysis_free. */
bool ism_analyse(const ism_mesh *m, const ism_tape *f, const ism_analysis_options *o,
                 ism_analysis *a, ism_error *err);

void ism_analysis_free(ism_analysis *a);

#endif
