/* sched.c — single flight and its bookkeeping (sched.h): the name table of flights in
 * progress, waiter lists, deadlines and the draining state; per-user counts and limits are
 * the queue's (job_queue.h). */
#include "server/isomeshd/sched.h"
#include "server/common/text_hash.h"

#include <limits.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "server/isomeshd/errors.h"

/* The flight a queue entry is embedded in. */
#define FLIGHT_OF(e) ((ismd_flight *)((char *)(e) - offsetof(ismd_flight, qe)))

bool ismd_sched_init(ismd_sched *s, ismd_queue *queue, double job_timeout_s,
                     double queue_timeout_s, ismd_metrics *metrics)
{
    memset(s, 0, sizeof *s);
    s->nbuckets = 256;
    s->table = calloc(s->nbuckets, sizeof *s->table);
    if (!s->table || !queue)
        return false;
    pthread_mutex_init(&s->lock, NULL);
    s->queue = queue;
    s->job_timeout_s = job_timeout_s;
    s->queue_timeout_s = queue_timeout_s;
    s->metrics = metrics;
    s->next_id = 1;
    atomic_store(&metrics->queue_capacity, (long long)queue->capacity);
    return true;
}

void ismd_sched_destroy(ismd_sched *s)
{
    free(s->table);
    free(s->storing);
    if (s->queue)
        s->queue->ops->destroy(s->queue);
    pthread_mutex_destroy(&s->lock);
}

void ismd_sched_lock(ismd_sched *s)
{
    pthread_mutex_lock(&s->lock);
}

void ismd_sched_unlock(ismd_sched *s)
{
    pthread_mutex_unlock(&s->lock);
}

/* ---- flights ------------------------------------------------------------------------- */

static ismd_flight **flight_slot(ismd_sched *s, const char *name)
{
    ismd_flight **f = &s->table[ism_text_hash(name) & (s->nbuckets - 1)];
    while (*f && strcmp((*f)->name, name) != 0)
        f = &(*f)->hnext;
    return f;
}

static void waiter_append(ismd_flight *f, ismd_waiter *w)
{
    w->flight = f;
    w->prev = f->waiters.prev;
    w->next = &f->waiters;
    f->waiters.prev->next = w;
    f->waiters.prev = w;
    f->nwaiters++;
}

static void waiter_unlink(ismd_waiter *w)
{
    ismd_flight *f = w->flight;
    w->prev->next = w->next;
    w->next->prev = w->prev;
    w->prev = w->next = NULL;
    w->flight = NULL;
    f->nwaiters--;
}

static long long seconds_ns(double s)
{
    return (long long)(s * 1e9);
}

static void publish_queue(ismd_sched *s)
{
    atomic_store(&s->metrics->queue_depth, (long long)s->queue->ops->length(s->queue));
}

static void wake_pool(ismd_sched *s)
{
    if (s->wake)
        s->wake(s->wake_ctx);
}
/* Workers ready and not computing: flights that would start at once, not wait. */
static size_t idle_workers(const ismd_sched *s)
{
    long long idle = atomic_load(&s->metrics->workers_ready) - atomic_load(&s->metrics->workers_busy) -
                     (long long)s->queue->ops->length(s->queue);
    return idle > 0 ? (size_t)idle : 0;
}


/* The submission of both entry points; ask_shared: a new flight goes to the shared stage
 * first (when there is one), else straight to the queue. */
static ismd_submit submit(ismd_sched *s, const char *key, const char *fmt, ism_blob *request,
                          const char *user, const ismd_user_limits *lim, ismd_waiter *w,
                          bool ask_shared)
{
    char name[ISM_CACHE_NAME_MAX];
    if (!ism_cache_name(name, key, fmt))
        return ISMD_SUBMIT_NO_MEMORY;
    ismd_flight **slot = flight_slot(s, name);
    if (*slot) {
        ismd_flight *f = *slot;
        waiter_append(f, w);
        atomic_fetch_add(&s->metrics->singleflight_joins, 1);
        if (!ask_shared && f->shared)
            ismd_sched_enqueue(s, f); /* computed here now (or answered, refused) */
        return ISMD_SUBMIT_JOINED;
    }
    if (s->draining)
        return ISMD_SUBMIT_DRAINING;
    ismd_flight *f = calloc(1, sizeof *f);
    if (!f)
        return ISMD_SUBMIT_NO_MEMORY;
    snprintf(f->name, sizeof f->name, "%s", name);
    snprintf(f->key, sizeof f->key, "%s", key);
    snprintf(f->fmt, sizeof f->fmt, "%s", fmt);
    snprintf(f->user, sizeof f->user, "%s", user);
    f->waiters.prev = f->waiters.next = &f->waiters;
    f->id = s->next_id;
    f->qe.user = f->user;
    f->qe.seq = f->id;
    s->queue->slack = idle_workers(s);
    switch (s->queue->ops->push(s->queue, &f->qe, lim)) {
    case ISMD_PUSH_OK:
        break;
    case ISMD_PUSH_USER_LIMIT:
        free(f);
        atomic_fetch_add(&s->metrics->rejected_client_limit, 1);
        return ISMD_SUBMIT_CLIENT_LIMIT;
    case ISMD_PUSH_FULL:
        free(f);
        atomic_fetch_add(&s->metrics->rejected_queue_full, 1);
        return ISMD_SUBMIT_QUEUE_FULL;
    default:
        free(f);
        return ISMD_SUBMIT_NO_MEMORY;
    }
    if (ask_shared && s->shared_begin) { /* admitted; the shared cache is asked first */
        s->queue->ops->drop(s->queue, &f->qe);
        f->lim = lim ? *lim : (ismd_user_limits){0};
        if (!s->shared_begin(s->shared_ctx, f)) {
            free(f);
            return ISMD_SUBMIT_NO_MEMORY;
        }
        f->shared = true;
    }
    s->next_id++;
    f->request = ism_blob_ref(request);
    f->submitted_ns = ism_now_ns();
    /* awaiting another daemon: its wait for a worker and its computation */
    f->deadline_ns = f->submitted_ns + seconds_ns(s->queue_timeout_s) +
                     (f->shared ? seconds_ns(s->job_timeout_s) : 0);
    f->hnext = NULL;
    *slot = f;
    f->aprev = s->all_tail;
    if (s->all_tail)
        s->all_tail->anext = f;
    else
        s->all_head = f;
    s->all_tail = f;
    s->nflights++;
    waiter_append(f, w);
    publish_queue(s);
    wake_pool(s);
    return ISMD_SUBMIT_NEW;
}

ismd_submit ismd_sched_submit(ismd_sched *s, const char *key, const char *fmt,
                              ism_blob *request, const char *user,
                              const ismd_user_limits *lim, ismd_waiter *w)
{
    return submit(s, key, fmt, request, user, lim, w, true);
}

ismd_submit ismd_sched_submit_here(ismd_sched *s, const char *key, const char *fmt,
                                   ism_blob *request, const char *user,
                                   const ismd_user_limits *lim, ismd_waiter *w)
{
    return submit(s, key, fmt, request, user, lim, w, false);
}

/* Takes f out of the table, the all-flights list and the queue's books, and frees it. */
static void flight_free(ismd_sched *s, ismd_flight *f)
{
    ismd_flight **slot = flight_slot(s, f->name);
    if (*slot == f)
        *slot = f->hnext;
    if (f->aprev)
        f->aprev->anext = f->anext;
    else
        s->all_head = f->anext;
    if (f->anext)
        f->anext->aprev = f->aprev;
    else
        s->all_tail = f->aprev;
    s->nflights--;
    s->queue->ops->drop(s->queue, &f->qe);
    ism_blob_unref(f->request);
    free(f);
}

/* Does nobody but the cluster executor of f's own queue entry wait for f? */
bool ismd_sched_only_passive(const ismd_flight *f)
{
    for (const ismd_waiter *w = f->waiters.next; w != &f->waiters; w = w->next)
        if (!w->passive)
            return false;
    return true;
}

void ismd_sched_detach(ismd_sched *s, ismd_waiter *w)
{
    ismd_flight *f = w->flight;
    if (!f)
        return;
    waiter_unlink(w);
    if (f->nwaiters > 0) /* passive ones alone: their executor decides (cluster.h) */
        return;
    if (f->qe.queued || f->shared) {
        atomic_fetch_add(&s->metrics->computations[ISMD_OUT_CANCELED], 1);
        flight_free(s, f);
        publish_queue(s);
    } else {
        wake_pool(s); /* running without waiters: the pool stops it */
    }
}

void ismd_sched_finish(ismd_sched *s, ismd_flight *f, const ismd_result *r, ismd_outcome o)
{
    bool was_queued = f->qe.queued;
    atomic_fetch_add(&s->metrics->computations[o], 1);
    while (f->waiters.next != &f->waiters) {
        ismd_waiter *w = f->waiters.next;
        waiter_unlink(w);
        w->done(w, r);
    }
    flight_free(s, f);
    if (was_queued)
        publish_queue(s);
}

void ismd_sched_fail(ismd_sched *s, ismd_flight *f, unsigned status, const char *code,
                     const char *message, ismd_outcome o)
{
    ismd_result r = {.status = status, .content_type = "application/json"};
    r.body = ismd_error_json(code, message, NULL);
    long long now = ism_now_ns();
    if (f->running) {
        r.queue_ms = (f->started_ns - f->submitted_ns) / 1e6;
        r.worker_ms = (now - f->started_ns) / 1e6;
    } else {
        r.queue_ms = (now - f->submitted_ns) / 1e6;
    }
    ismd_sched_finish(s, f, &r, o);
    ism_blob_unref(r.body);
}

void ismd_sched_cancel(ismd_sched *s, ismd_flight *f)
{
    if (f->running) {
        f->canceled = true;
        wake_pool(s);
        return;
    }
    ismd_sched_fail(s, f, 499, "canceled", "the job was canceled", ISMD_OUT_CANCELED);
}

void ismd_sched_progress(ismd_sched *s, ismd_flight *f, double fraction)
{
    (void)s;
    f->progress = fraction;
    for (ismd_waiter *w = f->waiters.next; w != &f->waiters; w = w->next)
        if (w->progress)
            w->progress(w, fraction, f->running || f->elsewhere);
}

ismd_flight *ismd_sched_next(ismd_sched *s)
{
    ismd_qentry *e = s->queue->ops->pop(s->queue);
    if (!e)
        return NULL;
    ismd_flight *f = FLIGHT_OF(e);
    publish_queue(s);
    f->running = true;
    f->started_ns = ism_now_ns();
    f->deadline_ns = f->started_ns + seconds_ns(s->job_timeout_s);
    struct timespec wall;
    clock_gettime(CLOCK_REALTIME, &wall);
    f->started_unix_ms = (long long)wall.tv_sec * 1000 + wall.tv_nsec / 1000000;
    atomic_fetch_add(&s->metrics->computations_started, 1);
    ismd_sched_progress(s, f, 0);
    return f;
}

size_t ismd_sched_expire(ismd_sched *s, long long now_ns, ismd_flight **expired, size_t max)
{
    size_t n = 0;
    char msg[200];
    ismd_flight *f = s->all_head;
    while (f) {
        ismd_flight *next = f->anext;
        if (f->deadline_ns <= now_ns) {
            if (f->running) {
                if (n < max)
                    expired[n++] = f;
            } else if (f->shared) {
                ismd_sched_fail(s, f, 504, "deadline_exceeded",
                                "the computation on another daemon did not finish in time "
                                "(--queue-timeout + --job-timeout)", ISMD_OUT_DEADLINE);
            } else {
                snprintf(msg, sizeof msg, "no worker became free for this computation within "
                         "%g s (--queue-timeout); every worker is busy, retry later",
                         s->queue_timeout_s);
                ismd_sched_fail(s, f, 503, "queue_timeout", msg, ISMD_OUT_DEADLINE);
            }
        }
        f = next;
    }
    return n;
}

long long ismd_sched_next_deadline(const ismd_sched *s)
{
    long long best = LLONG_MAX;
    for (const ismd_flight *f = s->all_head; f; f = f->anext)
        if (f->deadline_ns < best)
            best = f->deadline_ns;
    return best;
}

ismd_flight *ismd_sched_preempt_victim(ismd_sched *s)
{
    const ismd_queue_ops *q = s->queue->ops;
    ismd_flight *best = NULL;
    int best_n = 0;
    for (ismd_flight *f = s->all_head; f; f = f->anext) {
        if (!f->running)
            continue;
        int n = q->user_running(s->queue, &f->qe);
        if (n > best_n || (best && n == best_n && f->started_ns >= best->started_ns)) {
            best = f;
            best_n = n;
        }
    }
    /* a user must hold at least two workers to lose one to a user with none; above the
     * fair share (a half), one to a user below it. Either way the loser keeps at least as
     * many as the winner then has, so no worker is taken back and forth. */
    int share = s->queue->fair_share;
    bool starving = best_n >= 2 && q->waiting_below(s->queue, 1);
    bool over = share > 0 && best_n > share && q->waiting_below(s->queue, share);
    return starving || over ? best : NULL;
}

void ismd_sched_requeue(ismd_sched *s, ismd_flight *f)
{
    s->queue->ops->requeue(s->queue, &f->qe);
    f->running = false;
    f->deadline_ns = ism_now_ns() + seconds_ns(s->queue_timeout_s);
    atomic_fetch_add(&s->metrics->preemptions, 1);
    publish_queue(s);
    ismd_sched_progress(s, f, 0);
}

void ismd_sched_drain(ismd_sched *s)
{
    s->draining = true;
    ismd_flight *f = s->all_head;
    while (f) {
        ismd_flight *next = f->anext;
        if (f->qe.queued || f->shared)
            ismd_sched_fail(s, f, 503, "shutting_down",
                            "the server is shutting down; retry on another instance",
                            ISMD_OUT_CANCELED);
        f = next;
    }
}

/* ---- the shared cache's side (shared_cache.h) ---------------------------------------- */

ismd_flight *ismd_sched_find(ismd_sched *s, const char *name)
{
    return *flight_slot(s, name);
}

bool ismd_sched_enqueue(ismd_sched *s, ismd_flight *f)
{
    f->shared = false;
    f->elsewhere = false;
    f->deadline_ns = ism_now_ns() + seconds_ns(s->queue_timeout_s);
    s->queue->slack = idle_workers(s);
    ismd_push p = s->queue->ops->push(s->queue, &f->qe, &f->lim);
    if (p == ISMD_PUSH_OK) {
        publish_queue(s);
        wake_pool(s);
        return true;
    }
    ismd_result r = {.status = 500, .content_type = "application/json"};
    if (p == ISMD_PUSH_USER_LIMIT) {
        atomic_fetch_add(&s->metrics->rejected_client_limit, 1);
        r.status = 429;
        r.body = ismd_error_json("too_many_requests",
                                 "too many computations of yours are queued or running "
                                 "(--user-jobs); wait for one to finish", NULL);
    } else if (p == ISMD_PUSH_FULL) {
        atomic_fetch_add(&s->metrics->rejected_queue_full, 1);
        r.status = 503;
        r.body = ismd_error_json("queue_full",
                                 "every worker is busy and the queue is full; retry later", NULL);
    } else {
        r.body = ismd_error_json("out_of_memory", "the server ran out of memory", NULL);
    }
    ismd_sched_answer(s, f, &r);
    ism_blob_unref(r.body);
    return false;
}

void ismd_sched_answer(ismd_sched *s, ismd_flight *f, const ismd_result *r)
{
    while (f->waiters.next != &f->waiters) {
        ismd_waiter *w = f->waiters.next;
        waiter_unlink(w);
        w->done(w, r);
    }
    flight_free(s, f);
}

/* ---- flights whose entries are still being written (worker_pool.c) -------------------- */

bool ismd_sched_storing_begin(ismd_sched *s, const char *name)
{
    if (s->nstoring == s->storing_cap) {
        size_t cap = s->storing_cap ? 2 * s->storing_cap : 8;
        char(*grown)[ISM_CACHE_NAME_MAX] = realloc(s->storing, cap * sizeof *grown);
        if (!grown)
            return false;
        s->storing = grown;
        s->storing_cap = cap;
    }
    snprintf(s->storing[s->nstoring++], ISM_CACHE_NAME_MAX, "%s", name);
    return true;
}

void ismd_sched_storing_end(ismd_sched *s, const char *name)
{
    for (size_t i = 0; i < s->nstoring; i++)
        if (!strcmp(s->storing[i], name)) {
            memcpy(s->storing[i], s->storing[--s->nstoring], ISM_CACHE_NAME_MAX);
            return;
        }
}

bool ismd_sched_storing(const ismd_sched *s, const char *name)
{
    for (size_t i = 0; i < s->nstoring; i++)
        if (!strcmp(s->storing[i], name))
            return true;
    return false;
}
