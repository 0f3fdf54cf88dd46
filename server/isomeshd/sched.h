/* sched.h — single flight: every computation in progress is one "flight", named by the cache
 * entry it will produce ("<key>.<format>"). A request for a name already in flight joins it as
 * one more waiter instead of computing again. Flights wait in the job queue (job_queue.h),
 * run on a worker (worker_pool.h) and finish exactly once, handing every waiter the same
 * result. A flight belongs to the user who started it (the queue serves users fairly and
 * holds their limits); a user asking for a name in flight joins it whoever started it, so
 * identical requests compute once across users. Also the draining state at shutdown.
 *
 * One mutex (ismd_sched_lock) guards flights, waiters, the queue and the jobs table (jobs.h);
 * HTTP handlers suspend their connection while holding it, and everything that resumes one
 * (a waiter's done callback) runs with it held, so a resume can never overtake a suspend.
 * Only the pool thread finishes running flights. */
#ifndef ISMD_SCHED_H
#define ISMD_SCHED_H

#include <pthread.h>
#include <stdbool.h>
#include <stdint.h>

#include "server/common/blob.h"
#include "server/common/cache.h"
#include "server/isomeshd/job_queue.h"
#include "server/isomeshd/metrics.h"
#include "core/util/clock.h"

/* What a finished flight hands its waiters (they take references to what they keep). */
typedef struct ismd_result {
    unsigned status;           /* 200, or the error status */
    ism_blob *body;            /* the mesh bytes, or the error JSON */
    const char *content_type;  /* of body (static string) */
    ism_blob *stats, *features;/* status 200 only; may be NULL */
    double queue_ms, worker_ms;/* time waiting for a worker, time on it */
    char timing[256];          /* extra Server-Timing entries from the pipeline's stats */
    const char *cache;         /* "shared": computed by another daemon (shared_cache.h) */
} ismd_result;

#define ISMD_ENTRY_ID_MAX 48       /* a cluster queue (stream) entry id, NUL included */

typedef struct ismd_flight ismd_flight;
typedef struct ismd_waiter ismd_waiter;
struct ismd_waiter {
    ismd_waiter *prev, *next;
    ismd_flight *flight;       /* NULL once finished or detached */
    /* The cluster executor's waiter for the entry its own flight put on the queue
     * (cluster.h): it keeps the flight only while someone else waits for it too. */
    bool passive;
    /* Called once, lock held, when the flight finishes. */
    void (*done)(ismd_waiter *w, const ismd_result *r);
    /* Optional, lock held: the flight started running or reported progress. */
    void (*progress)(ismd_waiter *w, double fraction, bool running);
};

struct ismd_flight {
    char name[ISM_CACHE_NAME_MAX];
    char key[65];
    char fmt[8];
    ism_blob *request;         /* canonical request JSON sent to the worker */
    uint64_t id;               /* job id in worker frames */
    bool running;
    bool shared;               /* asking the shared cache first: neither queued nor running */
    bool elsewhere;            /* shared, and running on another daemon (cluster.h) */
    bool canceled;             /* running: to be stopped by the pool, waiters answered 499 */
    ismd_user_limits lim;      /* the user's limits, for queueing after the shared cache */
    char cluster_entry[ISMD_ENTRY_ID_MAX]; /* the cluster queue entry it added, or "" */
    double progress;
    long long submitted_ns, started_ns;
    long long deadline_ns;     /* queued: the end of its wait (--queue-timeout); running: of
                                  its computation (--job-timeout, from its start) */
    long long started_unix_ms; /* wall-clock start (for job views), set with started_ns */
    ismd_waiter waiters;       /* list sentinel */
    size_t nwaiters;
    char user[ISMD_QUEUE_USER_MAX]; /* who started it (its queue line and limits) */
    ismd_flight *hnext;        /* name table chain */
    ismd_qentry qe;            /* its place in the queue (job_queue.h); qe.queued: waiting */
    ismd_flight *aprev, *anext;/* list of all flights, oldest first */
};

typedef enum ismd_submit {
    ISMD_SUBMIT_NEW,           /* a new flight was queued */
    ISMD_SUBMIT_JOINED,        /* joined a flight in progress */
    ISMD_SUBMIT_QUEUE_FULL,    /* 503 */
    ISMD_SUBMIT_CLIENT_LIMIT,  /* 429: the user's --user-jobs (or tokens file jobs=N) */
    ISMD_SUBMIT_DRAINING,      /* 503, shutting down */
    ISMD_SUBMIT_NO_MEMORY,     /* 500 */
} ismd_submit;

typedef struct ismd_sched {
    pthread_mutex_t lock;
    ismd_flight **table;
    size_t nbuckets;
    ismd_flight *all_head, *all_tail;
    size_t nflights;
    ismd_queue *queue;
    uint64_t next_id;
    bool draining;
    double job_timeout_s;      /* a computation's time on a worker */
    double queue_timeout_s;    /* a computation's wait for a worker */
    ismd_metrics *metrics;
    void (*wake)(void *ctx);   /* tells the pool thread to look again (set by the pool) */
    void *wake_ctx;
    /* Optional (shared_cache.h): takes each new flight before the queue; false when out of
     * memory. The flight is admitted first (limits checked), then waits there (f->shared). */
    bool (*shared_begin)(void *ctx, ismd_flight *f);
    void *shared_ctx;
    /* Names of flights answered whose entries are not all written out yet: their surface is
     * still coming from the worker, and their writes to the remote tiers wait for it
     * (worker_pool.c), so that Redis never holds a mesh without its surface. The shared
     * stage keeps such a flight's lock, and the cluster executor its report, until then. */
    char (*storing)[ISM_CACHE_NAME_MAX];
    size_t nstoring, storing_cap;
} ismd_sched;

bool ismd_sched_init(ismd_sched *s, ismd_queue *queue, double job_timeout_s,
                     double queue_timeout_s, ismd_metrics *metrics);
void ismd_sched_destroy(ismd_sched *s);
void ismd_sched_lock(ismd_sched *s);
void ismd_sched_unlock(ismd_sched *s);

/* --- lock held for everything below --- */

/* Adds waiter w to the flight for key.fmt, creating and queueing it in user's line when there
 * is none. request is the canonical request JSON (referenced, not copied); lim holds the
 * user's own limits (NULL or zeros: the defaults). */
ismd_submit ismd_sched_submit(ismd_sched *s, const char *key, const char *fmt,
                              ism_blob *request, const char *user,
                              const ismd_user_limits *lim, ismd_waiter *w);

/* The same, but a new flight goes straight to the local queue, and a flight of that name
 * still in the shared stage moves there: the cluster queue (cluster.h) chose this daemon to
 * compute it. */
ismd_submit ismd_sched_submit_here(ismd_sched *s, const char *key, const char *fmt,
                                   ism_blob *request, const char *user,
                                   const ismd_user_limits *lim, ismd_waiter *w);

/* Takes w off its flight (a canceled job, a client that left). A queued flight left without
 * waiters is dropped; a running one is stopped by the pool (its worker is replaced). A flight
 * left with passive waiters only goes on until their owner cancels it (cluster.h: unless
 * another daemon waits for it). */
void ismd_sched_detach(ismd_sched *s, ismd_waiter *w);
/* Whether every waiter of f is passive (the cluster executor's). */
bool ismd_sched_only_passive(const ismd_flight *f);

/* Cancels f for every waiter (its passive waiters alone left, and no other daemon wants it:
 * cluster.h): answered 499 now when it waits, by the pool (which stops its worker) when it
 * runs. */
void ismd_sched_cancel(ismd_sched *s, ismd_flight *f);

/* Hands r to every waiter and frees the flight (must not be queued). */
void ismd_sched_finish(ismd_sched *s, ismd_flight *f, const ismd_result *r, ismd_outcome o);

/* Finishes a queued or running flight with an error JSON {"error": {code, message}}. */
void ismd_sched_fail(ismd_sched *s, ismd_flight *f, unsigned status, const char *code,
                     const char *message, ismd_outcome o);

/* Records progress (running) and tells the waiters. */
void ismd_sched_progress(ismd_sched *s, ismd_flight *f, double fraction);

/* The next queued flight, now marked running (NULL when none). */
ismd_flight *ismd_sched_next(ismd_sched *s);

/* Finishes every flight past its deadline that is not running: 503 queue_timeout when it
 * waited for a worker, 504 when it awaited another daemon's computation. Running ones are
 * returned through expired[] (up to max) for the pool to kill (504). Returns how many. */
size_t ismd_sched_expire(ismd_sched *s, long long now_ns, ismd_flight **expired, size_t max);

/* Earliest deadline of any flight (LLONG_MAX when none). */
long long ismd_sched_next_deadline(const ismd_sched *s);

/* Preemption, so that users who each hold a worker with endless work cannot keep another
 * user's request from one (fair order, every worker busy): the flight to take back is the
 * latest started of the user holding the most workers, when a user with nothing running
 * waits and that user holds at least two, or (no default --user-running: the queue's
 * fair_share, half the workers rounded up) when that user holds more than the share and a
 * user below it waits. NULL when none should be. */
ismd_flight *ismd_sched_preempt_victim(ismd_sched *s);
/* A running flight goes back to the head of its user's line, its waiters told it is queued
 * again (the pool stops its worker). */
void ismd_sched_requeue(ismd_sched *s, ismd_flight *f);

/* Stops accepting flights and fails every queued one with 503. */
void ismd_sched_drain(ismd_sched *s);

/* The flight for name ("<key>.<fmt>"), or NULL. */
ismd_flight *ismd_sched_find(ismd_sched *s, const char *name);
/* Moves a flight from the shared cache to the queue. False when the queue refused it (the
 * flight is then answered 429 or 503 and freed). */
bool ismd_sched_enqueue(ismd_sched *s, ismd_flight *f);
/* Hands r to every waiter and frees the flight, without counting a computation (an answer
 * from the shared cache, or an error found there). */
void ismd_sched_answer(ismd_sched *s, ismd_flight *f, const ismd_result *r);

/* The storing list above: name's entries go on being written after its answer (false when
 * out of memory: the caller writes them at once), they are all written, and whether they
 * still are being. */
bool ismd_sched_storing_begin(ismd_sched *s, const char *name);
void ismd_sched_storing_end(ismd_sched *s, const char *name);
bool ismd_sched_storing(const ismd_sched *s, const char *name);

#endif
