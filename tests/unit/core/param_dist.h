/* param_dist.h — the distance to the zero set of a surface known by a parametrisation
 * (param_dist.c), found from it, not from f: a second method for the tests that check a
 * distance the polygoniser or the analysis measures from f. Three pinch-point surfaces:
 *   Steiner's Roman surface x²y² + y²z² + z²x² + xyz = 0: S(u, v, w) = (−vw, uw, uv) on the
 *     unit sphere, and the three coordinate axes (f = 0 on them beyond the pinch points ±½);
 *   the cross-cap 4x²(x² + y² + z² + z) + y²(y² + z² − 1) = 0: S(a, b, c) = (ab, 2ac, c² − a²)
 *     on the unit sphere (f(S) = 0 expands to 0 with a² + b² + c² = 1), and the z axis
 *     (f = 0 on it beyond the pinch points (0, 0, 0) and (0, 0, 1));
 *   the Whitney umbrella x² − y²z = 0: S(u, v) = (uv, v, u²) on the plane (|u|, |v| ≤ 1.1:
 *     the box ±1 and a margin), and the z axis (the whisker z < 0). */
#ifndef TESTS_UNIT_CORE_PARAM_DIST_H
#define TESTS_UNIT_CORE_PARAM_DIST_H

typedef enum { PARAM_STEINER, PARAM_CROSS_CAP, PARAM_WHITNEY } param_surface;

typedef struct param_dist param_dist;

/* The search's samples of the surface (a few MB); NULL when out of memory. */
param_dist *param_dist_new(param_surface which);
void param_dist_free(param_dist *r);

/* The distance from q to f = 0: the nearest point of the parametrised image (double curves
 * and pinch points included) or of the surface's axes. q within PARAM_DIST_REACH of the
 * surface (asserted: farther the sample neighbourhood searched is too small). */
#define PARAM_DIST_REACH 0.01
double param_dist_at(const param_dist *r, const double q[3]);

/* An upper bound of param_dist_at, cheaper: the nearest point one search from the nearest
 * sample reaches (or an axis). Where it is at most some figure the distance is too; where
 * it is larger param_dist_at says how much. */
double param_dist_upper(const param_dist *r, const double q[3]);

#endif
