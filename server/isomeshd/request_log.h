/* request_log.h — the log line and the metrics of a request: counted when answered, timed
 * and logged when finished. */
#ifndef ISMD_REQUEST_LOG_H
#define ISMD_REQUEST_LOG_H

#include <stdbool.h>

#include "server/isomeshd/http_types.h"

/* r is answered with status: counted in requests_total now, once, while its bytes are still
 * to leave (see ismd_metrics_count). */
void ismd_request_answered(ismd_req *r, unsigned status);

/* The log line and the metrics of r, which has ended (completed: its answer went out whole;
 * cut: why the connection table closed its connection, or NULL). */
void ismd_request_record(ismd_req *r, bool completed, const char *cut);

#endif
