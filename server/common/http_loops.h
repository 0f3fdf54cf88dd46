/* http_loops.h — the HTTP polling threads: n libmicrohttpd daemons in external epoll mode on
 * one listening socket, each driven by its own thread. */
#ifndef ISM_HTTP_LOOPS_H
#define ISM_HTTP_LOOPS_H

#include <microhttpd.h>
#include <stdbool.h>

typedef struct ism_http_loops ism_http_loops;

/* Starts n daemons, each with `flags` (MHD_USE_EPOLL is added, no internal thread), the
 * access handler ah/ah_cls, the options opts (ended by MHD_OPTION_END; no listening socket,
 * connection limit or thread option among them), listen_fd shared by all and at most
 * ceil(conn_limit / n) connections each, and a thread per daemon. NULL on failure (logged,
 * nothing left running). */
ism_http_loops *ism_http_loops_start(unsigned n, unsigned flags, int listen_fd,
                                       unsigned conn_limit, MHD_AccessHandlerCallback ah,
                                       void *ah_cls, const struct MHD_OptionItem *opts);
/* Every daemon stops accepting new connections (the listening socket stays open). */
void ism_http_loops_quiesce(ism_http_loops *l);
/* Stops the threads, then the daemons (every suspended connection must have been resumed),
 * and frees l. The listening socket is left to the caller. */
void ism_http_loops_stop(ism_http_loops *l);

#endif
