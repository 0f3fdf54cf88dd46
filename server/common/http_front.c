/* http_front.c — the own sender of http_front.h: accepting, peeking at request heads, answering
 * with a held-back header block and sendfile, handing connections to libmicrohttpd, and the
 * idle and stall deadlines of the connections it holds. */
#include "server/common/http_front.h"

#include <errno.h>
#include <fcntl.h>
#include <netinet/in.h>
#include <netinet/tcp.h>
#include <pthread.h>
#include <stdatomic.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>
#include <sys/epoll.h>
#include <sys/eventfd.h>
#include <sys/sendfile.h>
#include <unistd.h>

#include "core/util/clock.h"
#include "server/common/log.h"

/* Bytes of a request head looked at: a longer head goes to libmicrohttpd (which answers 431
 * beyond its own memory limit). Browsers' heads are 0.5-2 KB. */
#define HEAD_PEEK 8192
/* New connections taken per wake: the listening socket wakes one front per connection
 * (EPOLLEXCLUSIVE), which hands each to the front holding the fewest (hand_in). */
#define ACCEPT_BATCH 4
/* How often the deadlines are checked: they are coarse (seconds). */
#define SCAN_NS 100000000LL
#define EVENTS 64
/* Descriptors of the polling thread's own (libmicrohttpd's epoll set, its wake and stop
 * eventfds) the front's epoll set also watches (ism_front_watch). */
#define WATCH_MAX 4
/* Out of descriptors (or memory) for a new connection: accepting pauses this long (the
 * listening socket stays readable, so retrying at once would spin). */
#define ACCEPT_PAUSE_NS 100000000LL
/* Work one connection gets per wake-up, after which it goes back to the end of the queue
 * (a client reading as fast as loopback delivers would otherwise keep its thread from
 * epoll_wait, the deadlines and libmicrohttpd's connections): 2 MB of body, the default of
 * nginx's sendfile_max_chunk for the same loop; 8 answers bound pipelined small ones. */
#define WAKE_BYTES ((size_t)2 << 20)
#define WAKE_ANSWERS 8

typedef struct fconn {
    int fd;
    struct sockaddr_storage peer;
    socklen_t peer_len;
    bool sending;
    bool nodelay; /* TCP_NODELAY set (at its first answer, for good: send_some) */
    bool spent;      /* queued again with its wake-up's share spent, the socket not full */
    unsigned unsent; /* its TCP_NOTSENT_LOWAT (h.unsent_min until adapt_unsent moves it) */
    long long woke_ns; /* when its answer last found the socket full or started */
    ism_front_answer a;
    size_t head_sent, body_sent;
    long long deadline_ns;
    void *ctx; /* the hooks' (opened) */
    struct fconn *prev, *next;
} fconn;

struct ism_front {
    ism_front_hooks h;
    int listen_fd, ep;
    struct MHD_Daemon *d;
    atomic_bool quiesced;
    long long paused_until_ns; /* 0: the listening socket is in ep */
    fconn *head;
    /* connections held, with those handed in and not yet taken: written by this front and by
     * the fronts handing it connections, read by all of them to find the least held */
    atomic_uint n;
    long long next_scan_ns;
    ism_front *peer;       /* the next front on the same listening socket (a ring; itself) */
    pthread_mutex_t in_mu; /* guards inbox */
    fconn *inbox;          /* accepted by another front for this one (hand_in) */
    int in_fd;             /* an eventfd in ep: readable once something is in inbox */
    int watch[WATCH_MAX]; /* their events' data.ptr: &watch[i] */
    unsigned watched;
};

static long long after(double s)
{
    return ism_now_ns() + (long long)(s * 1e9);
}

static void unlink_conn(ism_front *f, fconn *c)
{
    if (c->prev)
        c->prev->next = c->next;
    else
        f->head = c->next;
    if (c->next)
        c->next->prev = c->prev;
    atomic_fetch_sub(&f->n, 1);
    epoll_ctl(f->ep, EPOLL_CTL_DEL, c->fd, NULL);
}

/* The end of a connection no longer linked: the closed hook, its socket, its entry. */
static void release(ism_front *f, fconn *c)
{
    if (c->ctx && f->h.closed)
        f->h.closed(f->h.cls, c->ctx);
    close(c->fd);
    free(c);
}

static void drop(ism_front *f, fconn *c)
{
    unlink_conn(f, c);
    release(f, c);
}

/* To libmicrohttpd, with whatever the client sent still unread in the socket. */
static void give(ism_front *f, int fd, const struct sockaddr_storage *peer, socklen_t len,
                 void *ctx)
{
    if (ctx && f->h.handing)
        f->h.handing(f->h.cls, ctx);
    if (MHD_add_connection(f->d, fd, (const struct sockaddr *)peer, len) != MHD_YES)
        ism_logf(ISM_LOG_WARN, "http_front", "libmicrohttpd refused a connection: %s",
                 strerror(errno)); /* it closed the socket */
    if (ctx && f->h.handing)
        f->h.handing(f->h.cls, NULL);
}

static void set_unsent(fconn *c, unsigned bytes)
{
    if (setsockopt(c->fd, IPPROTO_TCP, TCP_NOTSENT_LOWAT, &bytes, sizeof bytes) == 0)
        c->unsent = bytes;
}

static void give_conn(ism_front *f, fconn *c)
{
    unlink_conn(f, c);
    /* TCP_NODELAY stays as the own answers left it (set, no cork: libmicrohttpd takes the
     * Nagle and cork state of a socket it is given for unknown and sets what it needs) */
    if (c->unsent != f->h.unsent_min) /* libmicrohttpd's copies are bounded by the listening
                                         socket's (isomeshd http.c NOTSENT_LOWAT) */
        set_unsent(c, f->h.unsent_min);
    give(f, c->fd, &c->peer, c->peer_len, c->ctx);
    free(c);
}

enum { SENT_WHOLE = 1, SOCKET_FULL = 0, SEND_FAILED = -1, WAKE_SPENT = 2 };

/* Sends what is left of c's answer, at most *budget bytes (taken off it): SENT_WHOLE (and
 * pushed), SOCKET_FULL, SEND_FAILED, or WAKE_SPENT with the socket still taking bytes.
 * Segments stay full without a cork: the header block goes with MSG_MORE (held back for the
 * body), sendfile marks every chunk but its last one MSG_MORE itself, and the last one leaves
 * at once under TCP_NODELAY, set once per connection. So an answer is two system calls, as
 * with nginx's sendfile (which corks and uncorks around it: two more). Why not the cork this
 * front kept on, pushing each answer's last segment by setting TCP_NODELAY (one setsockopt
 * per answer): under the system's bbr (no fq qdisc, so TCP paces with a timer of its own) it
 * cost twice nginx's CPU per answer, almost all in the kernel (perf: the pacing timer's
 * _raw_spin_unlock_irqrestore under tcp_write_xmit, 22% of the daemon's samples against
 * nginx's 11%, softirqs 10.7% against 3.4%). Measured: cached 336 KB mesh, wrk -t2, 16
 * connections, 3 alternated rounds of 5 s beside nginx (a worker per core), load 11-16: the
 * daemon's CPU per request 86.9 us with the kept cork, 43.6 uncorking after each answer as
 * nginx does, 40.8 this way (nginx 51.9); req/s 0.86x, 1.15x, 1.14x nginx's. */
static int send_some(fconn *c, size_t *budget)
{
    if (!c->nodelay) {
        int one = 1;
        setsockopt(c->fd, IPPROTO_TCP, TCP_NODELAY, &one, sizeof one);
        c->nodelay = true;
    }
    while (c->head_sent < c->a.head_len) {
        ssize_t n = send(c->fd, c->a.head + c->head_sent, c->a.head_len - c->head_sent,
                         (c->a.len ? MSG_MORE : 0) | MSG_NOSIGNAL);
        if (n < 0)
            return errno == EAGAIN || errno == EWOULDBLOCK ? SOCKET_FULL : SEND_FAILED;
        c->head_sent += (size_t)n;
    }
    while (c->body_sent < c->a.len) {
        if (!*budget)
            return WAKE_SPENT;
        size_t want = c->a.len - c->body_sent;
        size_t now = want < *budget ? want : *budget;
        off_t off = (off_t)(c->a.offset + (long long)c->body_sent);
        /* a body in memory: the last piece leaves at once, as sendfile's last chunk does */
        ssize_t n = c->a.mem ? send(c->fd, c->a.mem + c->body_sent, now,
                                    (now < want ? MSG_MORE : 0) | MSG_NOSIGNAL)
                             : sendfile(c->fd, c->a.fd, &off, now);
        if (n < 0)
            return errno == EAGAIN || errno == EWOULDBLOCK ? SOCKET_FULL : SEND_FAILED;
        if (n == 0)
            return SEND_FAILED; /* the file is shorter than promised */
        c->body_sent += (size_t)n;
        *budget -= (size_t)n;
    }
    return SENT_WHOLE;
}

/* The unsent queue a connection gets, adapted at each wake-up that continues a body: the
 * kernel wakes a writer once less than half its TCP_NOTSENT_LOWAT is unsent, so a body of B
 * bytes takes about 2B / lowat wake-ups for a reader that is not as fast as loopback (1.55
 * MB at the listening socket's 256 KB: 6-12; nginx, whose sendfile queues a whole body,
 * 0.2-0.4 per request at 256 connections). A 4 MB queue for every connection halved the
 * CPU per 1.55 MB answer at 256 connections, but beside 450 slow readers /healthz's p99
 * went from ~10 ms to 180-1,000 ms (4 MB queued for each: the kernel's TCP memory under
 * pressure, long sends on the polling threads). So the queue follows the reader's rate,
 * the bytes the socket took at this wake-up over the time since the last one: from
 * KEEP_UP_BPS it doubles (up to unsent_max), below SLOW_BPS it halves (down to unsent_min,
 * which a slow reader therefore keeps), in between it stays. A wake-up that moved under a
 * quarter of the queue (bytes arriving, not room made) says nothing. */
#define KEEP_UP_BPS (512ll << 10) /* 6x bench_http's slow readers (16 KB per 0.2 s) */
#define SLOW_BPS (160ll << 10)    /* 2x them */
static void adapt_unsent(ism_front *f, fconn *c, size_t moved, long long now)
{
    long long dt = now - c->woke_ns;
    c->woke_ns = now;
    if (dt <= 0)
        return;
    long long bps = (long long)((double)moved * 1e9 / (double)dt);
    if (bps >= KEEP_UP_BPS && moved >= c->unsent / 4 && c->unsent < f->h.unsent_max)
        set_unsent(c, c->unsent * 2 < f->h.unsent_max ? c->unsent * 2 : f->h.unsent_max);
    else if (bps < SLOW_BPS && c->unsent > f->h.unsent_min)
        set_unsent(c, c->unsent / 2 > f->h.unsent_min ? c->unsent / 2 : f->h.unsent_min);
}

/* Back to the end of the queue: MOD reports a ready socket again, edge-triggered or not
 * (should it fail, c's deadline still ends it). */
static void requeue(ism_front *f, fconn *c)
{
    struct epoll_event ev = {.events = EPOLLIN | EPOLLOUT | EPOLLRDHUP | EPOLLET, .data.ptr = c};
    epoll_ctl(f->ep, EPOLL_CTL_MOD, c->fd, &ev);
}

/* Sends what c has to send, then answers the requests that have arrived, until the socket
 * is full or empty or this wake-up's share is spent (then c is queued again); hands c over
 * or closes it when that is its end. */
static void serve(ism_front *f, fconn *c)
{
    size_t budget = WAKE_BYTES;
    for (unsigned answers = 0;;) {
        if (c->sending) {
            size_t moved = c->head_sent + c->body_sent;
            bool resumed = c->body_sent && !c->spent; /* the socket full last time, now not */
            c->spent = false;
            int st = send_some(c, &budget);
            if (resumed)
                adapt_unsent(f, c, c->head_sent + c->body_sent - moved, ism_now_ns());
            if (st == SOCKET_FULL || st == WAKE_SPENT) {
                /* only bytes moved push the deadline back (set where the answer starts): a
                 * wake-up for bytes arriving must not, or a client trickling them holds an
                 * answer stalled before its first byte for ever */
                if (c->head_sent + c->body_sent != moved)
                    c->deadline_ns = after(f->h.stall_s);
                if (st == WAKE_SPENT) {
                    c->spent = true;
                    requeue(f, c);
                }
                return;
            }
            c->sending = false;
            f->h.done(f->h.cls, &c->a, st == SENT_WHOLE);
            if (c->ctx && f->h.busy)
                f->h.busy(f->h.cls, c->ctx, false);
            if (st == SEND_FAILED) {
                drop(f, c);
                return;
            }
            c->deadline_ns = after(f->h.idle_s);
            if (++answers == WAKE_ANSWERS) {
                requeue(f, c);
                return;
            }
        }
        char buf[HEAD_PEEK];
        ssize_t n = recv(c->fd, buf, sizeof buf, MSG_PEEK);
        if (n < 0 && (errno == EAGAIN || errno == EWOULDBLOCK))
            return;
        if (n <= 0) { /* closed by the client, or failed */
            drop(f, c);
            return;
        }
        const char *end = memmem(buf, (size_t)n, "\r\n\r\n", 4);
        size_t len = end ? (size_t)(end + 4 - buf) : 0;
        c->a.mem = NULL; /* a file's, unless the hook says otherwise */
        if (!end || atomic_load(&f->quiesced) ||
            !f->h.answer(f->h.cls, buf, len, c->ctx, &c->a)) {
            give_conn(f, c); /* a head still arriving, or a request not ours */
            return;
        }
        if (recv(c->fd, buf, len, 0) != (ssize_t)len) { /* peeked bytes: cannot fail */
            f->h.done(f->h.cls, &c->a, false);
            drop(f, c);
            return;
        }
        c->sending = true;
        c->head_sent = c->body_sent = 0;
        c->woke_ns = ism_now_ns();
        c->deadline_ns = c->woke_ns + (long long)(f->h.stall_s * 1e9);
        if (c->ctx && f->h.busy)
            f->h.busy(f->h.cls, c->ctx, true);
    }
}

/* Starts holding c (counted in f->n already): its events, then what it has sent. */
static void hold(ism_front *f, fconn *c)
{
    struct epoll_event ev = {.events = EPOLLIN | EPOLLOUT | EPOLLRDHUP | EPOLLET, .data.ptr = c};
    if (epoll_ctl(f->ep, EPOLL_CTL_ADD, c->fd, &ev) != 0) {
        atomic_fetch_sub(&f->n, 1);
        give(f, c->fd, &c->peer, c->peer_len, c->ctx);
        free(c);
        return;
    }
    c->prev = NULL;
    c->next = f->head;
    if (f->head)
        f->head->prev = c;
    f->head = c;
    serve(f, c); /* the request has often arrived with the connection */
}

/* The front holding the fewest connections, f on a tie. Why: the listening socket wakes the
 * first front in its wait queue whose thread sleeps in epoll_wait, and a front stays ready
 * for it while connections wait in the backlog (level-triggered), so the one that wakes
 * would take a whole burst (measured: wrk's 64 connections, all on one of four fronts). */
static ism_front *least_held(ism_front *f)
{
    ism_front *best = f;
    unsigned fewest = atomic_load(&f->n);
    for (ism_front *p = f->peer; p != f; p = p->peer) {
        unsigned n = atomic_load(&p->n);
        if (n < fewest)
            best = p, fewest = n;
    }
    return best;
}

/* c, accepted by another front, to t (counted in t->n already), which holds it on its thread
 * (take_in): each front's connections are served by its own thread only. */
static void hand_in(ism_front *t, fconn *c)
{
    pthread_mutex_lock(&t->in_mu);
    c->next = t->inbox;
    t->inbox = c;
    pthread_mutex_unlock(&t->in_mu);
    uint64_t one = 1;
    if (write(t->in_fd, &one, sizeof one) != sizeof one) /* cannot overflow: read empties it */
        ism_logf(ISM_LOG_WARN, "http_front", "eventfd: %s", strerror(errno));
}

static void take_in(ism_front *f)
{
    uint64_t count;
    if (read(f->in_fd, &count, sizeof count) < 0 && errno != EAGAIN)
        ism_logf(ISM_LOG_WARN, "http_front", "eventfd: %s", strerror(errno));
    pthread_mutex_lock(&f->in_mu);
    fconn *c = f->inbox;
    f->inbox = NULL;
    pthread_mutex_unlock(&f->in_mu);
    while (c) {
        fconn *next = c->next;
        hold(f, c);
        c = next;
    }
}

static void accept_some(ism_front *f)
{
    if (atomic_load(&f->quiesced)) { /* a re-arm (listen_again) raced the quiesce */
        epoll_ctl(f->ep, EPOLL_CTL_DEL, f->listen_fd, NULL);
        return;
    }
    for (int i = 0; i < ACCEPT_BATCH && !atomic_load(&f->quiesced); i++) {
        struct sockaddr_storage peer;
        socklen_t len = sizeof peer;
        int fd = accept4(f->listen_fd, (struct sockaddr *)&peer, &len,
                         SOCK_NONBLOCK | SOCK_CLOEXEC);
        if (fd < 0) {
            if (errno == EMFILE || errno == ENFILE || errno == ENOBUFS || errno == ENOMEM) {
                ism_logf(ISM_LOG_WARN, "http_accept", "%s: accepting pauses", strerror(errno));
                epoll_ctl(f->ep, EPOLL_CTL_DEL, f->listen_fd, NULL);
                f->paused_until_ns = ism_now_ns() + ACCEPT_PAUSE_NS;
            } else if (errno != EAGAIN && errno != EWOULDBLOCK && errno != ECONNABORTED)
                ism_logf(ISM_LOG_WARN, "http_accept", "%s", strerror(errno));
            return;
        }
        fconn *c = atomic_load(&f->n) < f->h.max_conns ? calloc(1, sizeof *c) : NULL;
        if (!c) {
            give(f, fd, &peer, len, NULL);
            continue;
        }
        bool keep = true;
        c->ctx = f->h.opened ? f->h.opened(f->h.cls, fd, (const struct sockaddr *)&peer, &keep)
                             : NULL;
        if (!keep) { /* refused by the caller's rules: libmicrohttpd answers or closes it */
            give(f, fd, &peer, len, c->ctx);
            free(c);
            continue;
        }
        c->fd = fd;
        c->unsent = f->h.unsent_min; /* the listening socket's, inherited */
        c->peer = peer;
        c->peer_len = len;
        c->deadline_ns = after(f->h.idle_s);
        ism_front *to = least_held(f);
        atomic_fetch_add(&to->n, 1);
        if (to == f)
            hold(f, c);
        else
            hand_in(to, c);
    }
}

static void listen_again(ism_front *f, long long now)
{
    if (!f->paused_until_ns || now < f->paused_until_ns)
        return;
    f->paused_until_ns = 0;
    struct epoll_event ev = {.events = EPOLLIN | EPOLLEXCLUSIVE, .data.ptr = NULL};
    if (!atomic_load(&f->quiesced))
        epoll_ctl(f->ep, EPOLL_CTL_ADD, f->listen_fd, &ev);
}

static void check_deadlines(ism_front *f)
{
    long long now = ism_now_ns();
    listen_again(f, now);
    if (now < f->next_scan_ns)
        return;
    f->next_scan_ns = now + SCAN_NS;
    for (fconn *c = f->head, *next; c; c = next) {
        next = c->next;
        if (now < c->deadline_ns)
            continue;
        if (c->sending) { /* a reader that stopped reading */
            f->h.done(f->h.cls, &c->a, false);
            drop(f, c);
        } else {
            give_conn(f, c);
        }
    }
}

ism_front *ism_front_new(const ism_front_hooks *h, int listen_fd, struct MHD_Daemon *d,
                         ism_front *peer)
{
    ism_front *f = calloc(1, sizeof *f);
    if (!f)
        return NULL;
    f->h = *h;
    f->listen_fd = listen_fd;
    f->d = d;
    f->ep = epoll_create1(EPOLL_CLOEXEC);
    f->in_fd = eventfd(0, EFD_CLOEXEC | EFD_NONBLOCK);
    struct epoll_event ev = {.events = EPOLLIN | EPOLLEXCLUSIVE, .data.ptr = NULL};
    struct epoll_event in = {.events = EPOLLIN, .data.ptr = &f->in_fd};
    int fl = fcntl(listen_fd, F_GETFL); /* every front accepts: none may block in accept */
    if (f->ep < 0 || f->in_fd < 0 || fl < 0 || fcntl(listen_fd, F_SETFL, fl | O_NONBLOCK) != 0 ||
        epoll_ctl(f->ep, EPOLL_CTL_ADD, listen_fd, &ev) != 0 ||
        epoll_ctl(f->ep, EPOLL_CTL_ADD, f->in_fd, &in) != 0) {
        ism_logf(ISM_LOG_ERROR, "http_start_failed", "front epoll: %s", strerror(errno));
        if (f->ep >= 0)
            close(f->ep);
        if (f->in_fd >= 0)
            close(f->in_fd);
        free(f);
        return NULL;
    }
    pthread_mutex_init(&f->in_mu, NULL);
    if (peer) { /* into peer's ring, before any of its threads runs */
        f->peer = peer->peer;
        peer->peer = f;
    } else {
        f->peer = f;
    }
    return f;
}

int ism_front_watch(ism_front *f, int fd)
{
    if (f->watched == WATCH_MAX)
        return -1;
    f->watch[f->watched] = fd;
    struct epoll_event ev = {.events = EPOLLIN, .data.ptr = &f->watch[f->watched]};
    if (epoll_ctl(f->ep, EPOLL_CTL_ADD, fd, &ev) != 0) {
        ism_logf(ISM_LOG_ERROR, "http_start_failed", "front epoll: %s", strerror(errno));
        return -1;
    }
    return (int)f->watched++;
}

unsigned ism_front_run(ism_front *f, int timeout_ms)
{
    struct epoll_event evs[EVENTS];
    int n = epoll_wait(f->ep, evs, EVENTS, timeout_ms);
    if (n < 0 && errno != EINTR)
        ism_logf(ISM_LOG_WARN, "http_poll", "%s", strerror(errno));
    unsigned fired = 0;
    for (int i = 0; i < n; i++) {
        void *p = evs[i].data.ptr;
        if (!p)
            accept_some(f);
        else if (p == &f->in_fd)
            take_in(f);
        else if ((int *)p >= f->watch && (int *)p < f->watch + WATCH_MAX)
            fired |= 1u << ((int *)p - f->watch);
        else
            serve(f, p);
    }
    check_deadlines(f);
    return fired;
}

int ism_front_wait_ms(const ism_front *f, int max_ms)
{
    if (!f->head && !f->paused_until_ns)
        return max_ms;
    long long ms = (f->next_scan_ns - ism_now_ns()) / 1000000 + 1;
    return ms < 0 ? 0 : ms < max_ms ? (int)ms : max_ms;
}

void ism_front_quiesce(ism_front *f)
{
    atomic_store(&f->quiesced, true);
    epoll_ctl(f->ep, EPOLL_CTL_DEL, f->listen_fd, NULL);
}

void ism_front_free(ism_front *f)
{
    if (!f)
        return;
    while (f->head) {
        fconn *c = f->head;
        if (c->sending)
            f->h.done(f->h.cls, &c->a, false);
        drop(f, c);
    }
    for (fconn *c = f->inbox, *next; c; c = next) { /* handed in, never held */
        next = c->next;
        release(f, c);
    }
    close(f->in_fd);
    close(f->ep);
    pthread_mutex_destroy(&f->in_mu);
    free(f);
}
