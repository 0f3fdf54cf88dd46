/* singular.h — isolated singular points of the surface inside a node (f = 0 and ∇f = 0 with
 * a non-degenerate Hessian: the nodes of Kummer's surfaces, cone apexes). Where the paper
 * leaves two separate caps of the two cones in such a node, the polygoniser fans every
 * polygon of the node from the singular point, so the cones meet there in one vertex: a
 * non-manifold point the analysis can find. */
#ifndef ISM_SINGULAR_H
#define ISM_SINGULAR_H

#include <stdbool.h>
#include "core/octree/cell_types.h"
#include "core/octree/sampler.h"

/* Newton on ∇f = 0 from the centre of the box lo..hi. True, with the point in *s, when it
 * converges strictly inside the box to a point of f = 0 whose Hessian is non-degenerate
 * and indefinite (two cones meet there). */
bool ism_find_singular_point(ism_sampler *smp, const double lo[3], const double hi[3],
                             ism_fpoint *s);

/* Where two crossing lines meet on a tile (start), on the lattice plane through start
 * perpendicular to `axis` (start[axis] stays as it is, exactly): Newton on the in-plane
 * gradient to f's critical point on the plane, strictly inside the rectangle lo..hi (in the
 * plane's two other axes, in order (axis+1)%3, (axis+2)%3). Returns
 *   ISM_PLANE_APEX, with the point in *s, when it is a singular point of the surface (full
 *     gradient vanishing, Hessian non-degenerate and indefinite: a cone's apex in the face,
 *     where the four lines meet);
 *   +1 or -1, the sign of f there, when f does not vanish but the Hessian is a cone's: the
 *     apex lies just off the plane, which cuts the cone in a hyperbola, not in two lines —
 *     the region of that sign runs between its branches;
 *   0 otherwise (two sheets crossing along a double line, whose Hessian is degenerate, or no
 *     critical point in the rectangle). */
#define ISM_PLANE_APEX 2
int ism_plane_crossing(ism_sampler *smp, int axis, const double start[3], const double lo[2],
                       const double hi[2], ism_fpoint *s);

#endif
