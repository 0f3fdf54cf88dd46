/* surface_prefetch.c — the copy of surface_prefetch.h: key the request, look in the local
 * tiers, fetch from Redis. */
#include "server/isomeshd/surface_prefetch.h"

#include "proto/computed.h"
#include "server/common/cache_redis.h"

int ismd_prefetch_surface(ism_cache *cache, ism_cache_tier *redis,
                          const ism_pipeline_limits *limits, const ism_blob *request,
                          char *name, bool copy)
{
    char own[ISM_CACHE_NAME_MAX];
    if (!name)
        name = own;
    name[0] = 0;
    if (!request)
        return -1;
    ism_pipeline_result pr;
    bool keyed = ism_pipeline_key((const char *)request->data, request->len, NULL, limits,
                                  &pr) &&
                 ism_cache_name(name, pr.surface_key, ISM_COMPUTED_EXT);
    ism_pipeline_result_free(&pr);
    if (!keyed) {
        name[0] = 0;
        return -1;
    }
    if (ism_cache_has(cache, name))
        return 1;
    const char *argv[1] = {name};
    if (!copy) {
        int n = ism_cache_redis_count(redis, argv, 1);
        return n < 0 ? -1 : n > 0;
    }
    ism_blob *got = NULL;
    if (ism_cache_redis_fetch(redis, argv, 1, &got) != 0)
        return -1;
    if (got)
        ism_cache_put_local(cache, name, got);
    ism_blob_unref(got);
    return got != NULL;
}
