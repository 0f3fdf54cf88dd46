/* clock.h — the monotonic clock every timing, deadline and back-off reads: nanoseconds (or
 * milliseconds, seconds) from an arbitrary start, never going back when the wall clock is set. */
#ifndef ISM_CLOCK_H
#define ISM_CLOCK_H

#include <time.h>

static inline long long ism_now_ns(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (long long)ts.tv_sec * 1000000000LL + ts.tv_nsec;
}

static inline double ism_now_ms(void) { return (double)ism_now_ns() / 1e6; }

static inline double ism_now_s(void) { return (double)ism_now_ns() / 1e9; }

/* CPU time of the whole process, all threads, in milliseconds: what a computation cost,
 * unlike the clocks above not stretched by other processes sharing the cores. */
static inline double ism_cpu_ms(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
    return (double)ts.tv_sec * 1e3 + (double)ts.tv_nsec / 1e6;
}

/* CPU time of the calling thread alone, in milliseconds. */
static inline double ism_thread_cpu_ms(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
    return (double)ts.tv_sec * 1e3 + (double)ts.tv_nsec / 1e6;
}

#endif
