/* shared_cache.c — the shared stage of shared_cache.h: one task per new flight, run on the
 * Redis tier's thread, stepping through look / wait / lock / hold. The task never keeps a
 * pointer to its flight: it finds it again by name and id under the scheduler's lock each
 * time (the flight may have ended, been canceled or have passed its deadline meanwhile), and
 * never holds that lock across a Redis call. */
#include "server/isomeshd/shared_cache.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/random.h>
#include <unistd.h>

#include "server/common/cache_redis.h"
#include "proto/request.h"
#include "server/common/log.h"
#include "server/isomeshd/cluster.h"
#include "server/isomeshd/errors.h"
#include "server/isomeshd/redis_tasks.h"
#include "server/isomeshd/surface_prefetch.h"
#include "server/isomeshd/worker_pool.h"

#define POLL_MIN_NS 10000000LL        /* first look after finding the lock taken */
#define POLL_MAX_NS 100000000LL       /* then every 1.5x longer, up to this */
#define HOLD_TICK_NS 10000000LL       /* how often a holder checks whether its flight ended */
#define RENEW_RETRY_NS 200000000LL    /* a failed extension is retried this soon */
#define STOP_WAIT_NS 3000000000LL     /* ismd_shared_stop waits this long for its tasks */
#define REMOTE_POLL_NS 20000000LL     /* a computation on the cluster queue is looked at */

/* T_SURFACE: holding the entry's lock, waiting for another daemon's polygonisation of its
 * surface (for another format: that daemon holds the surface's lock) to be stored; with
 * --cluster, also another flight's of this daemon (it may run anywhere). */
typedef enum tstate { T_LOOK, T_WAIT, T_HOLD, T_REMOTE, T_SURFACE } tstate;

struct ismd_shared {
    ismd_sched *sched;
    ism_cache *cache;
    ism_cache_tier *redis;
    ism_redis_counters *counters;
    const ism_pipeline_limits *limits;
    long ttl_ms;
    char instance[128];           /* host/pid/random: this daemon in lock tokens */
    ismd_cluster *cluster;        /* --cluster: computations go to the cluster queue */
    ismd_redis_tasks *tasks;      /* the stage's tasks and the cluster queue's */
};

typedef struct task {
    ism_redis_task base;          /* first: the tier hands this back */
    ismd_shared *sh;
    char name[ISM_CACHE_NAME_MAX];
    char key[65], fmt[8];
    uint64_t flight_id;
    tstate state;
    bool missed, lock_lost;
    char surface[ISM_CACHE_NAME_MAX];   /* "<surface key>.mesh" once looked for */
    bool surface_locked;                /* its lock is ours: polygonised here */
    long long poll_ns, renew_at_ns;
    char token[192];
    char user[ISMD_QUEUE_USER_MAX];     /* T_REMOTE: the flight's user and its entry */
    char entry[ISMD_CLUSTER_ID_MAX];
    char stream[ISMD_CLUSTER_KEY_MAX];  /* the entry's stream (another user's when joined) */
    bool wanting;                       /* said so in Redis (ismd_cluster_want) */
    long long cancel_since_ns;          /* the first try of that cancel (0: none yet) */
    long long want_at_ns;               /* when to say it again */
} task;

/* The task's flight if it still exists (lock held); shared_only: still in this stage. */
static ismd_flight *my_flight(task *k, bool shared_only)
{
    ismd_flight *f = ismd_sched_find(k->sh->sched, k->name);
    if (!f || f->id != k->flight_id || (shared_only && !f->shared))
        return NULL;
    return f;
}

/* ---- ending a task ------------------------------------------------------------------- */

/* The group's release (redis_tasks.h): the stage and its cluster queue go together. */
static void free_shared(void *owner)
{
    ismd_shared *sh = owner;
    ismd_cluster_free(sh->cluster);
    free(sh);
}

/* Releases what the task holds (its flight's results are written out before its lock goes)
 * and frees it. Returns 0 for the tier ("finished"). */
static long long task_end(task *k, ism_cache_tier *t)
{
    ismd_shared *sh = k->sh;
    if (k->wanting)
        ismd_cluster_want(sh->cluster, k->name, false);
    if (k->state == T_REMOTE)
        ismd_cluster_cancel(sh->cluster, k->name, k->stream, k->entry);
    bool holding = k->state == T_HOLD || k->state == T_REMOTE || k->state == T_SURFACE;
    if (holding && !k->lock_lost) {
        ism_cache_redis_flush(t);
        ism_cache_redis_unlock(t, k->name, k->token);
    }
    if (k->surface_locked) /* after the flush: the surface went out with the mesh */
        ism_cache_redis_unlock(t, k->surface, k->token);
    if (!holding)
        atomic_fetch_sub(&sh->counters->asking, 1);
    free(k);
    ismd_redis_tasks_ended(sh->tasks);
    return 0;
}

ismd_cluster *ismd_shared_cluster(ismd_shared *sh)
{
    return sh ? sh->cluster : NULL;
}

/* ---- answers ------------------------------------------------------------------------- */

static void answer(task *k, const ismd_result *r)
{
    ismd_shared *sh = k->sh;
    if (!ismd_redis_tasks_enter(sh->tasks))
        return;
    ismd_flight *f = my_flight(k, true);
    if (f) {
        ismd_result copy = *r;
        copy.queue_ms = (ism_now_ns() - f->submitted_ns) / 1e6;
        ismd_sched_answer(sh->sched, f, &copy);
    }
    ismd_redis_tasks_leave(sh->tasks);
}

static void answer_error(task *k, unsigned status, const char *code, const char *message)
{
    ismd_result r = {.status = status, .content_type = "application/json"};
    r.body = ismd_error_json(code, message, NULL);
    if (r.body)
        answer(k, &r);
    ism_blob_unref(r.body);
}

/* Moves the flight on to the local queue. False when it is gone (or the queue refused it). */
static bool to_queue(task *k)
{
    ismd_shared *sh = k->sh;
    if (!ismd_redis_tasks_enter(sh->tasks))
        return false;
    ismd_flight *f = my_flight(k, true);
    bool queued = f && ismd_sched_enqueue(sh->sched, f);
    ismd_redis_tasks_leave(sh->tasks);
    return queued;
}

/* Redis could not help: compute here. */
static long long go_local(task *k, ism_cache_tier *t)
{
    atomic_fetch_add(&k->sh->counters->fallbacks, 1);
    to_queue(k);
    return task_end(k, t);
}

/* ---- steps --------------------------------------------------------------------------- */

/* Look again later in state st: first at POLL_MIN_NS after entering it (one more lock wait
 * counted), then 1.5x longer each time up to POLL_MAX_NS. The time of the next look. */
static long long poll_again(task *k, tstate st, long long now)
{
    if (k->state != st) {
        k->state = st;
        k->poll_ns = POLL_MIN_NS;
        atomic_fetch_add(&k->sh->counters->lock_waits, 1);
    } else {
        k->poll_ns = k->poll_ns * 3 / 2 > POLL_MAX_NS ? POLL_MAX_NS : k->poll_ns * 3 / 2;
    }
    return now + k->poll_ns;
}

/* The lock is another daemon's: wait (with --cluster, saying so in Redis, so that its origin
 * does not cancel the computation when its own requests leave). */
static long long wait_more(task *k, long long now)
{
    ismd_shared *sh = k->sh;
    if (sh->cluster && now >= k->want_at_ns) {
        ismd_cluster_want(sh->cluster, k->name, true);
        k->wanting = true;
        k->want_at_ns = now + sh->ttl_ms * 1000000LL / 3;
    }
    return poll_again(k, T_WAIT, now);
}

/* Whether the flight still waits here; *need_request (unless NULL) when it has no canonical
 * request. */
static bool still_wanted(task *k, bool *need_request)
{
    if (!ismd_redis_tasks_enter(k->sh->tasks))
        return false;
    ismd_flight *f = my_flight(k, true);
    if (f && need_request)
        *need_request = f->request == NULL;
    ismd_redis_tasks_leave(k->sh->tasks);
    return f != NULL;
}

/* A stored request is used only if it still gives its key (a new mesher gives new keys). */
static bool request_gives_key(ismd_shared *sh, const ism_blob *req, const task *k)
{
    ism_pipeline_result pr;
    memset(&pr, 0, sizeof pr);
    bool same = ism_pipeline_key((const char *)req->data, req->len, k->fmt, sh->limits, &pr) &&
                !strcmp(pr.key, k->key);
    ism_pipeline_result_free(&pr);
    return same;
}

static void attach_request(task *k, ism_blob *req)
{
    if (!ismd_redis_tasks_enter(k->sh->tasks))
        return;
    ismd_flight *f = my_flight(k, true);
    if (f && !f->request)
        f->request = ism_blob_ref(req);
    ismd_redis_tasks_leave(k->sh->tasks);
}

static void unref_all(ism_blob **b, size_t n)
{
    for (size_t i = 0; i < n; i++)
        ism_blob_unref(b[i]);
}

/* A lock no daemon would have set (no expiry, or a longer one) was removed: say so once. */
static void stale_lock_removed(task *k)
{
    atomic_fetch_add(&k->sh->counters->stale_locks, 1);
    ism_log_field f[] = {ISM_LS("name", k->name), ISM_LI("max_ttl_ms", k->sh->ttl_ms)};
    ism_log_fields(ISM_LOG_WARN, "redis_stale_lock_removed", f, 2);
}

/* What Redis holds of an entry: the mesh, its stats, its features (and its request). */
typedef struct stored {
    char names[4][ISM_CACHE_NAME_MAX];
    const char *argv[4];
    ism_blob *got[4];
} stored;

/* Reads the first n parts. 0, or -1 when Redis is unavailable. */
static int fetch_stored(const task *k, ism_cache_tier *t, size_t n, stored *st)
{
    const char *exts[4] = {k->fmt, "stats.json", "features.json", "request.json"};
    memset(st->got, 0, sizeof st->got);
    for (size_t i = 0; i < n; i++) {
        ism_cache_name(st->names[i], k->key, exts[i]);
        st->argv[i] = st->names[i];
    }
    return ism_cache_redis_fetch(t, st->argv, n, st->got);
}

/* Mesh, stats and features all there: copied into the local tiers, every waiter answered,
 * and true (the parts are released); else false (the caller still owns them). */
static bool answer_stored(task *k, ism_cache_tier *t, stored *st, size_t n)
{
    ism_blob **got = st->got;
    if (!got[0] || !got[1] || !got[2])
        return false;
    atomic_fetch_add(&t->counters.hits, 1);
    for (size_t i = 0; i < n; i++)
        if (got[i])
            ism_cache_put_local(k->sh->cache, st->names[i], got[i]);
    ismd_result r = {.status = 200, .body = got[0], .stats = got[1], .features = got[2],
                     .content_type = ism_format_mime_of(k->fmt), .cache = "shared"};
    answer(k, &r);
    unref_all(got, n);
    return true;
}

static long long to_cluster(task *k, ism_cache_tier *t, long long now);

/* The request of the task's flight (a new reference), or NULL. */
static ism_blob *flight_request(task *k)
{
    if (!ismd_redis_tasks_enter(k->sh->tasks))
        return NULL;
    ismd_flight *f = my_flight(k, true);
    ism_blob *req = f ? ism_blob_ref(f->request) : NULL;
    ismd_redis_tasks_leave(k->sh->tasks);
    return req;
}

static void renew_lock(task *k, ism_cache_tier *t, long long now);

/* Holding the entry's lock, the flight is computed (here, or on the cluster queue): encoded
 * from its surface when that is stored (copied from Redis first when computed here; the
 * executor copies it on the cluster queue, cluster.c); else polygonised under the surface's
 * own lock, or, when another daemon holds that one (it polygonises the surface for another
 * format and is storing it), started once that daemon has stored it, to be encoded from it. */
static long long start(task *k, ism_cache_tier *t, long long now)
{
    ismd_shared *sh = k->sh;
    ism_blob *req = flight_request(k);
    int have = ismd_prefetch_surface(sh->cache, t, sh->limits, req, k->surface, !sh->cluster);
    ism_blob_unref(req);
    if (have == 0 && !k->surface_locked) {
        /* kin: polygonised by this daemon for another format: the pool holds this flight
         * behind it (worker_pool.c), no need to wait for Redis; not so with --cluster,
         * where the two may run on two daemons */
        char kin[sizeof sh->instance + 1];
        snprintf(kin, sizeof kin, "%s/", sh->instance);
        int got = ism_cache_redis_lock_kin(t, k->surface, k->token, sh->ttl_ms, kin);
        if (got == 0 || (got == 2 && sh->cluster)) { /* look again as for a lock (wait_more) */
            renew_lock(k, t, now); /* reads neither state nor poll_ns */
            return poll_again(k, T_SURFACE, now);
        }
        k->surface_locked = got == 1; /* -1, Redis failed: polygonised all the same */
    }
    k->state = T_HOLD;
    if (sh->cluster)
        return to_cluster(k, t, now);
    if (!to_queue(k))
        return task_end(k, t); /* gone meanwhile, or refused by the queue: release the lock */
    return now + HOLD_TICK_NS;
}

/* T_SURFACE: while the flight still waits here, look at the surface again. */
static long long surface_wait(task *k, ism_cache_tier *t, long long now)
{
    if (!still_wanted(k, NULL))
        return task_end(k, t);
    return start(k, t, now);
}

/* Look in Redis; answer, wait, or take the lock and queue the flight. */
static long long look(task *k, ism_cache_tier *t, long long now)
{
    ismd_shared *sh = k->sh;
    bool need_request = false;
    if (!still_wanted(k, &need_request))
        return task_end(k, t);
    if (!ism_cache_redis_up(t))
        return go_local(k, t);
    int locked = ism_cache_redis_locked(t, k->name, sh->ttl_ms);
    if (locked < 0)
        return go_local(k, t);
    if (locked == 2)
        stale_lock_removed(k);
    else if (locked)
        return wait_more(k, now); /* computing elsewhere (or writing its results out) */

    stored st;
    size_t n = need_request ? 4 : 3;
    if (fetch_stored(k, t, n, &st) < 0)
        return go_local(k, t);
    if (answer_stored(k, t, &st, n)) /* complete: a crashed writer may have left less */
        return task_end(k, t);
    char (*names)[ISM_CACHE_NAME_MAX] = st.names;
    const char **argv = st.argv;
    ism_blob **got = st.got;
    if (!k->missed) {
        k->missed = true;
        atomic_fetch_add(&t->counters.misses, 1);
    }
    if (need_request) {
        if (!got[3] || !request_gives_key(sh, got[3], k)) {
            unref_all(got, n);
            answer_error(k, 404, "unknown_mesh",
                         "no mesh with this key is known to this service; POST its request to "
                         "/v1/mesh");
            return task_end(k, t);
        }
        ism_cache_put_local(sh->cache, names[3], got[3]);
        attach_request(k, got[3]);
    }
    unref_all(got, n);

    int acquired = ism_cache_redis_lock(t, k->name, k->token, sh->ttl_ms);
    if (acquired < 0)
        return go_local(k, t);
    if (!acquired)
        return wait_more(k, now);
    /* Someone may have finished it between the look and the lock: look again. */
    int there = ism_cache_redis_count(t, argv, 3);
    if (there < 0 || there == 3) {
        ism_cache_redis_unlock(t, k->name, k->token);
        return there == 3 ? now : go_local(k, t);
    }
    atomic_fetch_add(&sh->counters->locks_acquired, 1);
    if (k->state == T_WAIT)
        atomic_fetch_add(&sh->counters->lock_takeovers, 1);
    if (k->wanting) { /* the lock is ours now: our own cancel decides */
        ismd_cluster_want(sh->cluster, k->name, false);
        k->wanting = false;
        k->want_at_ns = 0;
    }
    k->state = T_HOLD;
    atomic_fetch_sub(&sh->counters->asking, 1);
    k->renew_at_ns = now + sh->ttl_ms * 1000000LL / 3;
    return start(k, t, now);
}

/* Extends the lock (and the surface's, when held) every third of its lifetime. */
static void renew_lock(task *k, ism_cache_tier *t, long long now)
{
    ismd_shared *sh = k->sh;
    if (!k->lock_lost && now >= k->renew_at_ns) {
        if (k->surface_locked) /* lost, another daemon may polygonise it too: no worse */
            ism_cache_redis_renew(t, k->surface, k->token, sh->ttl_ms);
        int kept = ism_cache_redis_renew(t, k->name, k->token, sh->ttl_ms);
        if (kept == 0) {
            k->lock_lost = true;
            atomic_fetch_add(&sh->counters->locks_lost, 1);
            ism_log_field f = ISM_LS("name", k->name);
            ism_log_fields(ISM_LOG_WARN, "redis_lock_lost", &f, 1);
        }
        k->renew_at_ns = kept < 0 ? now + RENEW_RETRY_NS : now + sh->ttl_ms * 1000000LL / 3;
    }
}

/* Holding the lock while the flight computes here: extend it; release it when it ends and
 * its entries have gone to Redis (after its answer they wait for its surface: sched.h
 * storing), so that a daemon that then finds the lock gone finds them there. */
static long long hold(task *k, ism_cache_tier *t, long long now)
{
    ismd_shared *sh = k->sh;
    if (!ismd_redis_tasks_enter(sh->tasks))
        return task_end(k, t);
    bool running = my_flight(k, false) != NULL || ismd_sched_storing(sh->sched, k->name);
    ismd_redis_tasks_leave(sh->tasks);
    if (!running)
        return task_end(k, t);
    renew_lock(k, t, now);
    return now + HOLD_TICK_NS;
}

/* ---- the cluster queue (cluster.h) ---------------------------------------------------- */

/* Holding the lock: the computation goes on its user's stream instead of the local queue. */
static long long to_cluster(task *k, ism_cache_tier *t, long long now)
{
    ismd_shared *sh = k->sh;
    if (!ismd_redis_tasks_enter(sh->tasks))
        return task_end(k, t);
    ismd_flight *f = my_flight(k, true);
    ism_blob *req = f ? ism_blob_ref(f->request) : NULL;
    ismd_user_limits lim = f ? f->lim : (ismd_user_limits){0};
    if (f)
        snprintf(k->user, sizeof k->user, "%s", f->user);
    ismd_redis_tasks_leave(sh->tasks);
    if (!req)
        return task_end(k, t);
    int rc = ismd_cluster_enqueue(sh->cluster, k->name, k->key, k->fmt, k->user, &lim, req,
                                  k->entry, k->stream);
    ism_blob_unref(req);
    if (rc < 0) { /* Redis failed just now: compute here */
        atomic_fetch_add(&sh->counters->fallbacks, 1);
        return to_queue(k) ? now + HOLD_TICK_NS : task_end(k, t);
    }
    if (rc == 0) {
        answer_error(k, 429, "too_many_requests",
                     "too many computations of yours are queued or running in the service "
                     "(--user-jobs, counted over every daemon); wait for one to finish");
        return task_end(k, t);
    }
    atomic_fetch_add(&sh->sched->metrics->cluster_submitted, 1);
    if (ismd_redis_tasks_enter(sh->tasks)) { /* an executor here that takes the entry joins the flight */
        ismd_flight *g = my_flight(k, true);
        if (g)
            snprintf(g->cluster_entry, sizeof g->cluster_entry, "%s", k->entry);
        ismd_redis_tasks_leave(sh->tasks);
    }
    k->state = T_REMOTE;
    return now + REMOTE_POLL_NS;
}

/* Running on another daemon: tell the waiters (progress events, the job's state). */
static void running_elsewhere(task *k, double progress)
{
    if (!ismd_redis_tasks_enter(k->sh->tasks))
        return;
    ismd_flight *f = my_flight(k, true);
    if (f && (!f->elsewhere || f->progress != progress)) {
        if (!f->elsewhere) {
            struct timespec wall;
            clock_gettime(CLOCK_REALTIME, &wall);
            f->elsewhere = true;
            f->started_ns = ism_now_ns();
            f->started_unix_ms = (long long)wall.tv_sec * 1000 + wall.tv_nsec / 1000000;
        }
        ismd_sched_progress(k->sh->sched, f, progress);
    }
    ismd_redis_tasks_leave(k->sh->tasks);
}

/* Computed elsewhere: answered from Redis, or (the results did not fit there) computed here. */
static long long remote_done(task *k, ism_cache_tier *t, long long now)
{
    stored st;
    int rc = fetch_stored(k, t, 3, &st);
    k->state = T_HOLD; /* no cancel from here on; the lock is still ours to release */
    if (rc == 0 && answer_stored(k, t, &st, 3))
        return task_end(k, t);
    unref_all(st.got, 3);
    return to_queue(k) ? now + HOLD_TICK_NS : task_end(k, t);
}

static long long remote_failed(task *k, ism_cache_tier *t, ismd_cj_view *v)
{
    ismd_result r = {.status = v->status >= 400 ? v->status : 500,
                     .content_type = "application/json", .body = v->error};
    if (!r.body)
        r.body = ismd_error_json("cluster_error", "the computation failed on another daemon",
                                 NULL);
    if (r.body)
        answer(k, &r);
    ism_blob_unref(r.body);
    k->state = T_HOLD;
    return task_end(k, t);
}

/* Following the computation on the cluster queue. */
static long long remote(task *k, ism_cache_tier *t, long long now)
{
    ismd_shared *sh = k->sh;
    if (!ismd_redis_tasks_enter(sh->tasks))
        return task_end(k, t);
    ismd_flight *f = my_flight(k, false);
    /* this daemon's executor took it; or, gone, because it is done: the executor took the
     * entry and finished it between two looks (a small mesh takes less than REMOTE_POLL_NS),
     * and its entries wait for its surface (sched.h storing). Not a cancel: the locks are kept
     * until they are written, as for a flight seen running here (hold), so that another
     * daemon asked for another format meanwhile waits for the surface instead of
     * polygonising it again */
    bool here = f ? !f->shared : ismd_sched_storing(sh->sched, k->name);
    ismd_redis_tasks_leave(sh->tasks);
    if (here) {
        k->state = T_HOLD;
        return now + HOLD_TICK_NS;
    }
    if (!f) { /* nobody waits any more (or past its deadline): cancel */
        /* again while Redis does not take it (a command timeout on a loaded machine, a
         * reconnect), for at most a lock lifetime: lost, the computation ran on elsewhere
         * for nobody (seen: test_a_delete_whose_set_read_times_out_is_not_lost) */
        bool taken = ismd_cluster_cancel(sh->cluster, k->name, k->stream, k->entry);
        if (!k->cancel_since_ns)
            k->cancel_since_ns = now;
        if (!taken && now - k->cancel_since_ns < sh->ttl_ms * 1000000LL) {
            renew_lock(k, t, now);
            return now + RENEW_RETRY_NS;
        }
        k->state = T_HOLD; /* made or given up */
        return task_end(k, t);
    }
    renew_lock(k, t, now);
    ismd_cj_view v;
    if (!ism_cache_redis_up(t) || ismd_cluster_view(sh->cluster, k->name, k->entry, &v) < 0)
        return go_local(k, t);
    switch (v.state) {
    case ISMD_CJ_QUEUED:
        return now + REMOTE_POLL_NS;
    case ISMD_CJ_RUNNING:
        running_elsewhere(k, v.progress);
        return now + REMOTE_POLL_NS;
    case ISMD_CJ_DONE:
        return remote_done(k, t, now);
    case ISMD_CJ_FAILED:
        return remote_failed(k, t, &v);
    default: /* its record is gone, or the computation was canceled (cluster.h: never for
              * requests here, which still wait for it): start over */
        if (!k->lock_lost)
            ism_cache_redis_unlock(t, k->name, k->token);
        k->state = T_LOOK;
        atomic_fetch_add(&sh->counters->asking, 1);
        return now;
    }
}

static long long task_run(ism_redis_task *base, ism_cache_tier *t, bool stopping)
{
    task *k = (task *)base;
    if (stopping || ismd_redis_tasks_stopping(k->sh->tasks))
        return task_end(k, t);
    long long now = ism_now_ns();
    return k->state == T_HOLD      ? hold(k, t, now)
           : k->state == T_REMOTE  ? remote(k, t, now)
           : k->state == T_SURFACE ? surface_wait(k, t, now)
                                   : look(k, t, now);
}

/* ---- the hook ------------------------------------------------------------------------ */

/* sched.h's shared_begin: called with the scheduler's lock held for each new flight. */
static bool begin(void *ctx, ismd_flight *f)
{
    ismd_shared *sh = ctx;
    task *k = calloc(1, sizeof *k);
    if (!k)
        return false;
    k->sh = sh;
    k->base.run = task_run;
    k->state = T_LOOK;
    k->flight_id = f->id;
    snprintf(k->name, sizeof k->name, "%s", f->name);
    snprintf(k->key, sizeof k->key, "%s", f->key);
    snprintf(k->fmt, sizeof k->fmt, "%s", f->fmt);
    snprintf(k->token, sizeof k->token, "%s/%llu", sh->instance, (unsigned long long)f->id);
    if (!ismd_redis_tasks_added(sh->tasks)) {
        free(k);
        return false;
    }
    atomic_fetch_add(&sh->counters->asking, 1);
    ism_cache_redis_schedule(sh->redis, &k->base, 0);
    return true;
}

ismd_shared *ismd_shared_start(ismd_sched *sched, ism_cache *cache, ism_cache_tier *redis,
                               const ism_pipeline_limits *limits, double lock_ttl_s,
                               const ismd_cluster_settings *cluster)
{
    ismd_shared *sh = calloc(1, sizeof *sh);
    if (!sh || !(sh->tasks = ismd_redis_tasks_new(sched, free_shared, sh))) {
        free(sh);
        return NULL;
    }
    sh->sched = sched;
    sh->cache = cache;
    sh->redis = redis;
    sh->counters = ism_cache_redis_counters(redis);
    sh->limits = limits;
    sh->ttl_ms = (long)(lock_ttl_s * 1000);
    char host[64] = "host";
    gethostname(host, sizeof host - 1);
    host[sizeof host - 1] = 0;
    unsigned long long nonce = 0;
    if (getrandom(&nonce, sizeof nonce, 0) != (ssize_t)sizeof nonce)
        nonce = (unsigned long long)ism_now_ns();
    snprintf(sh->instance, sizeof sh->instance, "%s/%ld/%016llx", host, (long)getpid(), nonce);
    if (cluster) {
        ismd_cluster_env env = {sh->tasks, sched, cache, redis, limits, sh->instance, sh->ttl_ms};
        if (!(sh->cluster = ismd_cluster_start(&env, cluster))) {
            ismd_redis_tasks_stop(sh->tasks, 0); /* no task yet: frees sh */
            return NULL;
        }
    }
    ismd_sched_lock(sched);
    sched->shared_begin = begin;
    sched->shared_ctx = sh;
    ismd_sched_unlock(sched);
    return sh;
}

void ismd_shared_stop(ismd_shared *sh)
{
    ismd_sched_lock(sh->sched);
    sh->sched->shared_begin = NULL;
    sh->sched->shared_ctx = NULL;
    ismd_sched_unlock(sh->sched);
    ismd_redis_tasks_stop(sh->tasks, STOP_WAIT_NS); /* sh is freed with the last task */
}
