/* singular.h — isolated singular points of the surface inside a node (f = 0 and ∇f = 0 with
 * a non-degenerate Hessian: the nodes of Kummer's surfaces, cone apexes). Where the paper
 * leaves two separate caps of the two cones in such a node, the polygoniser fans every
 * polygon of the node from the singular point, so the cones meet there in one vertex: a
 * non-manifold point the analysis can find. */
#ifndef ISM_SINGULAR_H
#define ISM_SINGULAR_H

#include <stdbool.h>
#include "core/octree/cell.h"

/* Newton on ∇f = 0 from the centre of the box lo..hi. True, with the point in *s, when it
 * converges strictly inside the box to a point of f = 0 whose Hessian is non-degenerate
 * and indefinite (two cones meet there). */
bool ism_find_singular_point(ism_sampler *smp, const double lo[3], const double hi[3],
                             ism_fpoint *s);

/* The same on the lattice plane through start perpendicular to `axis` (start[axis] stays
 * as it is, exactly): Newton on the in-plane gradient from start; accepted strictly inside
 * the rectangle lo..hi (in the plane's two other axes, in order (axis+1)%3, (axis+2)%3),
 * with the full gradient vanishing and the Hessian non-degenerate and indefinite. */
bool ism_find_singular_point_on_plane(ism_sampler *smp, int axis, const double start[3],
                                      const double lo[2], const double hi[2], ism_fpoint *s);

/* Two crossing lines on a tile whose crossing is no singular point: where f restricted to the
 * plane has its critical point (Newton from start, strictly inside lo..hi) f does not vanish,
 * but the Hessian there is a cone's — a cone's apex lies close to the plane, off it, and the
 * plane cuts the cone in a hyperbola, not in two lines. Returns the sign of f at that point
 * (the region of that sign runs between the hyperbola's branches), or 0 when this is not the
 * case (a double line crossing the plane has a degenerate Hessian). */
int ism_apex_off_plane_sign(ism_sampler *smp, int axis, const double start[3],
                            const double lo[2], const double hi[2]);

#endif
