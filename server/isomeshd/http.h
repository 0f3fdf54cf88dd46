/* http.h — isomeshd's HTTP front (the server state every route sees and the per-request
 * context are http_types.h's): libmicrohttpd set-up (--http-threads polling threads,
 * suspend/resume) and the request life cycle (first call: route, 413/415 checks; body calls;
 * answer on a later call). The route table is routes.h's, answering respond.h's, waiting for
 * a computation flight_wait.h's, and the connections' limits and deadlines conns.h's.
 *
 * A request that needs a computation joins or starts a flight (sched.h) and suspends its
 * connection; the flight's end resumes it and the handler's next call answers. Nothing in the
 * MHD threads ever blocks on a worker. Handlers run on any of the polling threads at once:
 * what they share is behind the scheduler lock, the cache tiers' locks or atomics. */
#ifndef ISMD_HTTP_H
#define ISMD_HTTP_H

#include <stdbool.h>

#include "server/isomeshd/http_types.h"

/* Starts MHD on an already listening socket. False on failure (logged). */
bool ismd_http_start(ismd_server *s, int listen_fd);
/* Stops accepting new connections (closes the listening socket). */
void ismd_http_quiesce(ismd_server *s);
/* Waits up to max_s seconds for open requests to finish, then stops MHD. */
void ismd_http_stop(ismd_server *s, double max_s);

#endif
