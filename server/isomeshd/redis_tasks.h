/* redis_tasks.h — the lifetime of a group of tasks on the Redis tier's thread that use the
 * scheduler (the shared stage's and the cluster queue's, shared_cache.h and cluster.h): they
 * enter the scheduler only while the group is not stopping, and the group's owner is freed
 * once it has stopped and its last task has ended (tasks may outlive the stop while the tier
 * closes). */
#ifndef ISMD_REDIS_TASKS_H
#define ISMD_REDIS_TASKS_H

#include <stdbool.h>

#include "server/isomeshd/sched.h"

typedef struct ismd_redis_tasks ismd_redis_tasks;

/* A group for sched's users. release(owner) is called once, from ismd_redis_tasks_stop or
 * from the last task's ismd_redis_tasks_ended after it; the group is freed right after.
 * NULL when out of memory. */
ismd_redis_tasks *ismd_redis_tasks_new(ismd_sched *sched, void (*release)(void *owner),
                                       void *owner);

/* The scheduler, locked, for a task: true (leave with ismd_redis_tasks_leave), or false (not
 * locked) once stopping. */
bool ismd_redis_tasks_enter(ismd_redis_tasks *g);
void ismd_redis_tasks_leave(ismd_redis_tasks *g);

/* True once ismd_redis_tasks_stop has begun: a task should end. */
bool ismd_redis_tasks_stopping(ismd_redis_tasks *g);

/* One task more (false once stopping: the task must not start); one task less. */
bool ismd_redis_tasks_added(ismd_redis_tasks *g);
void ismd_redis_tasks_ended(ismd_redis_tasks *g);

/* No more entering: waits for the tasks inside the scheduler to leave, then (bounded by
 * wait_ns) for every task to end. Releases the owner now when none is left, else the last
 * task to end does. */
void ismd_redis_tasks_stop(ismd_redis_tasks *g, long long wait_ns);

#endif
