/* cell_cache.c — allocation of the per-thread lattice point and segment memos. */
#include "core/octree/cell_cache.h"

#include <stdlib.h>

bool ism_cell_cache_init(ism_cell_cache *c)
{
    c->points = calloc((size_t)1 << ISM_POINT_CACHE_BITS, sizeof *c->points);
    c->segments = calloc((size_t)1 << ISM_SEGMENT_CACHE_BITS, sizeof *c->segments);
    return c->points && c->segments;
}

void ism_cell_cache_free(ism_cell_cache *c)
{
    free(c->points);
    free(c->segments);
    c->points = NULL;
    c->segments = NULL;
}
