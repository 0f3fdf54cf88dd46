/* surface_prefetch.h — before a computation starts on this daemon: the surface's stored
 * computed mesh ("<surface key>.mesh", proto/computed.h), when only Redis has it, is copied
 * into the local tiers, so that the worker encodes it instead of polygonising again. */
#ifndef ISMD_SURFACE_PREFETCH_H
#define ISMD_SURFACE_PREFETCH_H

#include <stdbool.h>

#include "server/common/blob.h"
#include "server/common/cache.h"
#include "server/common/pipeline.h"

/* Redis thread only (redis is the cache's Redis tier): copies the stored computed surface of
 * request (canonical request JSON, keyed under limits) from redis into cache's local tiers
 * unless cache has it already (with copy false, only looks whether Redis has it). Returns 1
 * when the local tiers have it (now; or Redis, not copied), 0 when neither they nor Redis
 * do, -1 for a NULL or unkeyable request or when Redis did not answer. name (when not NULL)
 * gets the surface's entry name, "<surface key>.mesh" ("" for -1 by keying). */
int ismd_prefetch_surface(ism_cache *cache, ism_cache_tier *redis,
                          const ism_pipeline_limits *limits, const ism_blob *request,
                          char *name, bool copy);

#endif
