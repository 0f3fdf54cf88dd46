/* user_metrics.c — per-user gauges for /metrics (user_metrics.h): a snapshot of the queue's
 * user loads under the scheduler's lock, sorted by load, the top ones by name and the rest
 * as "other". */
#include "server/isomeshd/user_metrics.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static int by_load_desc(const void *a, const void *b)
{
    const ismd_user_load *x = a, *y = b;
    int lx = x->queued + x->running, ly = y->queued + y->running;
    if (lx != ly)
        return ly - lx;
    return strcmp(x->user, y->user);
}

/* A Prometheus label value: backslash, quote and newline escaped. */
static void label_value(char *out, size_t cap, const char *s)
{
    size_t o = 0;
    for (; *s && o + 3 < cap; s++) {
        if (*s == '\\' || *s == '"') {
            out[o++] = '\\';
            out[o++] = *s;
        } else if (*s == '\n') {
            out[o++] = '\\';
            out[o++] = 'n';
        } else {
            out[o++] = *s;
        }
    }
    out[o] = 0;
}

char *ismd_user_metrics_render(ismd_sched *s, size_t *len)
{
    ismd_sched_lock(s);
    size_t n = s->queue->ops->users(s->queue, NULL, 0);
    ismd_user_load *loads = calloc(n ? n : 1, sizeof *loads);
    if (loads)
        n = s->queue->ops->users(s->queue, loads, n);
    ismd_sched_unlock(s);
    if (!loads)
        return NULL;
    qsort(loads, n, sizeof *loads, by_load_desc);

    size_t shown = n < ISMD_USER_METRICS_TOP ? n : ISMD_USER_METRICS_TOP;
    size_t cap = 512 + (shown + 1) * 2 * (ISMD_QUEUE_USER_MAX * 2 + 96);
    char *text = malloc(cap);
    if (!text) {
        free(loads);
        return NULL;
    }
    size_t o = 0;
    o += (size_t)snprintf(text + o, cap - o,
                          "# HELP isomesh_user_jobs Computations per user (token user, or client "
                          "address without tokens), by state; users beyond the top %d are summed "
                          "as user=\"other\".\n# TYPE isomesh_user_jobs gauge\n",
                          ISMD_USER_METRICS_TOP);
    int other_q = 0, other_r = 0;
    for (size_t i = 0; i < n; i++) {
        if (i >= shown) {
            other_q += loads[i].queued;
            other_r += loads[i].running;
            continue;
        }
        char name[ISMD_QUEUE_USER_MAX * 2];
        label_value(name, sizeof name, loads[i].user);
        o += (size_t)snprintf(text + o, cap - o,
                              "isomesh_user_jobs{user=\"%s\",state=\"queued\"} %d\n"
                              "isomesh_user_jobs{user=\"%s\",state=\"running\"} %d\n",
                              name, loads[i].queued, name, loads[i].running);
    }
    if (n > shown)
        o += (size_t)snprintf(text + o, cap - o,
                              "isomesh_user_jobs{user=\"other\",state=\"queued\"} %d\n"
                              "isomesh_user_jobs{user=\"other\",state=\"running\"} %d\n",
                              other_q, other_r);
    o += (size_t)snprintf(text + o, cap - o,
                          "# HELP isomesh_users_active Users with computations queued or "
                          "running.\n# TYPE isomesh_users_active gauge\nisomesh_users_active %zu\n",
                          n);
    free(loads);
    *len = o < cap ? o : cap - 1;
    return text;
}
