/* quiet.h — the balls where the octree does not chase hidden pieces (ism_poly_options.quiet:
 * around the singular locus, whose mesh the conformance pass rebuilds) and, under max_error,
 * does not split nodes they hold (octree_build.c conformed), indexed in a uniform grid of
 * cells as large as the largest radius (ball_grid.h), so a query reads a few cells around the
 * box whatever the number of balls. */
#ifndef ISM_QUIET_H
#define ISM_QUIET_H

#include <stdbool.h>
#include <stddef.h>
#include "core/octree/ball_grid.h"

typedef struct ism_quiet {
    const double (*ball)[4]; /* x, y, z, radius (not owned) */
    ism_ball_grid grid;
} ism_quiet;

/* Indexes n balls (kept by the caller while q is used). False when memory ran out. */
bool ism_quiet_init(ism_quiet *q, const double (*ball)[4], size_t n);
void ism_quiet_free(ism_quiet *q);

/* Does the box lo..hi lie inside one of the balls? */
bool ism_quiet_holds(const ism_quiet *q, const double lo[3], const double hi[3]);

/* Does the box lo..hi meet one of the balls (the nearest point of the box inside it) or come
 * within `reach` (>= 0) of a ball's centre? */
bool ism_quiet_near(const ism_quiet *q, const double lo[3], const double hi[3], double reach);

#endif
