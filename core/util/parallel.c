/* parallel.c — a fork/join loop over numbered tasks on a pool's threads (pool.h), and what
 * it cost. Each
 * thread starts on its own contiguous block of task numbers (neighbouring tasks share
 * memoised work, so a thread keeps its locality); one that runs dry steals the upper half of
 * the largest block left. A block is one atomic word (next and end task), claimed from the
 * front by its owner and split from the back by thieves with compare-and-swap: no lock, and
 * the owner's word stays in its own cache line until someone steals. */
#include "core/util/parallel.h"
#include "core/util/clock.h"

#include <stdalign.h>
#include <stdatomic.h>
#include <stdbool.h>
#include <stdint.h>
#include <unistd.h>

/* Task numbers [lo, hi) packed as lo << 32 | hi (task counts stay below 2^32). */
typedef struct block {
    alignas(ISM_CACHE_LINE) _Atomic uint64_t range; /* a line each: claims do not bounce */
} block;

struct loop;

typedef struct worker {
    alignas(ISM_CACHE_LINE) struct loop *l; /* a line each: written per task */
    int id;
    double cpu_ms;     /* the thread's CPU while it ran tasks */
    double longest_ms; /* its longest task's */
} worker;

typedef struct loop {
    void (*fn)(void *, size_t, int);
    void *ctx;
    int threads;
    bool timed;        /* each task's CPU is read (for an ism_par_cost) */
    block blocks[ISM_MAX_THREADS];
    worker w[ISM_MAX_THREADS];
} loop;

static uint64_t pack(uint32_t lo, uint32_t hi) { return (uint64_t)lo << 32 | hi; }
static uint32_t lo_of(uint64_t r) { return (uint32_t)(r >> 32); }
static uint32_t hi_of(uint64_t r) { return (uint32_t)r; }

/* The next task of block b from its front, or false when it is empty. */
static bool claim(block *b, uint32_t *task)
{
    uint64_t r = atomic_load_explicit(&b->range, memory_order_relaxed);
    for (;;) {
        if (lo_of(r) >= hi_of(r))
            return false;
        if (atomic_compare_exchange_weak(&b->range, &r, pack(lo_of(r) + 1, hi_of(r)))) {
            *task = lo_of(r);
            return true;
        }
    }
}

/* Moves the upper half of the largest other block into thread id's (empty) block; false
 * when every block is empty. Only a block's owner grows it, and only while it is empty, so
 * thieves that saw it empty never race with the store. */
static bool steal(loop *l, int id)
{
    for (;;) {
        int victim = -1;
        uint32_t most = 0;
        uint64_t seen = 0;
        for (int t = 0; t < l->threads; t++) {
            uint64_t r = atomic_load_explicit(&l->blocks[t].range, memory_order_relaxed);
            uint32_t left = lo_of(r) < hi_of(r) ? hi_of(r) - lo_of(r) : 0;
            if (t != id && left > most) {
                most = left;
                victim = t;
                seen = r;
            }
        }
        if (victim < 0)
            return false;
        uint32_t lo = lo_of(seen), hi = hi_of(seen), mid = lo + (hi - lo) / 2;
        if (atomic_compare_exchange_strong(&l->blocks[victim].range, &seen, pack(lo, mid))) {
            atomic_store(&l->blocks[id].range, pack(mid, hi));
            return true;
        }
    }
}

static void run_tasks(worker *w)
{
    loop *l = w->l;
    block *own = &l->blocks[w->id];
    double t0 = l->timed ? ism_thread_cpu_ms() : 0, t = t0;
    for (;;) {
        uint32_t task;
        if (claim(own, &task)) {
            l->fn(l->ctx, task, w->id);
            if (!l->timed)
                continue;
            double now = ism_thread_cpu_ms();
            w->longest_ms = now - t > w->longest_ms ? now - t : w->longest_ms;
            t = now;
        } else if (!steal(l, w->id)) {
            break;
        }
    }
    w->cpu_ms = l->timed ? ism_thread_cpu_ms() - t0 : 0;
}

/* The pool's job: thread id runs tasks until none is left anywhere. */
static void run_job(void *arg, int id)
{
    loop *l = arg;
    run_tasks(&l->w[id]);
}

/* Loops too long for a packed block, run in slices. */
static void run_in_slices(ism_pool *pool, size_t ntasks, void (*fn)(void *, size_t, int),
                          void *ctx, ism_par_cost *cost);

void ism_pool_for(ism_pool *pool, size_t ntasks, void (*fn)(void *, size_t, int), void *ctx,
                  ism_par_cost *cost)
{
    if (ntasks > UINT32_MAX) {
        run_in_slices(pool, ntasks, fn, ctx, cost);
        return;
    }
    int threads = ism_pool_threads(pool);
    if (threads > ISM_MAX_THREADS)
        threads = ISM_MAX_THREADS;
    if ((size_t)threads > ntasks)
        threads = (int)ntasks;
    if (threads < 1)
        return;
    loop l;
    l.fn = fn;
    l.ctx = ctx;
    l.timed = cost != NULL;
    for (int i = 0; i < threads; i++) { /* blocks for every thread before any starts */
        atomic_init(&l.blocks[i].range, pack((uint32_t)(ntasks * (size_t)i / (size_t)threads),
                                             (uint32_t)(ntasks * (size_t)(i + 1) /
                                                        (size_t)threads)));
        l.w[i] = (worker){&l, i, 0, 0};
    }
    l.threads = threads;
    ism_pool_run(pool, threads, run_job, &l);
    if (!cost)
        return;
    double busiest = 0, longest = 0, all = 0;
    for (int i = 0; i < threads; i++) {
        all += l.w[i].cpu_ms;
        busiest = l.w[i].cpu_ms > busiest ? l.w[i].cpu_ms : busiest;
        longest = l.w[i].longest_ms > longest ? l.w[i].longest_ms : longest;
    }
    cost->cpu_ms += all;
    cost->caller_ms += l.w[0].cpu_ms;
    cost->busiest_ms += busiest;
    cost->even_ms += all / threads > longest ? all / threads : longest;
}

void ism_parallel_for_costed(int threads, size_t ntasks, void (*fn)(void *, size_t, int),
                             void *ctx, ism_par_cost *cost)
{
    if (threads > ISM_MAX_THREADS)
        threads = ISM_MAX_THREADS;
    if ((size_t)threads > ntasks)
        threads = (int)ntasks;
    ism_pool *pool = threads > 1 ? ism_pool_new(threads) : NULL;
    ism_pool_for(pool, ntasks, fn, ctx, cost); /* no pool: the calling thread alone */
    ism_pool_free(pool);
}

/* Task numbers offset into a slice: fn sees the loop's own numbering. */
typedef struct slice {
    void (*fn)(void *, size_t, int);
    void *ctx;
    size_t first;
} slice;

static void slice_task(void *arg, size_t task, int thread)
{
    slice *s = arg;
    s->fn(s->ctx, s->first + task, thread);
}

static void run_in_slices(ism_pool *pool, size_t ntasks, void (*fn)(void *, size_t, int),
                          void *ctx, ism_par_cost *cost)
{
    for (size_t first = 0; first < ntasks; first += UINT32_MAX) {
        slice s = {fn, ctx, first};
        size_t n = ntasks - first < UINT32_MAX ? ntasks - first : UINT32_MAX;
        ism_pool_for(pool, n, slice_task, &s, cost);
    }
}

void ism_parallel_for(int threads, size_t ntasks, void (*fn)(void *, size_t, int), void *ctx)
{
    ism_parallel_for_costed(threads, ntasks, fn, ctx, NULL);
}

int ism_cpu_count(void)
{
    long n = sysconf(_SC_NPROCESSORS_ONLN);
    return n < 1 ? 1 : (int)n;
}

int ism_threads_resolve(int requested)
{
    return ism_threads_given(requested, ism_cpu_count());
}
