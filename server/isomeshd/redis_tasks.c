/* redis_tasks.c — the task group of redis_tasks.h: a count of live tasks and of tasks inside
 * the scheduler, a stopping flag, and the owner's release by whoever ends last. */
#include "server/isomeshd/redis_tasks.h"

#include <pthread.h>
#include <stdlib.h>
#include <time.h>

#include "core/util/clock.h"

#define STOP_POLL_NS 20000000L /* ismd_redis_tasks_stop looks at the count this often */

struct ismd_redis_tasks {
    ismd_sched *sched;
    void (*release)(void *owner);
    void *owner;
    pthread_mutex_t lock;      /* guards the fields below */
    pthread_cond_t changed;
    int ntasks, inside;        /* tasks alive; tasks using the scheduler now */
    bool stopping, detached;   /* no more scheduler use; stopped (the last task releases) */
};

ismd_redis_tasks *ismd_redis_tasks_new(ismd_sched *sched, void (*release)(void *owner),
                                       void *owner)
{
    ismd_redis_tasks *g = calloc(1, sizeof *g);
    if (!g)
        return NULL;
    g->sched = sched;
    g->release = release;
    g->owner = owner;
    pthread_mutex_init(&g->lock, NULL);
    pthread_cond_init(&g->changed, NULL);
    return g;
}

static void release(ismd_redis_tasks *g)
{
    g->release(g->owner);
    pthread_mutex_destroy(&g->lock);
    pthread_cond_destroy(&g->changed);
    free(g);
}

bool ismd_redis_tasks_enter(ismd_redis_tasks *g)
{
    pthread_mutex_lock(&g->lock);
    bool ok = !g->stopping;
    if (ok)
        g->inside++;
    pthread_mutex_unlock(&g->lock);
    if (ok)
        ismd_sched_lock(g->sched);
    return ok;
}

void ismd_redis_tasks_leave(ismd_redis_tasks *g)
{
    ismd_sched_unlock(g->sched);
    pthread_mutex_lock(&g->lock);
    g->inside--;
    pthread_cond_broadcast(&g->changed);
    pthread_mutex_unlock(&g->lock);
}

bool ismd_redis_tasks_stopping(ismd_redis_tasks *g)
{
    pthread_mutex_lock(&g->lock);
    bool stopping = g->stopping;
    pthread_mutex_unlock(&g->lock);
    return stopping;
}

bool ismd_redis_tasks_added(ismd_redis_tasks *g)
{
    pthread_mutex_lock(&g->lock);
    bool ok = !g->stopping;
    if (ok)
        g->ntasks++;
    pthread_mutex_unlock(&g->lock);
    return ok;
}

void ismd_redis_tasks_ended(ismd_redis_tasks *g)
{
    pthread_mutex_lock(&g->lock);
    bool last = --g->ntasks == 0 && g->detached;
    pthread_cond_broadcast(&g->changed);
    pthread_mutex_unlock(&g->lock);
    if (last)
        release(g);
}

void ismd_redis_tasks_stop(ismd_redis_tasks *g, long long wait_ns)
{
    pthread_mutex_lock(&g->lock);
    g->stopping = true;
    while (g->inside > 0) /* short: nobody waits on the network inside */
        pthread_cond_wait(&g->changed, &g->lock);
    long long until = ism_now_ns() + wait_ns;
    while (g->ntasks > 0 && ism_now_ns() < until) {
        struct timespec ts;
        clock_gettime(CLOCK_REALTIME, &ts);
        ts.tv_nsec += STOP_POLL_NS;
        if (ts.tv_nsec >= 1000000000) {
            ts.tv_sec++;
            ts.tv_nsec -= 1000000000;
        }
        pthread_cond_timedwait(&g->changed, &g->lock, &ts);
    }
    bool free_now = g->ntasks == 0;
    g->detached = true; /* otherwise the last task releases (when the tier closes) */
    pthread_mutex_unlock(&g->lock);
    if (free_now)
        release(g);
}
