/* shared_cache.h — the shared cache on a computation's path. With --redis, every new flight
 * (sched.h) stops here before the queue, and a task on the Redis tier's thread
 * (cache_redis.h) decides, without ever blocking an HTTP thread:
 *
 *   1. Someone holds the entry's lock (another daemon is computing it): wait, polling Redis
 *      every 10 ms growing to 100 ms, until the lock goes (released, or expired because its
 *      holder died), then look again.
 *   2. The mesh, its stats and its features are in Redis (a daemon that died while writing
 *      them may have left only some: that counts as missing): copy them into the local tiers
 *      and answer every waiter ("X-Cache: shared"). Nothing is computed here.
 *   3. Otherwise take the lock (SET NX PX, a token naming this daemon and flight) and queue
 *      the flight for a local worker (first copying the surface's stored computed mesh from
 *      Redis, when there is one, so the worker only encodes it). When there is none, the
 *      surface's own lock ("<surface key>.mesh") is taken too, so that a daemon asked for
 *      another format of it meanwhile waits (polling as in 1, holding its own lock) for the
 *      stored surface instead of polygonising it again; held by another daemon, this flight
 *      waits so (with --cluster the origin holds it for the executor, and waits for it held by
 *      any other flight, its own daemon's too: the two may run on two daemons). While it
 *      computes, the locks are extended every third of their lifetime; when the flight has
 *      ended and its results are in the tiers (the surface first: the mesh's entries reach
 *      Redis only after it, worker_pool.c), they are written out and the locks released.
 *   A GET of a key unknown here (no local request.json) fetches the canonical request from
 *   Redis in step 2, checks that it still gives its key, and computes the other format.
 *   Redis unreachable at any step: the flight is queued at once and computed here (counted as
 *   a fallback); the daemon keeps serving from its own tiers.
 *
 * Waiting is bounded by the flight's deadline (--queue-timeout + --job-timeout); a dead
 * holder by the lock's lifetime (--redis-lock-ttl). */
#ifndef ISMD_SHARED_CACHE_H
#define ISMD_SHARED_CACHE_H

#include "server/common/cache.h"
#include "server/common/pipeline.h"
#include "server/isomeshd/cluster.h"
#include "server/isomeshd/sched.h"

typedef struct ismd_shared ismd_shared;

/* Hooks the shared stage into sched (new flights go through it). With cluster (not NULL), a
 * computation step 3 would queue here goes to the cluster queue instead (cluster.h), and this
 * daemon's executor takes work from it. NULL when out of memory. */
ismd_shared *ismd_shared_start(ismd_sched *sched, ism_cache *cache, ism_cache_tier *redis,
                               const ism_pipeline_limits *limits, double lock_ttl_s,
                               const ismd_cluster_settings *cluster);

/* The cluster queue (cluster.h) when started with one, else NULL. */
ismd_cluster *ismd_shared_cluster(ismd_shared *sh);

/* Unhooks and waits (bounded) for the tasks to finish, releasing the locks they hold. Call
 * after the pool has stopped and before the scheduler is destroyed; frees sh. */
void ismd_shared_stop(ismd_shared *sh);

#endif
