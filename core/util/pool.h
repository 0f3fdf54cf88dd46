/* pool.h — a few threads kept for the length of one computation (one ism_polygonise call):
 * made once, then told again and again to run a job on each of them, so the many parallel
 * loops of one call do not each create and join threads (each new thread faults in a fresh
 * stack, may land on another core and starts with cold caches). Between jobs the workers
 * sleep on a condition variable: an idle pool takes no CPU. The caller owns the pool; there
 * is no shared or global pool. */
#ifndef ISM_POOL_H
#define ISM_POOL_H

typedef struct ism_pool ism_pool;

/* Threads one computation runs at most: a pool's size, a parallel loop's width, and the
 * range every threads option accepts (--threads, a request's field, ism_*_options.threads).
 * Why a cap at all: per-thread state lives in fixed-size arrays (a parallel loop's on its
 * caller's stack). */
#define ISM_MAX_THREADS 64

/* A pool of `threads` threads in all: the calling thread (number 0) and threads - 1
 * workers. If a worker cannot be started the pool has fewer (ism_pool_threads says how
 * many); NULL only when the pool itself cannot be allocated. */
ism_pool *ism_pool_new(int threads);

/* Stops and joins the workers (none may be running a job). NULL is allowed. */
void ism_pool_free(ism_pool *p);

/* How many threads the pool runs jobs on, the caller included (at least 1). */
int ism_pool_threads(const ism_pool *p);

/* Calls job(arg, id) once on each of the first n threads (id 0..n-1; id 0 is the calling
 * thread; n is capped at ism_pool_threads) and returns when every call has returned. Not
 * reentrant: one job at a time per pool, started by the thread that owns it. */
void ism_pool_run(ism_pool *p, int n, void (*job)(void *arg, int id), void *arg);

#endif
