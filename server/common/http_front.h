/* http_front.h — an own sender beside libmicrohttpd (http_loops.h, isomeshd --own-sender): a
 * polling thread accepts connections itself; a request whose head has fully arrived is shown
 * (peeked, not read) to a hook, which may answer it with a header block and a file range, sent
 * as nginx sends a static file: the header block held back (MSG_MORE), then sendfile, whose
 * last chunk leaves at once (TCP_NODELAY, no cork: http_front.c send_some). Every other request goes, with its connection, to the thread's libmicrohttpd daemon
 * (MHD_add_connection), which reads it from the socket as if it had accepted the connection
 * itself; so does a connection idle longer than idle_s. The caller's connection rules see the
 * front's connections from their accept through the opened/busy/closed/handing hooks. Why: libmicrohttpd 0.9.75 (and 1.0.1) pushes a file answer's
 * header block as a segment of its own (server/isomeshd/respond.c), which bbr makes
 * expensive. One front per polling thread, used only by it (ism_front_quiesce and the
 * hand-over of a new connection between fronts excepted). */
#ifndef ISM_HTTP_FRONT_H
#define ISM_HTTP_FRONT_H

#include <microhttpd.h>
#include <stdbool.h>
#include <stddef.h>
#include <sys/socket.h>

/* Longest header block a hook may write (isomeshd's cached answer: ~420 bytes with CORS). */
#define ISM_FRONT_HEAD_MAX 1024

typedef struct ism_front_answer {
    char head[ISM_FRONT_HEAD_MAX]; /* the status line and headers, ending in CRLF CRLF */
    size_t head_len;
    int fd;                         /* the body: len bytes of fd from offset (fd is the hook's) */
    long long offset;
    size_t len;
    const unsigned char *mem;       /* or, when not NULL, the len bytes here (the hook keeps
                                       them until done; fd is then not read) */
    void *ctx;                      /* the hook's own, given back to done */
} ism_front_answer;

typedef struct ism_front_hooks {
    /* The request head (len bytes, request line and headers up to CRLF CRLF; no body may
     * follow) on conn (opened's context, NULL without that hook): true with *a filled to
     * answer it here, false to leave it (and the connection) to libmicrohttpd. */
    bool (*answer)(void *cls, const char *head, size_t len, void *conn, ism_front_answer *a);
    /* a was sent whole (sent) or its connection failed or stalled (!sent): a->fd and a->ctx
     * are the hook's to release. */
    void (*done)(void *cls, ism_front_answer *a, bool sent);
    /* The caller's connection rules (optional, all four or none), so that the connections
     * the front holds count where libmicrohttpd's do. opened: a connection accepted; returns
     * its context (NULL: none) and sets *keep false when the rules refuse it, which then goes
     * to libmicrohttpd at once (to be answered or closed there). busy: conn starts (true) or
     * ends (false) an answer. closed: the front closed conn itself. handing: conn goes to
     * libmicrohttpd, called with it just before MHD_add_connection and with NULL just after
     * (the caller adopts conn in libmicrohttpd's connection notification of that call, and
     * releases it when none came). */
    void *(*opened)(void *cls, int fd, const struct sockaddr *peer, bool *keep);
    void (*busy)(void *cls, void *conn, bool busy);
    void (*closed)(void *cls, void *conn);
    void (*handing)(void *cls, void *conn);
    void *cls;
    unsigned max_conns; /* connections one front holds; beyond, new ones go at once */
    double idle_s;      /* a connection waiting this long for a request goes */
    double stall_s;     /* an answer that moves no byte this long: its connection is closed */
    /* Unsent bytes a connection may queue in the kernel (TCP_NOTSENT_LOWAT): unsent_min, the
     * listening socket's (inherited at accept), is what a new connection and a slow reader
     * get; a reader that keeps up has it doubled up to unsent_max, so a large answer takes
     * few wake-ups (http_front.c adapt_unsent). */
    unsigned unsent_min, unsent_max;
} ism_front_hooks;

typedef struct ism_front ism_front;

/* A front on listen_fd (non-blocking, shared with the other fronts: each is woken for a new
 * connection alone, EPOLLEXCLUSIVE) handing connections to d; peer: another front on the same
 * socket (NULL: the first), whose group it joins: a front accepting a connection gives it to
 * the one of the group holding the fewest, to be served by that one's thread. Every front of
 * a group is made before any of them runs, and freed after all have stopped running. NULL on
 * failure (logged). */
ism_front *ism_front_new(const ism_front_hooks *h, int listen_fd, struct MHD_Daemon *d,
                         ism_front *peer);
/* fd (the caller's, readable when it has work: level-triggered) joins the front's epoll set
 * so that the polling thread sleeps in one epoll_wait; its bit index (0-3), -1 on failure
 * (logged). Why one wait: the listening socket wakes one front per connection only when its
 * thread sleeps in epoll_wait on that set (EPOLLEXCLUSIVE); a thread in poll() on the set's
 * descriptor is woken for every connection, every thread, and the first takes it. */
int ism_front_watch(ism_front *f, int fd);
/* Waits up to timeout_ms (0: not at all) for work, then accepts, answers and hands over what
 * is ready and closes what timed out. Returns the watched descriptors found ready, bit i for
 * ism_front_watch's index i. */
unsigned ism_front_run(ism_front *f, int timeout_ms);
/* Milliseconds until the front's next deadline (at most max_ms). */
int ism_front_wait_ms(const ism_front *f, int max_ms);
/* Stops accepting (any thread). */
void ism_front_quiesce(ism_front *f);
/* Closes every connection it holds (answers under way end !sent) and frees f (NULL: none). */
void ism_front_free(ism_front *f);

#endif
