/* parallel.h — runs numbered tasks on a few threads (work stealing over blocks of task
 * numbers): on the threads of a pool the caller keeps (pool.h), or on threads made and
 * joined for one loop. No global state. The order in which tasks run is not fixed, so tasks
 * must write only to their own slots. */
#ifndef ISM_PARALLEL_H
#define ISM_PARALLEL_H

#include <stddef.h>

#include "core/util/cache_line.h"
#include "core/util/pool.h"


/* What parallel loops cost, in CPU milliseconds of each thread (CLOCK_THREAD_CPUTIME_ID),
 * added up over the loops it was passed to: all threads together; the calling thread's
 * share; per loop the busiest thread's (the loop's wall time on idle cores, but on loaded
 * ones a thread that starts late leaves its tasks to the others); and per loop the even
 * share max(CPU / threads, longest task) — what a fair split of the same tasks would take,
 * whatever the scheduler did. */
typedef struct ism_par_cost {
    double cpu_ms, caller_ms, busiest_ms, even_ms;
} ism_par_cost;

/* Calls fn(ctx, task, thread) once for every task in [0, ntasks), on the threads of pool
 * (thread is 0..ism_pool_threads(pool)-1, so per-thread state can be indexed by it; a NULL
 * pool runs every task on the calling thread), adding what the loop cost to *cost (when not
 * NULL). */
void ism_pool_for(ism_pool *pool, size_t ntasks, void (*fn)(void *ctx, size_t task, int thread),
                  void *ctx, ism_par_cost *cost);

/* The same on `threads` threads made for this loop alone (thread is 0..threads-1). */
void ism_parallel_for(int threads, size_t ntasks, void (*fn)(void *ctx, size_t task, int thread),
                      void *ctx);

/* The same, adding what the loop cost to *cost (when not NULL). */
void ism_parallel_for_costed(int threads, size_t ntasks,
                             void (*fn)(void *ctx, size_t task, int thread), void *ctx,
                             ism_par_cost *cost);

/* Turns per-task counts into where each task's output starts (an exclusive prefix sum, in
 * place); returns the total. What a loop counted per task, the next one writes at. */
static inline size_t ism_counts_to_offsets(size_t *v, size_t n)
{
    size_t sum = 0;
    for (size_t k = 0; k < n; k++) {
        size_t c = v[k];
        v[k] = sum;
        sum += c;
    }
    return sum;
}

/* Blocks of `per` items that cover n items (the last one may be short). */
static inline size_t ism_blocks(size_t n, size_t per) { return (n + per - 1) / per; }

/* Where block blk of `per` items ends among n items: min((blk + 1) * per, n) (it starts at
 * blk * per). */
static inline size_t ism_block_end(size_t blk, size_t per, size_t n)
{
    return (blk + 1) * per < n ? (blk + 1) * per : n;
}

/* Number of online processors (at least 1). */
int ism_cpu_count(void);

/* Threads a computation that asked for `requested` runs on, given `cores` online: requested,
 * or every core when 0 (the rule of every threads option), in 1..ISM_MAX_THREADS. */
static inline int ism_threads_given(int requested, int cores)
{
    int n = requested > 0 ? requested : cores;
    return n < 1 ? 1 : n > ISM_MAX_THREADS ? ISM_MAX_THREADS : n;
}

/* The same on this machine's cores (ism_cpu_count). */
int ism_threads_resolve(int requested);

#endif
