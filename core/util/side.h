/* side.h — one function run beside the caller's own work on a thread of its own, then
 * joined: for serial passes that share no data with what the caller does meanwhile (the
 * analysis's connectivity passes beside its evaluations on the pool), so the cores the pool
 * leaves idle between and inside its loops work on them. Inline when asked for no thread or
 * when a thread cannot be started; the result never depends on which. The thread counts in
 * its caller's thread budget: who starts one gives what runs beside it one thread fewer (the
 * analysis's pool, beside its connectivity passes; the analysis, beside the CLI's mesh
 * writer), so that the CLI's --threads and a daemon worker's limit hold every thread a run
 * has. */
#ifndef ISM_SIDE_H
#define ISM_SIDE_H

#include <pthread.h>
#include <stdbool.h>

typedef struct ism_side {
    void (*fn)(void *arg);
    void *arg;
    pthread_t tid;
    bool started; /* on its own thread (else it already ran) */
} ism_side;

/* Starts fn(arg) on a new thread when `thread`, else (or when that fails) runs it now. */
void ism_side_start(ism_side *s, bool thread, void (*fn)(void *arg), void *arg);

/* Waits for fn to return (at once when it ran inline). */
void ism_side_join(ism_side *s);

#endif
