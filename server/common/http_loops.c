/* http_loops.c — the HTTP polling threads of http_loops.h: one libmicrohttpd daemon per
 * thread in external epoll mode, all on one listening socket; each thread sleeps in poll() on
 * its daemon's epoll descriptor, its own wake descriptor and a shared stop descriptor, and
 * then runs the daemon once.
 *
 * Why not libmicrohttpd's own thread pool: MHD_epoll() in 0.9.75 drains events with
 * `while (epoll_wait(.., 128, timeout) == 128)`, the same blocking timeout on every call, so a
 * thread whose call returns exactly 128 events with nothing new pending sleeps while those
 * connections wait (seen: a 2.9 s stall after a burst of 128 new connections). The pool
 * therefore had to keep each thread's set under 128 descriptors: 35 threads for 4,000
 * connections, each waking for a few connections (1.1-2.5 context switches per request at
 * 256 connections, nginx 0.01-0.1). Here the wait happens outside: MHD_run() calls
 * epoll_wait with a zero timeout, which never sleeps, so any number of connections per
 * thread is safe and the threads can be as many as the cores.
 *
 * Why a wake descriptor per loop: without an internal thread MHD_start_daemon drops
 * MHD_USE_ITC (0.9.75 daemon.c: "useless if we are using 'external' select"), so
 * MHD_resume_connection from another thread only sets a flag that the next MHD_run reads;
 * nothing in the epoll set becomes readable. ism_http_resume writes the owning loop's
 * eventfd after resuming, and the loop drains it before running the daemon, so a resume that
 * lands after MHD_run read the flag leaves the descriptor readable for the next poll.
 *
 * With an own sender (http_front.h) the daemons have no listening socket: each thread's front
 * accepts, answers what its hook takes and hands the rest to the thread's daemon, and the
 * thread sleeps in epoll_wait on the front's set, which watches the daemon's epoll descriptor
 * and the wake and stop descriptors too (in poll() on the set's descriptor, every thread was
 * woken for every new connection: the kernel ends an EPOLLEXCLUSIVE wake-up at a set only
 * when a thread waits in epoll_wait on it). */
#include "server/common/http_loops.h"

#include <errno.h>
#include <poll.h>
#include <pthread.h>
#include <stdatomic.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>
#include <sys/eventfd.h>
#include <unistd.h>

#include "server/common/log.h"

/* Longest sleep without an event. Shutdowns wake a thread through the stop descriptor,
 * resumes through the loop's wake descriptor, new connections and data through the epoll
 * descriptor, connection timeouts through MHD_get_timeout() (0 too while libmicrohttpd holds
 * connections it has still to process). So the bound only caps how long a missed wake-up
 * could cost: measured with a 1,000 ms bound, no poll that slept its whole bound was followed
 * by a run that accepted, closed or spent over 2 ms (test_latency, test_connections,
 * test_slowloris, test_http_concurrency, test_api; release and AddressSanitizer builds). The
 * wake-up once thought missed beside 450 slow readers (/healthz p99 751 ms, ci6) was their
 * GETs each comparing a freshly stored 8.3 MB cache file on the polling threads (file_memo.h),
 * which stalls at any bound. */
#define MAX_WAIT_MS 1000

typedef struct loop {
    struct MHD_Daemon *d;
    ism_front *front; /* NULL: libmicrohttpd accepts (no own sender) */
    int epoll_fd;
    int wake_fd; /* an eventfd: readable after a resume of one of d's connections */
    int wake_bit; /* with a front: wake_fd's bit in ism_front_run's answer */
    pthread_t thread;
    bool running;
    ism_http_loops *set;
} loop;

struct ism_http_loops {
    unsigned n;
    int stop_fd; /* an eventfd: readable (for good) once stopping */
    atomic_bool stopping;
    loop *loops;
};

static int wait_ms(struct MHD_Daemon *d)
{
    MHD_UNSIGNED_LONG_LONG ms;
    if (MHD_get_timeout(d, &ms) != MHD_YES || ms > MAX_WAIT_MS)
        return MAX_WAIT_MS;
    return (int)ms;
}

/* Makes the eventfd fd readable (its counter cannot overflow: one read empties it). */
static void signal_fd(int fd, const char *what)
{
    uint64_t one = 1;
    if (write(fd, &one, sizeof one) != sizeof one)
        ism_logf(ISM_LOG_WARN, what, "eventfd: %s", strerror(errno));
}

static void drain_fd(int fd)
{
    uint64_t count;
    if (read(fd, &count, sizeof count) < 0 && errno != EAGAIN)
        ism_logf(ISM_LOG_WARN, "http_wake", "eventfd: %s", strerror(errno));
}

/* With an own sender: one epoll_wait on the front's set, which also watches the daemon's
 * epoll set and the wake and stop descriptors (start_daemon; http_front.h ism_front_watch:
 * the listening socket's EPOLLEXCLUSIVE wakes one thread per connection only so). */
static void front_loop(loop *l)
{
    while (!atomic_load(&l->set->stopping)) {
        int ms = ism_front_wait_ms(l->front, wait_ms(l->d));
        /* connections it hands over are run just below */
        unsigned fired = ism_front_run(l->front, ms);
        if (atomic_load(&l->set->stopping))
            break;
        if (fired >> l->wake_bit & 1)
            drain_fd(l->wake_fd); /* before the run, which takes every resume made so far */
        MHD_run(l->d);
    }
}

static void *loop_main(void *arg)
{
    loop *l = arg;
    MHD_run(l->d); /* the first run puts the listening socket in the epoll set */
    if (l->front) {
        front_loop(l);
        return NULL;
    }
    struct pollfd p[3] = {{.fd = l->epoll_fd, .events = POLLIN},
                          {.fd = l->wake_fd, .events = POLLIN},
                          {.fd = l->set->stop_fd, .events = POLLIN}};
    while (!atomic_load(&l->set->stopping)) {
        if (poll(p, 3, wait_ms(l->d)) < 0 && errno != EINTR)
            ism_logf(ISM_LOG_WARN, "http_poll", "%s", strerror(errno));
        if (atomic_load(&l->set->stopping))
            break;
        if (p[1].revents)
            drain_fd(l->wake_fd); /* before the run, which takes every resume made so far */
        MHD_run(l->d);
    }
    return NULL;
}

ism_http_loops *ism_http_loops_new(unsigned n)
{
    ism_http_loops *s = n ? calloc(1, sizeof *s) : NULL;
    if (!s)
        return NULL;
    s->stop_fd = -1;
    s->loops = calloc(n, sizeof *s->loops);
    if (!s->loops) {
        free(s);
        return NULL;
    }
    s->n = n;
    for (unsigned i = 0; i < n; i++)
        s->loops[i].wake_fd = -1;
    bool ok = (s->stop_fd = eventfd(0, EFD_CLOEXEC | EFD_NONBLOCK)) >= 0;
    for (unsigned i = 0; ok && i < n; i++)
        ok = (s->loops[i].wake_fd = eventfd(0, EFD_CLOEXEC | EFD_NONBLOCK)) >= 0;
    if (!ok) {
        ism_logf(ISM_LOG_ERROR, "http_start_failed", "eventfd: %s", strerror(errno));
        ism_http_loops_stop(s);
        return NULL;
    }
    return s;
}

/* Ends the threads started so far, then the daemons, and frees s. */
void ism_http_loops_stop(ism_http_loops *s)
{
    if (!s)
        return;
    atomic_store(&s->stopping, true);
    if (s->stop_fd >= 0)
        signal_fd(s->stop_fd, "http_stop");
    for (unsigned i = 0; i < s->n; i++)
        if (s->loops[i].running)
            pthread_join(s->loops[i].thread, NULL);
    for (unsigned i = 0; i < s->n; i++) {
        loop *l = &s->loops[i];
        ism_front_free(l->front); /* before its daemon: nothing more is handed over */
        if (l->d) {
            MHD_quiesce_daemon(l->d); /* so that stopping does not close the socket */
            MHD_stop_daemon(l->d);
        }
        if (l->wake_fd >= 0)
            close(l->wake_fd);
    }
    if (s->stop_fd >= 0)
        close(s->stop_fd);
    free(s->loops);
    free(s);
}

static bool start_daemon(ism_http_loops *s, loop *l, unsigned flags, int listen_fd,
                         unsigned limit, MHD_AccessHandlerCallback ah, void *ah_cls,
                         const struct MHD_OptionItem *opts, const ism_front_hooks *front)
{
    l->set = s;
    /* opts first: its first item is the external logger, which libmicrohttpd wants before any
     * other option (else it warns at every start, on the standard logger too) */
    if (front) /* the front accepts; libmicrohttpd gets connections from it */
        l->d = MHD_start_daemon(flags | MHD_USE_EPOLL | MHD_USE_NO_LISTEN_SOCKET, 0, NULL, NULL,
                                ah, ah_cls, MHD_OPTION_ARRAY, opts,
                                MHD_OPTION_CONNECTION_LIMIT, limit, MHD_OPTION_END);
    else
        l->d = MHD_start_daemon(flags | MHD_USE_EPOLL, 0, NULL, NULL, ah, ah_cls,
                                MHD_OPTION_ARRAY, opts,
                                MHD_OPTION_LISTEN_SOCKET, listen_fd,
                                MHD_OPTION_CONNECTION_LIMIT, limit,
                                MHD_OPTION_END);
    if (!l->d)
        return false;
    if (front && !(l->front = ism_front_new(front, listen_fd, l->d,
                                            l == s->loops ? NULL : s->loops[0].front)))
        return false;
    const union MHD_DaemonInfo *di = MHD_get_daemon_info(l->d, MHD_DAEMON_INFO_EPOLL_FD);
    if (!di)
        return false;
    l->epoll_fd = di->epoll_fd;
    return !l->front || (ism_front_watch(l->front, l->epoll_fd) >= 0 &&
                         (l->wake_bit = ism_front_watch(l->front, l->wake_fd)) >= 0 &&
                         ism_front_watch(l->front, s->stop_fd) >= 0);
}

bool ism_http_loops_start(ism_http_loops *s, unsigned flags, int listen_fd, unsigned conn_limit,
                          MHD_AccessHandlerCallback ah, void *ah_cls,
                          const struct MHD_OptionItem *opts, const ism_front_hooks *front)
{
    /* libmicrohttpd accepting: each daemon takes new connections until it holds its share.
     * The front accepting: it hands a connection to its own thread's daemon whatever the
     * others hold, so each daemon may hold them all (the caller's rules bound the total). */
    unsigned limit = front ? conn_limit : (conn_limit + s->n - 1) / s->n;
    /* Every daemon exists before any thread runs: ism_http_resume reads the whole table. */
    for (unsigned i = 0; i < s->n; i++)
        if (!start_daemon(s, &s->loops[i], flags, listen_fd, limit, ah, ah_cls, opts, front)) {
            ism_logf(ISM_LOG_ERROR, "http_start_failed",
                     "libmicrohttpd daemon %u of %u did not start", i + 1, s->n);
            return false;
        }
    for (unsigned i = 0; i < s->n; i++) {
        loop *l = &s->loops[i];
        l->running = pthread_create(&l->thread, NULL, loop_main, l) == 0;
        if (!l->running) {
            ism_logf(ISM_LOG_ERROR, "http_start_failed", "polling thread %u of %u: no thread",
                     i + 1, s->n);
            return false;
        }
    }
    return true;
}

void ism_http_resume(ism_http_loops *s, struct MHD_Connection *c)
{
    /* Read before resuming: once resumed, c may be answered and freed by its loop. */
    const union MHD_ConnectionInfo *ci = MHD_get_connection_info(c, MHD_CONNECTION_INFO_DAEMON);
    struct MHD_Daemon *d = ci ? ci->daemon : NULL;
    MHD_resume_connection(c);
    for (unsigned i = 0; i < s->n; i++)
        if (s->loops[i].d == d) {
            signal_fd(s->loops[i].wake_fd, "http_wake");
            return;
        }
    ism_logf(ISM_LOG_WARN, "http_wake", "a resumed connection of no known daemon");
}

void ism_http_loops_quiesce(ism_http_loops *s)
{
    for (unsigned i = 0; i < s->n; i++) {
        MHD_quiesce_daemon(s->loops[i].d); /* takes the socket out of the epoll set itself */
        if (s->loops[i].front)
            ism_front_quiesce(s->loops[i].front);
    }
}
