/* user_metrics.h — the per-user part of GET /metrics: computations queued and running per
 * user, in Prometheus text. Label cardinality is bounded: the ISMD_USER_METRICS_TOP users with
 * the most work get their own label, the rest are summed under user="other". */
#ifndef ISMD_USER_METRICS_H
#define ISMD_USER_METRICS_H

#include <stddef.h>

#include "server/isomeshd/sched.h"

#define ISMD_USER_METRICS_TOP 10

/* Takes the scheduler's lock briefly. A malloc'd string (*len its length), NULL when out of
 * memory. */
char *ismd_user_metrics_render(ismd_sched *s, size_t *len);

#endif
