/* quality.h — the triangle-quality pass (quality.c). */
#ifndef ISM_AN_QUALITY_H
#define ISM_AN_QUALITY_H

#include <stdbool.h>
#include "core/mesh/mesh.h"
#include "core/analysis/analysis_types.h"
#include "core/util/pool.h"

/* Smallest angles, degenerate triangles, vertex areas, total area, the triangles measured on
 * the threads of pool (NULL: the calling thread; the figures are the same on any number);
 * false when out of memory. */
bool ism_an_triangle_quality(const ism_mesh *m, ism_pool *pool, ism_analysis *a);

#endif
