/* blocks.c — runs independent blocks of analysis work (vertex or triangle ranges that
 * evaluate f) on a few threads, each with its own evaluation workspace, handing out blocks
 * from an atomic counter. Results land in per-block slots, so they never depend on which
 * thread ran what. */
#include "core/analysis/blocks.h"

#include <pthread.h>
#include <stdatomic.h>
#include <unistd.h>

#define MAX_THREADS 64

typedef struct block_queue {
    ism_an_block_fn fn;
    void *ctx;
    size_t nblocks;
    atomic_size_t next;
} block_queue;

typedef struct worker {
    block_queue *q;
    ism_eval_ws *ws;
} worker;

int ism_an_threads(int t)
{
    if (t <= 0) {
        long n = sysconf(_SC_NPROCESSORS_ONLN);
        t = n > 0 ? (int)(n < MAX_THREADS ? n : MAX_THREADS) : 1;
    }
    return t < MAX_THREADS ? t : MAX_THREADS;
}

static void drain(block_queue *q, ism_eval_ws *ws)
{
    for (;;) {
        size_t b = atomic_fetch_add(&q->next, 1);
        if (b >= q->nblocks)
            return;
        q->fn(q->ctx, ws, b);
    }
}

static void *worker_main(void *arg)
{
    worker *w = arg;
    drain(w->q, w->ws);
    return NULL;
}

bool ism_an_run_blocks(const ism_tape *f, int threads, size_t nblocks, ism_an_block_fn fn,
                       void *ctx)
{
    block_queue q = {.fn = fn, .ctx = ctx, .nblocks = nblocks};
    atomic_init(&q.next, 0);
    int nt = ism_an_threads(threads);
    if ((size_t)nt > nblocks)
        nt = nblocks ? (int)nblocks : 1;
    worker w[MAX_THREADS];
    pthread_t tid[MAX_THREADS];
    bool started[MAX_THREADS] = {false};
    for (int i = 0; i < nt; i++)
        w[i] = (worker){.q = &q, .ws = ism_eval_ws_new(f)};
    if (!w[0].ws) {
        for (int i = 1; i < nt; i++)
            if (w[i].ws)
                ism_eval_ws_free(w[i].ws);
        return false;
    }
    for (int i = 1; i < nt; i++)
        started[i] = w[i].ws && pthread_create(&tid[i], NULL, worker_main, &w[i]) == 0;
    drain(&q, w[0].ws); /* the calling thread works too, and finishes alone if need be */
    for (int i = 1; i < nt; i++)
        if (started[i])
            pthread_join(tid[i], NULL);
    for (int i = 0; i < nt; i++)
        if (w[i].ws)
            ism_eval_ws_free(w[i].ws);
    return true;
}
