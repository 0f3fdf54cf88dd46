/* http_loops.h — the HTTP polling threads: n libmicrohttpd daemons in external epoll mode on
 * one listening socket, each driven by its own thread, and the resume that wakes the thread
 * owning a connection. */
#ifndef ISM_HTTP_LOOPS_H
#define ISM_HTTP_LOOPS_H

#include <microhttpd.h>
#include <stdbool.h>

#include "server/common/http_front.h"

typedef struct ism_http_loops ism_http_loops;

/* n (at least 1) loops, each with its own wake descriptor; nothing runs yet (so that the
 * pointer can be stored where resumers find it before any request is served). NULL on
 * failure. */
ism_http_loops *ism_http_loops_new(unsigned n);
/* Starts l's n daemons, each with `flags` (MHD_USE_EPOLL is added, no internal thread), the
 * access handler ah/ah_cls, the options opts (ended by MHD_OPTION_END; no listening socket,
 * connection limit or thread option among them), listen_fd shared by all and at most
 * ceil(conn_limit / n) connections each, then a thread per daemon. With front (not NULL),
 * each thread accepts through an own sender (http_front.h) that hands libmicrohttpd what it
 * does not answer. false on failure (logged, nothing left running; l is still to be given to
 * ism_http_loops_stop). */
bool ism_http_loops_start(ism_http_loops *l, unsigned flags, int listen_fd, unsigned conn_limit,
                          MHD_AccessHandlerCallback ah, void *ah_cls,
                          const struct MHD_OptionItem *opts, const ism_front_hooks *front);
/* MHD_resume_connection(c), then wakes the polling thread of the daemon that owns c (in
 * external-epoll mode libmicrohttpd itself does not), so the answer goes out now. Any thread;
 * c must have been suspended and belong to one of l's daemons. */
void ism_http_resume(ism_http_loops *l, struct MHD_Connection *c);
/* Every daemon stops accepting new connections (the listening socket stays open). */
void ism_http_loops_quiesce(ism_http_loops *l);
/* Stops the threads, then the daemons (every suspended connection must have been resumed),
 * and frees l (NULL: nothing). The listening socket is left to the caller. */
void ism_http_loops_stop(ism_http_loops *l);

#endif
