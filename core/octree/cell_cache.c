/* cell_cache.c — allocation of the per-thread lattice point, segment and tile memos, and their
 * passing from one max_error round to the next. */
#include "core/octree/cell_cache.h"
#include "core/util/zeroed.h"

#include <stdlib.h>
#include <string.h>

bool ism_cell_cache_init(ism_cell_cache *c, ism_pool *pool, ism_par_cost *cost)
{
    /* zeroed by writing (zeroed.h): every lookup reads its slot before it fills it; a cache
     * line start is the lattice entries' alignment */
    c->points = ism_zeroed_alloc(pool, (size_t)1 << ISM_POINT_CACHE_BITS, sizeof *c->points,
                                 cost);
    c->segments = ism_zeroed_alloc(pool, (size_t)1 << ISM_SEGMENT_CACHE_BITS,
                                   sizeof *c->segments, cost);
    c->quiet = ism_zeroed_alloc(pool, (size_t)1 << ISM_QUIET_CACHE_BITS, sizeof *c->quiet, cost);
    c->tiles = ism_zeroed_alloc(pool, (size_t)1 << ISM_TILE_MEMO_BITS, sizeof *c->tiles, cost);
    c->round = 1;
    return c->points && c->segments && c->quiet && c->tiles;
}

void ism_cell_cache_next_round(ism_cell_cache *c)
{
    c->round++;
    memset(c->quiet, 0, ((size_t)1 << ISM_QUIET_CACHE_BITS) * sizeof *c->quiet);
    memset(c->tiles, 0, ((size_t)1 << ISM_TILE_MEMO_BITS) * sizeof *c->tiles);
}

void ism_cell_cache_free(ism_cell_cache *c)
{
    free(c->points);
    free(c->segments);
    free(c->quiet);
    free(c->tiles);
    c->tiles = NULL;
    c->points = NULL;
    c->segments = NULL;
    c->quiet = NULL;
}
