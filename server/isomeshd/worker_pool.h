/* worker_pool.h — the pre-started `isomesh --worker` processes and the one thread that talks
 * to them. Each worker is fork+exec'd (argv only, no shell) with PR_SET_PDEATHSIG and an
 * RLIMIT_AS memory limit, and speaks proto/frame.h over two pipes. The pool thread takes
 * flights from the scheduler's queue for idle workers, turns their PROGRESS frames into
 * progress, their RESULT frames into cache entries and finished flights, and enforces
 * deadlines. A flight whose surface is stored ("<surface key>.mesh", proto/computed.h) sends
 * it with the request, and the worker encodes from it instead of polygonising; a newly
 * computed surface comes back with the result and is stored in every tier. A worker that crashes, breaks the protocol, passes its deadline or loses all its
 * waiters is killed (if need be) and replaced; its flight is answered 500, 504 or dropped. */
#ifndef ISMD_WORKER_POOL_H
#define ISMD_WORKER_POOL_H

#include <stddef.h>

#include "server/common/cache.h"
#include "server/isomeshd/metrics.h"
#include "server/isomeshd/sched.h"

typedef struct ismd_pool_config {
    int workers;
    const char *worker_path;   /* the isomesh binary */
    size_t job_memory;         /* RLIMIT_AS per worker (0 = none) */
    int max_depth;
    size_t max_triangles;
    int threads;               /* polygoniser threads per job */
} ismd_pool_config;

typedef struct ismd_pool ismd_pool;

/* Starts the pool thread, which starts the workers. NULL on failure (logged). */
ismd_pool *ismd_pool_start(const ismd_pool_config *cfg, ismd_sched *sched, ism_cache *cache,
                           ismd_metrics *metrics);

/* Drains the scheduler (queued flights get 503), lets running flights finish for up to
 * grace_s seconds, then fails the rest with 503, stops every worker and joins the thread. */
void ismd_pool_stop(ismd_pool *p, double grace_s);

#endif
