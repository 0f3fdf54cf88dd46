/* http_loops.c — the HTTP polling threads of http_loops.h: one libmicrohttpd daemon per
 * thread in external epoll mode, all on one listening socket; each thread sleeps in poll() on
 * its daemon's epoll descriptor (and a shared stop descriptor) and then runs the daemon once.
 *
 * Why not libmicrohttpd's own thread pool: MHD_epoll() in 0.9.75 drains events with
 * `while (epoll_wait(.., 128, timeout) == 128)`, the same blocking timeout on every call, so a
 * thread whose call returns exactly 128 events with nothing new pending sleeps while those
 * connections wait (seen: a 2.9 s stall after a burst of 128 new connections). The pool
 * therefore had to keep each thread's set under 128 descriptors: 35 threads for 4,000
 * connections, each waking for a few connections (1.1-2.5 context switches per request at
 * 256 connections, nginx 0.01-0.1). Here the wait happens outside: MHD_run() calls
 * epoll_wait with a zero timeout, which never sleeps, so any number of connections per
 * thread is safe and the threads can be as many as the cores. */
#include "server/common/http_loops.h"

#include <errno.h>
#include <poll.h>
#include <pthread.h>
#include <stdatomic.h>
#include <stdlib.h>
#include <string.h>
#include <sys/eventfd.h>
#include <unistd.h>

#include "server/common/log.h"

/* Longest sleep without an event. Shutdowns wake a thread through the stop descriptor and
 * connection timeouts through MHD_get_timeout(), but a connection resumed from another
 * thread (every computed mesh, job event) does NOT wake this poll in external-epoll mode:
 * at 1000 ms every computed request took 1.0 s. Until resumes write a wake descriptor of
 * their own, the bound is what a resumed answer may wait: 10 ms (4 threads idle: 400
 * wake-ups a second, a few µs each). */
#define MAX_WAIT_MS 10

typedef struct loop {
    struct MHD_Daemon *d;
    int epoll_fd;
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

static void *loop_main(void *arg)
{
    loop *l = arg;
    struct pollfd p[2] = {{.fd = l->epoll_fd, .events = POLLIN},
                          {.fd = l->set->stop_fd, .events = POLLIN}};
    MHD_run(l->d); /* the first run puts the listening socket in the epoll set */
    while (!atomic_load(&l->set->stopping)) {
        if (poll(p, 2, wait_ms(l->d)) < 0 && errno != EINTR)
            ism_logf(ISM_LOG_WARN, "http_poll", "%s", strerror(errno));
        if (atomic_load(&l->set->stopping))
            break;
        MHD_run(l->d);
    }
    return NULL;
}

/* Ends the threads and daemons started so far. */
static void stop_all(ism_http_loops *s)
{
    atomic_store(&s->stopping, true);
    uint64_t one = 1;
    if (write(s->stop_fd, &one, sizeof one) != sizeof one)
        ism_logf(ISM_LOG_WARN, "http_stop", "eventfd: %s", strerror(errno));
    for (unsigned i = 0; i < s->n; i++)
        if (s->loops[i].running)
            pthread_join(s->loops[i].thread, NULL);
    for (unsigned i = 0; i < s->n; i++) {
        if (!s->loops[i].d)
            continue;
        MHD_quiesce_daemon(s->loops[i].d); /* so that stopping does not close the socket */
        MHD_stop_daemon(s->loops[i].d);
    }
    close(s->stop_fd);
    free(s->loops);
    free(s);
}

static bool start_one(ism_http_loops *s, loop *l, unsigned flags, int listen_fd, unsigned limit,
                      MHD_AccessHandlerCallback ah, void *ah_cls,
                      const struct MHD_OptionItem *opts)
{
    l->set = s;
    l->d = MHD_start_daemon(flags | MHD_USE_EPOLL, 0, NULL, NULL, ah, ah_cls,
                            MHD_OPTION_LISTEN_SOCKET, listen_fd,
                            MHD_OPTION_CONNECTION_LIMIT, limit,
                            MHD_OPTION_ARRAY, opts,
                            MHD_OPTION_END);
    if (!l->d)
        return false;
    const union MHD_DaemonInfo *di = MHD_get_daemon_info(l->d, MHD_DAEMON_INFO_EPOLL_FD);
    if (!di)
        return false;
    l->epoll_fd = di->epoll_fd;
    l->running = pthread_create(&l->thread, NULL, loop_main, l) == 0;
    return l->running;
}

ism_http_loops *ism_http_loops_start(unsigned n, unsigned flags, int listen_fd,
                                       unsigned conn_limit, MHD_AccessHandlerCallback ah,
                                       void *ah_cls, const struct MHD_OptionItem *opts)
{
    ism_http_loops *s = calloc(1, sizeof *s);
    if (!s)
        return NULL;
    s->loops = calloc(n, sizeof *s->loops);
    s->stop_fd = eventfd(0, EFD_CLOEXEC | EFD_NONBLOCK);
    if (!s->loops || s->stop_fd < 0) {
        if (s->stop_fd >= 0)
            close(s->stop_fd);
        free(s->loops);
        free(s);
        return NULL;
    }
    unsigned limit = (conn_limit + n - 1) / n;
    for (s->n = 0; s->n < n; s->n++) {
        if (!start_one(s, &s->loops[s->n], flags, listen_fd, limit, ah, ah_cls, opts)) {
            ism_logf(ISM_LOG_ERROR, "http_start_failed",
                     "libmicrohttpd daemon %u of %u did not start", s->n + 1, n);
            s->n++;
            stop_all(s);
            return NULL;
        }
    }
    return s;
}

void ism_http_loops_quiesce(ism_http_loops *s)
{
    for (unsigned i = 0; i < s->n; i++)
        MHD_quiesce_daemon(s->loops[i].d);
}

void ism_http_loops_stop(ism_http_loops *s)
{
    stop_all(s);
}
