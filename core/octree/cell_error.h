/* cell_error.h — how far the mesh an octree node would emit lies from the surface, measured
 * before the node is accepted: its edge roots (exact, by regula falsi) joined face by face
 * into polygons, each polygon triangulated as triangulate.c does it (a triangle as is, a
 * quad along its shorter diagonal, a larger polygon fanned from its centre projected onto
 * f = 0), and the first-order distance |f| / |∇f| taken at every triangle's centroid and
 * every edge's midpoint, measured again where it passes the bound (refine.h's
 * ism_sample_dist_between: the corners' bound, then the surface searched for near the point).
 * This is what the max_error criterion of the octree decides on. */
#ifndef ISM_CELL_ERROR_H
#define ISM_CELL_ERROR_H

#include <stdbool.h>
#include "core/octree/corners.h"
#include "core/octree/sampler.h"

/* The largest distance measured on the polygons through the node's edge roots; corners
 * k of the node lo..hi. Returns false (and leaves *err alone) when the roots do not form
 * clean polygons — a face crossed at one or more than two points (a corner exactly on the
 * surface is one root, corners.h's ism_zero_corner_faces) — so that the caller decides by
 * another rule. *err is +inf when f or ∇f is not
 * finite at a measuring point. The measuring stops at the first point beyond bound (*err is
 * then its distance): whether the node meets bound is the same as with every point
 * measured (INFINITY measures them all). shift > 0: the roots are first moved as
 * straddle.h moves vertices (box: the request's). */
bool ism_cell_error(ism_sampler *s, const ism_corners *k, double bound, double shift,
                    const double box[6], double *err);

/* The same with the triangles first split along the crease of f's top min/max, as the
 * polygoniser splits them under an error bound (crease_split.h). Also false when out of
 * memory. */
bool ism_cell_error_cut(ism_sampler *s, const ism_corners *k, double bound, double *err);

#endif
