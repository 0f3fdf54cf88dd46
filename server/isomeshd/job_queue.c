/* job_queue.c — the bounded FIFO implementation of job_queue.h, threaded through the
 * flights' own queue links (no allocation per push). */
#include "server/isomeshd/job_queue.h"

#include <stdlib.h>

#include "server/isomeshd/sched.h"

typedef struct fifo {
    ismd_queue base;
    ismd_flight *head, *tail;
    size_t len;
} fifo;

static bool fifo_push(ismd_queue *q, ismd_flight *f)
{
    fifo *x = (fifo *)q;
    if (x->len >= q->capacity)
        return false;
    f->qnext = NULL;
    f->qprev = x->tail;
    if (x->tail)
        x->tail->qnext = f;
    else
        x->head = f;
    x->tail = f;
    x->len++;
    f->queued = true;
    return true;
}

static void fifo_remove(ismd_queue *q, ismd_flight *f)
{
    fifo *x = (fifo *)q;
    if (!f->queued)
        return;
    if (f->qprev)
        f->qprev->qnext = f->qnext;
    else
        x->head = f->qnext;
    if (f->qnext)
        f->qnext->qprev = f->qprev;
    else
        x->tail = f->qprev;
    f->qprev = f->qnext = NULL;
    f->queued = false;
    x->len--;
}

static ismd_flight *fifo_pop(ismd_queue *q)
{
    fifo *x = (fifo *)q;
    ismd_flight *f = x->head;
    if (f)
        fifo_remove(q, f);
    return f;
}

static size_t fifo_length(const ismd_queue *q)
{
    return ((const fifo *)q)->len;
}

static void fifo_destroy(ismd_queue *q)
{
    free(q);
}

static const ismd_queue_ops FIFO_OPS = {
    .name = "fifo",
    .push = fifo_push,
    .pop = fifo_pop,
    .remove = fifo_remove,
    .length = fifo_length,
    .destroy = fifo_destroy,
};

ismd_queue *ismd_queue_fifo_new(size_t capacity)
{
    fifo *x = calloc(1, sizeof *x);
    if (!x)
        return NULL;
    x->base.ops = &FIFO_OPS;
    x->base.capacity = capacity;
    return &x->base;
}
