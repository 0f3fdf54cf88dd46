/* sp_place.h — where a vertex of the simplified mesh sits (sp_place.c): off the surface by
 * the offset along ∇f that best balances the signed errors around it. A mesh whose vertices
 * all lie on f = 0 has its chords and triangles on one side of a convex surface, the whole
 * bound spent on that side: the fewest such triangles on a sphere within E are 0.35 of
 * marching cubes' (equilateral, centroids exactly E deep). Vertices lifted by about E/2 put
 * the centroids E/2 the other way: twice the area per triangle within the same E, the vertex
 * itself measured like every other point. */
#ifndef ISM_SP_PLACE_H
#define ISM_SP_PLACE_H

#include "core/remesh/rm_pass.h"

/* A point measured around a moving vertex x: x itself (a = b = NULL), the midpoint of x and a
 * (b = NULL), or the centroid of x, a and b. */
typedef struct sp_stencil {
    const double *a, *b;
} sp_stencil;

/* At most this many stencils in a fan: a centroid per triangle, a midpoint per neighbour
 * (at most one more than the triangles) and the vertex. */
#define SP_MAX_STENCILS 80

/* The stencils of triangles fan[0..n) around the moving point (corners v and w; v == w for
 * one vertex): each centroid, each distinct edge at the point, and the point. Returns how
 * many (at most SP_MAX_STENCILS; 0 when there would be more). */
int sp_stencils(const rm_pass *p, const uint32_t *fan, uint32_t n, uint32_t v, uint32_t w,
                sp_stencil *s);

/* Moves x along ∇f's unit vector to the offset that minimises the largest |signed distance|
 * over the stencils (a linear model in the offset: a stencil's point moves by its weight, 1,
 * 1/2 or 1/3, of the offset); *before gets the model's largest distance at x before the
 * move, g ∇f at the new x. False when f cannot be measured at some stencil or at the new
 * x, or when the model's best is clearly above limit (nothing measured then). The caller
 * measures the new place with sp_measure. */
bool sp_place(rm_pass *p, const sp_stencil *s, int n, double limit, double x[3], double g[3],
              double *before);

/* The largest distance (rm_bound_distance) over the stencils with the moving point at x —
 * or, as soon as one measures above stop, that one (the caller's test has failed then; the
 * rest are not measured). INFINITY where f cannot be measured. */
double sp_measure(rm_pass *p, const sp_stencil *s, int n, const double x[3], double stop);

/* Moves free vertex v to its balancing offset when that lowers the largest distance of its
 * fan and keeps the fan's shape (rm_fan_accepts); true when it moved. */
bool sp_offset_vertex(rm_pass *p, uint32_t v);

#endif
