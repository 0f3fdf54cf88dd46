/* parallel.c — a fork/join loop over numbered tasks on pthreads. */
#include "core/util/parallel.h"

#include <pthread.h>
#include <stdatomic.h>
#include <unistd.h>

#define MAX_THREADS 64

typedef struct loop {
    void (*fn)(void *, size_t, int);
    void *ctx;
    size_t ntasks;
    atomic_size_t next;
} loop;

typedef struct worker {
    loop *l;
    int id;
} worker;

static void run_tasks(loop *l, int id)
{
    for (;;) {
        size_t t = atomic_fetch_add(&l->next, 1);
        if (t >= l->ntasks)
            return;
        l->fn(l->ctx, t, id);
    }
}

static void *thread_main(void *arg)
{
    worker *w = arg;
    run_tasks(w->l, w->id);
    return NULL;
}

void ism_parallel_for(int threads, size_t ntasks, void (*fn)(void *, size_t, int), void *ctx)
{
    loop l = {fn, ctx, ntasks, 0};
    if (threads > MAX_THREADS)
        threads = MAX_THREADS;
    if ((size_t)threads > ntasks)
        threads = (int)ntasks;
    pthread_t tid[MAX_THREADS];
    worker w[MAX_THREADS];
    int started = 0;
    for (int i = 1; i < threads; i++) {
        w[i] = (worker){&l, i};
        if (pthread_create(&tid[i], NULL, thread_main, &w[i]) != 0)
            break; /* fewer threads: the calling thread still runs every remaining task */
        started = i;
    }
    run_tasks(&l, 0);
    for (int i = 1; i <= started; i++)
        pthread_join(tid[i], NULL);
}

int ism_cpu_count(void)
{
    long n = sysconf(_SC_NPROCESSORS_ONLN);
    return n < 1 ? 1 : (int)n;
}
