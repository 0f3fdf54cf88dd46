/* job_queue.c — the per-user queue of job_queue.h: a line per user (entries threaded through
 * their own links, no allocation per push), a name table of lines, and the two orders.
 * A line exists while its user has anything queued or running, so the lines are bounded by
 * the queue's capacity plus the workers, and pop scans them (a few dozen on a lab server). */
#include "server/isomeshd/job_queue.h"
#include "server/common/text_hash.h"

#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define NBUCKETS 256

struct ismd_qline {
    char user[ISMD_QUEUE_USER_MAX];
    int queued, running;
    int max_jobs, max_running;     /* as given by the user's latest push */
    unsigned long long last_turn;  /* when this user last got a worker (0 = not yet) */
    ismd_qentry *head, *tail;      /* waiting entries, oldest first */
    ismd_qline *hnext;             /* name table chain */
    ismd_qline *prev, *next;       /* every line */
};

typedef struct uqueue {
    ismd_queue base;
    ismd_queue_order order;
    int user_jobs, user_running;
    ismd_qline *buckets[NBUCKETS];
    ismd_qline *lines;
    size_t len;
    unsigned long long turns;
} uqueue;

static ismd_qline **line_slot(uqueue *x, const char *user)
{
    ismd_qline **l = &x->buckets[ism_text_hash(user) % NBUCKETS];
    while (*l && strcmp((*l)->user, user) != 0)
        l = &(*l)->hnext;
    return l;
}

static ismd_qline *line_get(uqueue *x, const char *user)
{
    ismd_qline **slot = line_slot(x, user);
    if (*slot)
        return *slot;
    ismd_qline *l = calloc(1, sizeof *l);
    if (!l)
        return NULL;
    snprintf(l->user, sizeof l->user, "%s", user);
    *slot = l;
    l->next = x->lines;
    if (x->lines)
        x->lines->prev = l;
    x->lines = l;
    return l;
}

/* Frees a line with nothing queued or running. */
static void line_release(uqueue *x, ismd_qline *l)
{
    if (l->queued > 0 || l->running > 0)
        return;
    ismd_qline **slot = line_slot(x, l->user);
    if (*slot == l)
        *slot = l->hnext;
    if (l->prev)
        l->prev->next = l->next;
    else
        x->lines = l->next;
    if (l->next)
        l->next->prev = l->prev;
    free(l);
}

static ismd_push q_push(ismd_queue *q, ismd_qentry *e, const ismd_user_limits *lim)
{
    uqueue *x = (uqueue *)q;
    ismd_qline *l = line_get(x, e->user);
    if (!l)
        return ISMD_PUSH_NO_MEMORY;
    l->max_jobs = lim && lim->max_jobs > 0 ? lim->max_jobs : x->user_jobs;
    l->max_running = lim && lim->max_running > 0 ? lim->max_running : x->user_running;
    if (l->queued + l->running >= l->max_jobs) {
        line_release(x, l);
        return ISMD_PUSH_USER_LIMIT;
    }
    if (x->len >= q->capacity + q->slack) {
        line_release(x, l);
        return ISMD_PUSH_FULL;
    }
    e->line = l;
    e->next = NULL;
    e->prev = l->tail;
    if (l->tail)
        l->tail->next = e;
    else
        l->head = e;
    l->tail = e;
    l->queued++;
    x->len++;
    e->queued = true;
    return ISMD_PUSH_OK;
}

static void unlink_queued(uqueue *x, ismd_qentry *e)
{
    ismd_qline *l = e->line;
    if (e->prev)
        e->prev->next = e->next;
    else
        l->head = e->next;
    if (e->next)
        e->next->prev = e->prev;
    else
        l->tail = e->prev;
    e->prev = e->next = NULL;
    e->queued = false;
    l->queued--;
    x->len--;
}

static void q_drop(ismd_queue *q, ismd_qentry *e)
{
    uqueue *x = (uqueue *)q;
    ismd_qline *l = e->line;
    if (!l)
        return;
    if (e->queued)
        unlink_queued(x, e);
    else if (e->running)
        l->running--;
    e->running = false;
    e->line = NULL;
    line_release(x, l);
}

static bool may_run(const ismd_qline *l)
{
    return l->head && (l->max_running <= 0 || l->running < l->max_running);
}

/* fair: fewest running first, then the user served longest ago. */
static bool fair_before(const ismd_qline *a, const ismd_qline *b)
{
    if (a->running != b->running)
        return a->running < b->running;
    return a->last_turn < b->last_turn;
}

/* fifo: the oldest waiting entry. */
static bool fifo_before(const ismd_qline *a, const ismd_qline *b)
{
    return a->head->seq < b->head->seq;
}

static ismd_qentry *pop_with(ismd_queue *q, bool (*before)(const ismd_qline *, const ismd_qline *))
{
    uqueue *x = (uqueue *)q;
    ismd_qline *best = NULL;
    for (ismd_qline *l = x->lines; l; l = l->next)
        if (may_run(l) && (!best || before(l, best)))
            best = l;
    if (!best)
        return NULL;
    ismd_qentry *e = best->head;
    unlink_queued(x, e);
    e->running = true;
    best->running++;
    best->last_turn = ++x->turns;
    return e;
}

static ismd_qentry *fair_pop(ismd_queue *q)
{
    return pop_with(q, fair_before);
}

static ismd_qentry *fifo_pop(ismd_queue *q)
{
    return pop_with(q, fifo_before);
}

static bool fair_waiting_below(const ismd_queue *q, int n)
{
    for (const ismd_qline *l = ((const uqueue *)q)->lines; l; l = l->next)
        if (l->running < n && may_run(l))
            return true;
    return false;
}

static bool fifo_waiting_below(const ismd_queue *q, int n)
{
    (void)q;
    (void)n;
    return false; /* the reference order: served as it came, nobody preempted */
}

static int q_user_running(const ismd_queue *q, const ismd_qentry *e)
{
    (void)q;
    return e->line ? e->line->running : 0;
}

static void q_requeue(ismd_queue *q, ismd_qentry *e)
{
    uqueue *x = (uqueue *)q;
    ismd_qline *l = e->line;
    if (!l || !e->running)
        return;
    e->running = false;
    l->running--;
    e->prev = NULL;
    e->next = l->head;
    if (l->head)
        l->head->prev = e;
    else
        l->tail = e;
    l->head = e;
    l->queued++;
    x->len++;
    e->queued = true;
}

static size_t q_length(const ismd_queue *q)
{
    return ((const uqueue *)q)->len;
}

static size_t q_users(const ismd_queue *q, ismd_user_load *out, size_t max)
{
    const uqueue *x = (const uqueue *)q;
    size_t n = 0;
    for (const ismd_qline *l = x->lines; l; l = l->next, n++)
        if (n < max) {
            snprintf(out[n].user, sizeof out[n].user, "%s", l->user);
            out[n].queued = l->queued;
            out[n].running = l->running;
        }
    return n;
}

static void q_destroy(ismd_queue *q)
{
    uqueue *x = (uqueue *)q;
    while (x->lines) {
        ismd_qline *l = x->lines;
        x->lines = l->next;
        free(l);
    }
    free(x);
}

static const ismd_queue_ops FAIR_OPS = {
    .name = "fair", .push = q_push, .pop = fair_pop, .drop = q_drop,
    .length = q_length, .waiting_below = fair_waiting_below, .user_running = q_user_running,
    .requeue = q_requeue, .users = q_users, .destroy = q_destroy,
};

static const ismd_queue_ops FIFO_OPS = {
    .name = "fifo", .push = q_push, .pop = fifo_pop, .drop = q_drop,
    .length = q_length, .waiting_below = fifo_waiting_below, .user_running = q_user_running,
    .requeue = q_requeue, .users = q_users, .destroy = q_destroy,
};

ismd_queue *ismd_queue_new(size_t capacity, ismd_queue_order order, int user_jobs,
                           int user_running, int workers)
{
    uqueue *x = calloc(1, sizeof *x);
    if (!x)
        return NULL;
    x->base.ops = order == ISMD_ORDER_FIFO ? &FIFO_OPS : &FAIR_OPS;
    x->base.capacity = capacity;
    x->order = order;
    x->user_jobs = user_jobs > 0 ? user_jobs : 1;
    x->user_running = user_running;
    if (order == ISMD_ORDER_FAIR && user_running <= 0)
        x->base.fair_share = (workers + 1) / 2;
    return &x->base;
}
