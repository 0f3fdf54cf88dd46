/* test_parallel.c — the fork/join loop with work stealing (core/util/parallel.h): every task
 * runs exactly once on a thread number below the thread count, for task counts below, at and
 * above it, with uneven task lengths that make threads run dry and steal; what the loop cost
 * keeps its order (all threads >= busiest >= even share, caller <= all); the threads an
 * option asks for resolve by one rule. */
#include <criterion/criterion.h>
#include <stdatomic.h>
#include <stdlib.h>
#include <unistd.h>

#include "core/util/parallel.h"

enum { MAX_TASKS = 3000 };

typedef struct tally {
    atomic_int runs[MAX_TASKS];
    atomic_int bad_thread;
    int threads;
    size_t heavy_below; /* tasks below this number spin longer: the first block's owner
                           falls behind and the others steal from it */
} tally;

static void task(void *ctx, size_t i, int thread)
{
    tally *t = ctx;
    atomic_fetch_add(&t->runs[i], 1);
    if (thread < 0 || thread >= t->threads)
        atomic_store(&t->bad_thread, 1);
    volatile double x = 1;
    for (int k = 0; k < (i < t->heavy_below ? 20000 : 200); k++)
        x = x * 1.0000001 + 1e-9;
}

static void check_once(int threads, size_t ntasks, size_t heavy_below)
{
    tally *t = calloc(1, sizeof *t);
    cr_assert_not_null(t);
    t->threads = threads;
    t->heavy_below = heavy_below;
    ism_par_cost cost = {0, 0, 0, 0};
    ism_parallel_for_costed(threads, ntasks, task, t, &cost);
    for (size_t i = 0; i < ntasks; i++)
        cr_assert_eq(atomic_load(&t->runs[i]), 1, "%d threads, %zu tasks: task %zu ran %d times",
                     threads, ntasks, i, atomic_load(&t->runs[i]));
    for (size_t i = ntasks; i < MAX_TASKS; i++)
        cr_assert_eq(atomic_load(&t->runs[i]), 0);
    cr_expect_eq(atomic_load(&t->bad_thread), 0, "a thread number out of range");
    cr_expect_geq(cost.cpu_ms, cost.busiest_ms);
    cr_expect_geq(cost.cpu_ms, cost.caller_ms);
    cr_expect_geq(cost.busiest_ms + 1e-6, cost.even_ms, "busiest %g < even share %g",
                  cost.busiest_ms, cost.even_ms);
    free(t);
}

Test(parallel, every_task_once)
{
    const int threads[] = {1, 2, 3, 4, 8};
    const size_t counts[] = {0, 1, 2, 3, 7, 64, 1000, MAX_TASKS};
    for (size_t a = 0; a < sizeof threads / sizeof *threads; a++)
        for (size_t b = 0; b < sizeof counts / sizeof *counts; b++) {
            check_once(threads[a], counts[b], 0);
            check_once(threads[a], counts[b], counts[b] / 2);
        }
}

static void add_offset(void *ctx, size_t i, int thread)
{
    (void)thread;
    atomic_fetch_add((atomic_size_t *)ctx, i + 1);
}

Test(parallel, plain_loop_sums_every_task)
{
    atomic_size_t sum = 0;
    ism_parallel_for(2, 500, add_offset, &sum);
    cr_expect_eq(atomic_load(&sum), (size_t)500 * 501 / 2);
}

/* One pool, many loops (what one polygonise call does): every task of every loop once, on a
 * thread number below the pool's, for loops narrower and wider than the pool. */
Test(parallel, pool_runs_many_loops)
{
    ism_pool *pool = ism_pool_new(3);
    cr_assert_not_null(pool);
    cr_assert_eq(ism_pool_threads(pool), 3);
    tally *t = calloc(1, sizeof *t);
    cr_assert_not_null(t);
    t->threads = 3;
    const size_t counts[] = {0, 1, 2, 3, 7, 1000, MAX_TASKS, 5};
    for (int round = 0; round < 40; round++) {
        size_t n = counts[round % (sizeof counts / sizeof *counts)];
        for (size_t i = 0; i < MAX_TASKS; i++)
            atomic_store(&t->runs[i], 0);
        t->heavy_below = round % 2 ? n / 2 : 0;
        ism_pool_for(pool, n, task, t, NULL);
        for (size_t i = 0; i < MAX_TASKS; i++)
            cr_assert_eq(atomic_load(&t->runs[i]), i < n, "loop %d (%zu tasks): task %zu ran %d times",
                         round, n, i, atomic_load(&t->runs[i]));
    }
    cr_expect_eq(atomic_load(&t->bad_thread), 0, "a thread number out of range");
    free(t);
    ism_pool_free(pool);
}

/* A NULL pool is one thread: the caller runs every task as thread 0. */
Test(parallel, no_pool_runs_on_the_caller)
{
    tally *t = calloc(1, sizeof *t);
    cr_assert_not_null(t);
    t->threads = 1;
    ism_pool_for(NULL, 100, task, t, NULL);
    for (size_t i = 0; i < 100; i++)
        cr_assert_eq(atomic_load(&t->runs[i]), 1);
    cr_expect_eq(atomic_load(&t->bad_thread), 0);
    cr_expect_eq(ism_pool_threads(NULL), 1);
    free(t);
}

/* The "0 = every online core" rule of every threads option, with its cap: a count asked for
 * is kept, 0 takes the cores, and neither passes 64 (on a machine of 100 cores the CLI's
 * copy of the rule gave 100, where the analysis's gave 64). The machine's own count is read
 * here from sysconf, not from ism_cpu_count. */
Test(parallel, threads_resolve)
{
    cr_expect_eq(ism_threads_given(0, 100), 64);
    cr_expect_eq(ism_threads_given(0, 3), 3);
    cr_expect_eq(ism_threads_given(5, 100), 5);
    cr_expect_eq(ism_threads_given(64, 1), 64);
    cr_expect_eq(ism_threads_given(200, 1), 64);
    cr_expect_eq(ism_threads_given(0, 0), 1);
    long cores = sysconf(_SC_NPROCESSORS_ONLN);
    int want = cores < 1 ? 1 : cores > 64 ? 64 : (int)cores;
    cr_expect_eq(ism_threads_resolve(0), want);
    cr_expect_eq(ism_threads_resolve(7), 7);
}
