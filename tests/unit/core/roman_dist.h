/* roman_dist.h — the distance to the zero set of Steiner's Roman surface
 * f = x²y² + y²z² + z²x² + xyz (roman_dist.c), found from its parametrisation, not from f: a
 * second method for the tests that check a distance the analysis measures from f. */
#ifndef TESTS_UNIT_CORE_ROMAN_DIST_H
#define TESTS_UNIT_CORE_ROMAN_DIST_H

typedef struct roman_dist roman_dist;

/* The search's samples of the surface (a few MB); NULL when out of memory. */
roman_dist *roman_dist_new(void);
void roman_dist_free(roman_dist *r);

/* The distance from q to f = 0: the nearest point of the image of the unit sphere under
 * (u, v, w) -> (−vw, uw, uv) (the surface, double curves and pinch points included) or of
 * the three coordinate axes (f = 0 on them beyond the pinch points too). q within 0.01 of
 * the surface (asserted: farther the sample neighbourhood searched is too small). */
double roman_dist_at(const roman_dist *r, const double q[3]);

#endif
