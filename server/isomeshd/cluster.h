/* cluster.h — the cluster queue (--cluster, with --redis): every daemon that shares one Redis
 * is a front end and a worker host of one queue kept in Redis Streams.
 *
 * Keys (P = "<namespace>:v1:", ism_cache_redis_prefix):
 *   P q:<user>    one stream per user: an entry per computation waiting or running (fields
 *                 name, key, fmt, user, req = its canonical request); consumer group
 *                 "workers", one consumer per daemon
 *   P r:<user>    the user's given-back entries (preempted: taken again before its others),
 *                 same fields and group
 *   P run, P nwait  hashes user -> its entries taken (running, or pending on a dead daemon),
 *                 its entries not taken yet (over both streams)
 *   P wait        sorted set: users with an entry to take, below their running limit, scored
 *                 by their entries taken (run, nwait and wait are kept by every script that
 *                 changes a user's streams: choosing and sharing never read every user's;
 *                 a daemon starting on a queue left by older daemons, whose P users set
 *                 listed the users instead, computes them once and drops the set. Daemons
 *                 of the two layouts must not share one queue: upgrade them all at once)
 *   P ulim        hash user -> the user's running limit (0: none), from its latest entry
 *   P turns, P served  a count of every take, and hash user -> that count at the user's
 *                 last take: of the users tied in P wait, the one served longest ago is next
 *   P job:<name>  hash: state (queued, running, done, failed), progress, status and error
 *                 (failed), the daemon running it, its origin (the daemon that queued it),
 *                 its entry's id and stream, queued_ms, started_ms, ended_ms on Redis's
 *                 clock (one clock for every daemon), and alone (its last heartbeat: 1 when
 *                 it may be given back); expires
 *   P jobrec:<id> hash: a job (POST /v1/jobs) of any daemon: user, key, fmt, created, the
 *                 daemon holding it, and cancel once deleted (1, or final when that daemon
 *                 was not alive: never taken back), so that every daemon answers
 *                 GET and DELETE /v1/jobs/{id}; expires
 *   P deleted:<daemon>  set: ids of that daemon's jobs deleted through other daemons
 *   P cjobs:<name> set: ids of the jobs (any daemon's) recorded for that computation
 *   P alive:<daemon> present while that daemon lives (renewed like a heartbeat, expires
 *                 one lock lifetime after its last renewal)
 *   P nworkers    hash daemon -> its worker count (fields of daemons no longer alive are
 *                 dropped when read)
 *   P want:<name> sorted set: daemons whose requests wait for that computation (its lock is
 *                 another's), each until a lock lifetime after it last said so
 *
 * Canceling: a job is a waiter, and so is a synchronous request; a computation is canceled
 * only when nothing waits for it any more. A DELETE through the daemon holding the job, or a
 * client leaving, takes that one waiter off (sched.h). A DELETE through another daemon flags
 * the job's record (the job reads canceled everywhere at once) and puts its id in its
 * daemon's deleted set; that daemon takes the set every DELETES_TICK_NS and lets go of each
 * job as a DELETE there would, so requests sharing the computation keep it. A daemon that
 * died takes nothing: its deleted jobs read canceled at once, and a computation whose
 * origin died is stopped wherever it runs (or waits, or waits to be re-claimed) once every
 * job recorded for it was deleted and no other daemon holds its lock or waits for it: by the
 * DELETE itself, else by the heartbeat of its executor. The job hash's cancel flag is the computation's: set by its
 * origin when nothing there waits for it any more and no other daemon does (P want:<name>:
 * requests of other daemons waiting for its lock; with one, the computation goes on and the
 * first of them to take the lock joins its entry), or by an executor whose flight was
 * canceled, it tells the executor to stop unless requests on its own daemon share it. An
 * origin whose flight runs here (the executor's waiter is then passive) leaves that
 * decision to the executor, which stops it once neither requests here nor other daemons
 * want it.
 *
 * A live daemon cut off from Redis past a lock lifetime looks dead (its alive key and lock
 * expire): a DELETE elsewhere may flag its computation canceled as abandoned. That never
 * fails its requests: an executor's cancel only detaches its own waiter (requests there keep
 * the flight), and an origin reading its computation canceled starts over (shared_cache.c's
 * remote), computing it itself while Redis is unreachable. The cost is a computation done
 * twice at worst. A job of it deleted meanwhile stays canceled (its record's flag is final:
 * the DELETE found its daemon dead), on every daemon, even when the computation started
 * over finishes it there before that daemon takes the DELETE.
 *
 * The origin (shared_cache.c, on the Redis thread) adds a computation it holds the lock of to
 * its user's stream (refused when the user already has its --user-jobs there: cluster-wide),
 * then follows its job hash until it is done (the mesh is then read from the shared cache) or
 * failed (the error is answered), and cancels it when nobody waits for it any more (not when
 * this daemon's executor ran it and its flight has ended while its surface is still being
 * stored: the origin then keeps its locks until the entries are written, as it does for a
 * flight it sees running here).
 *
 * The executor (a task per daemon, on the Redis thread) takes entries while this daemon has
 * idle workers: first one pending on a daemon that has not heart-beaten for a lock lifetime
 * (XPENDING IDLE + XCLAIM: its daemon died), else a new one (XREADGROUP) from the user with the
 * fewest entries running cluster-wide, below that user's running limit, ties taken in turn:
 * the user's given-back entries first, then its stream. The entry becomes a local flight (or
 * joins one of the same name here); while it runs, its own task re-claims the entry every
 * heartbeat (resetting its idle time), publishes progress and watches for a cancel, and gives
 * the entry back when its user is over the service's fair share while another user waits and
 * nothing else on this daemon shares the computation (HEARTBEAT_LUA's over_share: sched.c's
 * preemption rule over the workers of every live daemon, P nworkers) and it is the user's
 * entry started last among those that may go (NEWEST_LUA: the least work lost). A given-back
 * entry goes to its user's P r:<user>, so it is that user's next computation to start; it
 * starts from scratch (its partial work lived in the worker process stopped to free the
 * worker). When an entry ends, the results are flushed to Redis before the job hash says so, and the entry
 * is acknowledged and deleted. Every step is one Lua script, so a
 * crash between two commands never leaves half a change. */
#ifndef ISMD_CLUSTER_H
#define ISMD_CLUSTER_H

#include <stdbool.h>

#include "server/common/blob.h"
#include "server/common/cache.h"
#include "server/common/pipeline.h"
#include "server/isomeshd/jobs.h"
#include "server/isomeshd/redis_tasks.h"
#include "server/isomeshd/sched.h"

#define ISMD_CLUSTER_ID_MAX ISMD_ENTRY_ID_MAX   /* a stream entry id, NUL included */
#define ISMD_CLUSTER_KEY_MAX 512                /* a key in Redis (a user's stream) */

typedef struct ismd_cluster ismd_cluster;

/* --cluster: the default per-user limits, held over the whole service, and the daemon's job
 * table (its jobs may be deleted through other daemons). */
typedef struct ismd_cluster_settings {
    int user_jobs, user_running;
    ismd_jobs *jobs;
} ismd_cluster_settings;

/* What the executor runs in: its tasks' group (they live and stop with the shared stage,
 * shared_cache.h, and enter the scheduler through it), the daemon's scheduler and cache, the
 * Redis tier, the request limits, this daemon's name (its consumer) and the lock lifetime. */
typedef struct ismd_cluster_env {
    ismd_redis_tasks *tasks;
    ismd_sched *sched;
    ism_cache *cache;
    ism_cache_tier *redis;
    const ism_pipeline_limits *limits;
    const char *instance;
    long ttl_ms;
} ismd_cluster_env;

typedef enum ismd_cj_state {
    ISMD_CJ_MISSING, ISMD_CJ_QUEUED, ISMD_CJ_RUNNING, ISMD_CJ_DONE, ISMD_CJ_FAILED,
    ISMD_CJ_CANCELED
} ismd_cj_state;

/* A computation as its job hash tells it. */
typedef struct ismd_cj_view {
    ismd_cj_state state;      /* MISSING: no hash, or one for another entry */
    double progress;
    unsigned status;          /* FAILED: the HTTP status */
    ism_blob *error;          /* FAILED: the error JSON (the caller unrefs it) */
} ismd_cj_view;

/* Starts the executor of env's daemon (its tasks live and stop with env->tasks). NULL when
 * out of memory or stopping. */
ismd_cluster *ismd_cluster_start(const ismd_cluster_env *env, const ismd_cluster_settings *set);
/* Frees c (NULL: nothing) once its tasks have all ended (env->tasks' release). */
void ismd_cluster_free(ismd_cluster *c);

/* ---- the origin's calls, Redis thread only ------------------------------------------- */

/* Adds flight f's computation (copied: name, key, format, user, limits, request) to its
 * user's stream, or joins the live entry of the same computation an origin left to the
 * daemons still waiting for it; id and stream get the entry's. 1 added or joined, 0 the user
 * has its limit of entries there, -1 Redis unavailable. */
int ismd_cluster_enqueue(ismd_cluster *c, const char *name, const char *key, const char *fmt,
                         const char *user, const ismd_user_limits *lim, const ism_blob *request,
                         char id[ISMD_CLUSTER_ID_MAX], char stream[ISMD_CLUSTER_KEY_MAX]);
/* Reads the job hash of name for entry id. 0, or -1 when Redis is unavailable. */
int ismd_cluster_view(ismd_cluster *c, const char *name, const char *id, ismd_cj_view *v);
/* Nobody here waits for entry id (of stream) any more: unless another daemon waits for the
 * computation (ismd_cluster_want), a waiting entry is deleted and a running one told to stop
 * (its executor sees the cancel at its next heartbeat). False when Redis did not take it. */
bool ismd_cluster_cancel(ismd_cluster *c, const char *name, const char *stream, const char *id);
/* want: a request here waits for name, whose lock another daemon holds (shared_cache.h step
 * 1); recorded for one lock lifetime, so call it again every third of that. !want: no more.
 * A computation somebody wants is not canceled when its origin's requests all leave: the
 * first waiter to take its lock joins it. */
void ismd_cluster_want(ismd_cluster *c, const char *name, bool want);

/* ---- jobs seen through any daemon (called from HTTP threads; never block) ---------- */

/* Records job id (of user, for key.fmt, created at created_unix) in Redis, so that any
 * daemon can answer for it. Fire and forget. */
void ismd_cluster_job_created(ismd_cluster *c, const char *id, const char *user,
                              const char *key, const char *fmt, long long created_unix);
/* Looks job id up in Redis and calls w->done once, scheduler lock held, with status 200 and
 * the job's JSON (jobs.h's form, its state from the computation's job hash or, without one,
 * done when the mesh is in the shared cache), 404 when no daemon recorded it, or 503 when
 * Redis is unavailable. False (w never called) when out of memory or stopping. */
bool ismd_cluster_job_lookup(ismd_cluster *c, const char *id, ismd_waiter *w);
/* DELETE of job id through a daemon that does not hold it: the job reads canceled on every
 * daemon, and the daemon holding it lets go of it as a DELETE there would (its computation
 * stops unless another request or job shares it). Fire and forget; the caller checked who
 * may. */
void ismd_cluster_job_delete(ismd_cluster *c, const char *id);

#endif
