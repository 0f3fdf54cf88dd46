/* cache_mem.h — the memory tier: a least-recently-used map from entry name to blob, bounded in
 * bytes (entry bytes plus a small per-entry overhead). Thread-safe; lookups are O(1). */
#ifndef ISM_CACHE_MEM_H
#define ISM_CACHE_MEM_H

#include <stddef.h>

#include "server/common/cache.h"

/* A tier holding at most capacity bytes. An entry larger than half the capacity is never kept
 * (one huge mesh must not flush everything else). NULL when out of memory. */
ism_cache_tier *ism_cache_mem_new(size_t capacity);

#endif
