/* pool.c — the threads of one computation, waiting between jobs. A job is published under
 * the pool's lock with a new generation number; each worker wakes on the generation's change,
 * runs its share if its number is below the job's width, and the last one back signals the
 * caller. Workers only read the job through the pool (not the caller's stack) and only while
 * the caller is waiting for them, so a job's data may live on the caller's stack. */
#include "core/util/pool.h"

#include <pthread.h>
#include <stdbool.h>
#include <stdint.h>
#include <stdlib.h>

typedef struct worker {
    ism_pool *pool;
    int id;
} worker;

struct ism_pool {
    pthread_mutex_t lock;
    pthread_cond_t start; /* a new generation (or quit) */
    pthread_cond_t done;  /* the last worker of a job is back */
    uint64_t generation;
    int width;            /* threads of the current job, the caller included */
    int running;          /* workers of the current job not back yet */
    bool quit;
    void (*job)(void *, int);
    void *arg;
    int nthreads;         /* 1 + workers started */
    pthread_t tid[ISM_MAX_THREADS];
    worker w[ISM_MAX_THREADS];
};

static void *worker_main(void *a)
{
    worker *w = a;
    ism_pool *p = w->pool;
    uint64_t seen = 0;
    pthread_mutex_lock(&p->lock);
    for (;;) {
        while (p->generation == seen && !p->quit)
            pthread_cond_wait(&p->start, &p->lock);
        if (p->quit)
            break;
        seen = p->generation;
        if (w->id >= p->width)
            continue; /* not in this job */
        void (*job)(void *, int) = p->job;
        void *arg = p->arg;
        pthread_mutex_unlock(&p->lock);
        job(arg, w->id);
        pthread_mutex_lock(&p->lock);
        if (--p->running == 0)
            pthread_cond_signal(&p->done);
    }
    pthread_mutex_unlock(&p->lock);
    return NULL;
}

ism_pool *ism_pool_new(int threads)
{
    ism_pool *p = calloc(1, sizeof *p);
    if (!p)
        return NULL;
    if (threads > ISM_MAX_THREADS)
        threads = ISM_MAX_THREADS;
    pthread_mutex_init(&p->lock, NULL);
    pthread_cond_init(&p->start, NULL);
    pthread_cond_init(&p->done, NULL);
    p->nthreads = 1;
    for (int i = 1; i < threads; i++) {
        p->w[i] = (worker){p, i};
        if (pthread_create(&p->tid[i], NULL, worker_main, &p->w[i]) != 0)
            break; /* fewer threads: jobs run narrower */
        p->nthreads = i + 1;
    }
    return p;
}

void ism_pool_free(ism_pool *p)
{
    if (!p)
        return;
    pthread_mutex_lock(&p->lock);
    p->quit = true;
    pthread_cond_broadcast(&p->start);
    pthread_mutex_unlock(&p->lock);
    for (int i = 1; i < p->nthreads; i++)
        pthread_join(p->tid[i], NULL);
    pthread_cond_destroy(&p->start);
    pthread_cond_destroy(&p->done);
    pthread_mutex_destroy(&p->lock);
    free(p);
}

int ism_pool_threads(const ism_pool *p) { return p ? p->nthreads : 1; }

void ism_pool_run(ism_pool *p, int n, void (*job)(void *arg, int id), void *arg)
{
    int width = n < ism_pool_threads(p) ? n : ism_pool_threads(p);
    if (width < 1)
        return;
    if (width > 1) {
        pthread_mutex_lock(&p->lock);
        p->job = job;
        p->arg = arg;
        p->width = width;
        p->running = width - 1;
        p->generation++;
        pthread_cond_broadcast(&p->start);
        pthread_mutex_unlock(&p->lock);
    }
    job(arg, 0);
    if (width > 1) {
        pthread_mutex_lock(&p->lock);
        while (p->running > 0)
            pthread_cond_wait(&p->done, &p->lock);
        pthread_mutex_unlock(&p->lock);
    }
}
