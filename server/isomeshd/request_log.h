/* request_log.h — the log line and the metrics of a finished request. */
#ifndef ISMD_REQUEST_LOG_H
#define ISMD_REQUEST_LOG_H

#include <stdbool.h>

#include "server/isomeshd/http_types.h"

/* The log line and the metrics of r, which has ended (completed: its answer went out whole;
 * cut: why the connection table closed its connection, or NULL). */
void ismd_request_record(ismd_req *r, bool completed, const char *cut);

#endif
