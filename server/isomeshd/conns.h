/* conns.h — the table of open HTTP connections (libmicrohttpd's socket contexts, and with
 * --own-sender those its own sender holds, own_conns.h): which address
 * holds how many, and what each one is doing. It owns three rules libmicrohttpd lacks:
 *
 *  - one connection limit, fair across addresses: below it everyone gets in; at it, a
 *    connection from an address holding fewer than the largest holder (by two or more) gets
 *    in and one of that holder's connections is closed — one waiting for a request (the one
 *    waiting longest) before a busy one (its newest). A connection from an address that is
 *    itself among the largest holders takes the place of its own address's longest-waiting
 *    idle connection, or is refused: answered 503 with Retry-After (its first request;
 *    never left unanswered in the backlog). The same for a connection beyond the
 *    per-address cap (--client-conns), which a trusted proxy's connections are exempt from
 *    (nginx holds the connections of many clients and limits them per client itself).
 *    Refused connections waiting for their request are few (REFUSED_ROOM) and brief
 *    (REFUSED_WAIT_NS); beyond that they are closed at once.
 *  - deadlines for receiving a request, whatever the trickle rate (libmicrohttpd's timeout
 *    only ends silence): its headers within header_s of the connection becoming ready for
 *    one (accepted, or its previous answer completed), its body within body_s of its
 *    headers. This also bounds how long a kept-alive connection waits idle.
 *  - clients that left a request still in progress: libmicrohttpd watches no suspended
 *    connection, so a thread peeks at the sockets of requests in progress and hands those
 *    whose peer closed to a callback (once per request).
 *
 * A connection is closed by shutdown(2) of its socket under the table's lock; libmicrohttpd
 * then sees the end of the stream and frees it. The descriptor cannot have been reused by
 * then: libmicrohttpd reports a close (ismd_conns_closed, which takes the lock) before it
 * closes the descriptor. Thread-safe; the callback runs with the table's lock held. */
#ifndef ISMD_CONNS_H
#define ISMD_CONNS_H

#include <stdbool.h>

#include "server/isomeshd/metrics.h"

typedef struct ismd_conn ismd_conn;
typedef struct ismd_conns ismd_conns;

typedef struct ismd_conns_config {
    unsigned max;              /* connections held at once (--max-connections) */
    unsigned per_address;      /* connections of one address (--client-conns; 0 = any) */
    const char *trusted;       /* addresses exempt from per_address (--trusted-proxy) */
    double header_s;           /* --header-timeout */
    double body_s;             /* --body-timeout */
    /* A request in progress (req as given to ismd_conns_request) whose connection is gone:
     * its client closed it, or the table did (evicted at the limit). Called once per request
     * with the table's lock held, from its thread or from ismd_conns_opened; must not call
     * back into the table. */
    void (*client_left)(void *ctx, void *req);
    void *ctx;
} ismd_conns_config;

/* Starts the table and its thread. NULL on failure (logged). */
ismd_conns *ismd_conns_start(const ismd_conns_config *cfg, ismd_metrics *metrics);
/* Stops the thread and frees the table (after libmicrohttpd has stopped). */
void ismd_conns_stop(ismd_conns *t);

/* A new connection on socket fd from address addr: admitted, admitted in place of another
 * (closed), or refused (left open for a 503, or closed). Always returns its entry (NULL only
 * when out of memory), to be handed back to ismd_conns_closed. */
ismd_conn *ismd_conns_opened(ismd_conns *t, int fd, const char *addr);
/* libmicrohttpd is done with c (before it closes the socket). */
void ismd_conns_closed(ismd_conns *t, ismd_conn *c);
/* The peer address c was opened with (NULL for NULL): set once, read without the lock, valid
 * until c is closed — every request's client address starts from it (client_addr.h) instead
 * of formatting the socket address again. */
const char *ismd_conns_peer(const ismd_conn *c);

/* c's request headers are complete; req is the caller's context for it; body: its body is
 * still to be received. */
void ismd_conns_request(ismd_conns *t, ismd_conn *c, void *req, bool body);
/* c's request body is complete (no effect when it was not awaited). */
void ismd_conns_body_done(ismd_conns *t, ismd_conn *c);
/* c's request completed: c waits for the next one. */
void ismd_conns_request_done(ismd_conns *t, ismd_conn *c);

/* Was c refused and left open so that its first request is answered 503 (and closed)? */
bool ismd_conns_refused(ismd_conns *t, const ismd_conn *c);

/* Connections libmicrohttpd must have room for beyond max: refused ones awaiting their 503. */
unsigned ismd_conns_refused_room(unsigned max);

/* Why the table closed c ("refused", "evicted", "header_deadline", "body_deadline"), or
 * NULL when it did not. */
const char *ismd_conns_cut_reason(ismd_conns *t, const ismd_conn *c);

#endif
