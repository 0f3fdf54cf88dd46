/* parallel.h — runs numbered tasks on a few threads (a shared atomic counter hands out task
 * numbers). Each call creates and joins its own threads: no pool, no global state. The
 * order in which tasks run is not fixed, so tasks must write only to their own slots. */
#ifndef ISM_PARALLEL_H
#define ISM_PARALLEL_H

#include <stddef.h>

/* Calls fn(ctx, task, thread) once for every task in [0, ntasks), on `threads` threads
 * (thread is 0..threads-1, so per-thread state can be indexed by it). */
void ism_parallel_for(int threads, size_t ntasks, void (*fn)(void *ctx, size_t task, int thread),
                      void *ctx);

/* Number of online processors (at least 1). */
int ism_cpu_count(void);

#endif
