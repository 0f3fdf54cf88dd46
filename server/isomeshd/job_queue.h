/* job_queue.h — where computations wait for a free worker: a small interface (push, pop,
 * remove, length) so the policy can change without touching the pool — today a bounded FIFO;
 * fair per-user scheduling later is another implementation of the same operations.
 * Not thread-safe by itself: the scheduler's lock (sched.h) guards every call. */
#ifndef ISMD_JOB_QUEUE_H
#define ISMD_JOB_QUEUE_H

#include <stdbool.h>
#include <stddef.h>

typedef struct ismd_flight ismd_flight;
typedef struct ismd_queue ismd_queue;

typedef struct ismd_queue_ops {
    const char *name;
    /* False when the queue is full (the caller answers 503). */
    bool (*push)(ismd_queue *q, ismd_flight *f);
    /* The next flight to run, or NULL. */
    ismd_flight *(*pop)(ismd_queue *q);
    /* Takes out a flight that is still queued (canceled or past its deadline). */
    void (*remove)(ismd_queue *q, ismd_flight *f);
    size_t (*length)(const ismd_queue *q);
    void (*destroy)(ismd_queue *q);
} ismd_queue_ops;

struct ismd_queue {
    const ismd_queue_ops *ops;
    size_t capacity;
};

/* First come, first served, at most capacity flights. */
ismd_queue *ismd_queue_fifo_new(size_t capacity);

#endif
