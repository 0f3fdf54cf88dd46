/* job_queue.h — where computations wait for a free worker: a small interface (push, pop, drop,
 * length, per-user loads) so the policy can change without touching the pool.
 *
 * Every flight belongs to the user who started it (a token's user, or a client address) and
 * waits in that user's own line. The queue keeps each user's counts and enforces the per-user
 * limits: at most max_jobs computations queued or running (more is refused: 429), at most
 * max_running of them on workers at once (the rest wait even when a worker is free). Two
 * orders serve the lines:
 *   fair  the user with the fewest computations running goes next, ties to the user served
 *         longest ago (round robin): a user with a hundred queued jobs gets one worker turn at
 *         a time while everyone else with work waiting gets theirs;
 *   fifo  the oldest flight of any user goes next (kept as the reference for benchmarks).
 * Not thread-safe by itself: the scheduler's lock (sched.h) guards every call. */
#ifndef ISMD_JOB_QUEUE_H
#define ISMD_JOB_QUEUE_H

#include <stdbool.h>
#include <stddef.h>

#define ISMD_QUEUE_USER_MAX 64   /* user name, NUL included */

typedef struct ismd_queue ismd_queue;
typedef struct ismd_qline ismd_qline; /* one user's line (private to the queue) */

/* What the queue keeps of one computation: its links in its user's line and its state there.
 * The scheduler embeds one in each flight (sched.h) and fills user and seq before a push; the
 * queue reads and writes nothing else of the flight. */
typedef struct ismd_qentry ismd_qentry;
struct ismd_qentry {
    const char *user;          /* its user (kept alive by the owner while on the books) */
    unsigned long long seq;    /* arrival order: the fifo order */
    bool queued;               /* waiting in its line */
    bool running;              /* popped and counted against its user, not yet dropped */
    ismd_qline *line;          /* NULL: not on the queue's books */
    ismd_qentry *prev, *next;  /* in its line, oldest first */
};

typedef enum ismd_queue_order { ISMD_ORDER_FAIR, ISMD_ORDER_FIFO } ismd_queue_order;

/* One user's limits for a push; 0 = the queue's defaults. */
typedef struct ismd_user_limits {
    int max_jobs, max_running;
} ismd_user_limits;

typedef enum ismd_push {
    ISMD_PUSH_OK,
    ISMD_PUSH_FULL,          /* the whole queue is at capacity (503) */
    ISMD_PUSH_USER_LIMIT,    /* this user has max_jobs queued or running (429) */
    ISMD_PUSH_NO_MEMORY,
} ismd_push;

/* A user with computations queued or running. */
typedef struct ismd_user_load {
    char user[ISMD_QUEUE_USER_MAX];
    int queued, running;
} ismd_user_load;

typedef struct ismd_queue_ops {
    const char *name;
    /* Queues e in the line of e->user. */
    ismd_push (*push)(ismd_queue *q, ismd_qentry *e, const ismd_user_limits *lim);
    /* The next entry to run (now counted as running for its user), or NULL. */
    ismd_qentry *(*pop)(ismd_queue *q);
    /* e leaves the queue's books for good (finished, canceled, past its deadline): a queued
     * entry leaves its line, a running one stops counting against its user. */
    void (*drop)(ismd_queue *q, ismd_qentry *e);
    size_t (*length)(const ismd_queue *q);
    /* True when a user with fewer than n computations running has a flight waiting that may
     * run (fair order only: the pool then frees a worker from a user holding more, see
     * sched.h). */
    bool (*waiting_below)(const ismd_queue *q, int n);
    /* Computations of e's user running now. */
    int (*user_running)(const ismd_queue *q, const ismd_qentry *e);
    /* A running e goes back to the head of its user's line (it was preempted). */
    void (*requeue)(ismd_queue *q, ismd_qentry *e);
    /* Fills up to max users with work; returns how many there are in all. */
    size_t (*users)(const ismd_queue *q, ismd_user_load *out, size_t max);
    void (*destroy)(ismd_queue *q);
} ismd_queue_ops;

struct ismd_queue {
    const ismd_queue_ops *ops;
    size_t capacity;
    size_t slack;       /* idle workers when a flight is pushed: that many will not wait, so
                           they do not count against capacity (a --queue 0 daemon still runs
                           one computation per idle worker) */
    int fair_share;     /* fair order without a default running limit: half the workers,
                           rounded up, the most a user keeps while other users wait (sched.h
                           preempts above it); 0 = none */
};

/* At most capacity flights waiting; user_jobs and user_running are the default per-user
 * limits. user_running 0: a user may run on every one of the workers while nobody else
 * waits, and on half of them (rounded up) while other users do (fair order). */
ismd_queue *ismd_queue_new(size_t capacity, ismd_queue_order order, int user_jobs,
                           int user_running, int workers);

#endif
