/* conns.c — the connection table of conns.h: per-address holders (a name table and a list),
 * each with its idle and busy connections in order, the fair admission at the limit, and the
 * thread that enforces the request deadlines and notices clients that left. */
#include "server/isomeshd/conns.h"

#include <errno.h>
#include <pthread.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/socket.h>
#include <time.h>

#include "core/util/clock.h"
#include "server/common/log.h"
#include "server/common/text_hash.h"
#include "server/isomeshd/client_addr.h"

#define NBUCKETS 1024          /* holder name table; addresses are few beside connections */
#define ADDR_MAX 64            /* an IPv6 literal with room to spare */
/* The thread's period: a deadline is enforced at most this late. */
#define TICK_NS 250000000LL
/* Refused connections left open for their first request (answered 503, then closed): at most
 * this many at once (beyond, a refusal closes at once), each for at most REFUSED_WAIT_NS
 * (a client sends its request as soon as it connects; one that does not is not waited for).
 * Bounded like the evicted connections that linger (http.c's CUT_ROOM). */
#define REFUSED_ROOM(max) ((max) / 16u + 16u)
#define REFUSED_WAIT_NS 2000000000LL
/* Sockets of requests in progress are peeked every this many ticks (a peek is a system call
 * per connection; a client that left is noticed within a second). */
#define PEEK_EVERY 4

typedef enum phase { P_READY, P_BODY, P_WORKING } phase;
/* A refused connection: closed at once, or open until its 503 is sent (counted in
 * t->lingering until libmicrohttpd closes it). */
typedef enum refusal { L_NONE, L_OPEN, L_COUNTED } refusal;

/* A link of a circular list with a sentinel. */
typedef struct node {
    struct node *prev, *next;
} node;

typedef struct holder {
    char addr[ADDR_MAX];
    unsigned count;            /* connections admitted and not closed by the table */
    node idle, busy;           /* ready for a request / receiving or answering one; oldest first */
    struct holder *hnext;      /* name table chain */
    node all;                  /* in the table's list of holders */
} holder;

struct ismd_conn {
    int fd;
    char addr[ADDR_MAX];       /* the peer's address as text, as opened (never changes) */
    holder *h;                 /* NULL once the table closed it (or refused it) */
    phase phase;
    long long since_ns;        /* start of the phase */
    void *req;                 /* the request in progress, if any */
    const char *cut;           /* why the table closed it */
    bool left_told;            /* client_left was called for this request */
    refusal linger;
    node link;                 /* in h->idle or h->busy */
    node all;                  /* in the table's list of connections */
};

struct ismd_conns {
    ismd_conns_config cfg;
    ismd_metrics *m;
    pthread_mutex_t lock;
    pthread_cond_t wake;
    holder *buckets[NBUCKETS];
    node holders, conns;
    unsigned count;            /* admitted connections (the limit counts these) */
    unsigned lingering;        /* refused ones left open for a 503 */
    bool stopping;
    pthread_t thread;
};

#define CONTAINER(ptr, type, field) ((type *)((char *)(ptr) - offsetof(type, field)))

static void node_init(node *s)
{
    s->prev = s->next = s;
}

static void node_push(node *s, node *n)
{
    n->prev = s->prev;
    n->next = s;
    s->prev->next = n;
    s->prev = n;
}

static void node_unlink(node *n)
{
    n->prev->next = n->next;
    n->next->prev = n->prev;
    n->prev = n->next = n;
}

static bool node_empty(const node *s)
{
    return s->next == s;
}

/* ---- holders ------------------------------------------------------------------------- */

static holder **holder_slot(ismd_conns *t, const char *addr)
{
    holder **h = &t->buckets[ism_text_hash(addr) % NBUCKETS];
    while (*h && strcmp((*h)->addr, addr) != 0)
        h = &(*h)->hnext;
    return h;
}

static holder *holder_get(ismd_conns *t, const char *addr)
{
    holder **slot = holder_slot(t, addr);
    if (*slot)
        return *slot;
    holder *h = calloc(1, sizeof *h);
    if (!h)
        return NULL;
    snprintf(h->addr, sizeof h->addr, "%s", addr);
    node_init(&h->idle);
    node_init(&h->busy);
    node_push(&t->holders, &h->all);
    *slot = h;
    return h;
}

static void holder_release(ismd_conns *t, holder *h)
{
    if (h->count)
        return;
    holder **slot = holder_slot(t, h->addr);
    *slot = h->hnext;
    node_unlink(&h->all);
    free(h);
}

static void publish(ismd_conns *t)
{
    atomic_store(&t->m->connections, (long long)t->count);
}

static void attach(ismd_conns *t, holder *h, ismd_conn *c)
{
    c->h = h;
    node_push(c->phase == P_READY ? &h->idle : &h->busy, &c->link);
    h->count++;
    t->count++;
    publish(t);
}

static void detach(ismd_conns *t, ismd_conn *c)
{
    holder *h = c->h;
    if (!h)
        return;
    node_unlink(&c->link);
    c->h = NULL;
    h->count--;
    t->count--;
    holder_release(t, h);
    publish(t);
}

/* Closes c for the given reason: it stops counting now, libmicrohttpd frees it when it sees
 * the end of its stream. A request of c's still in progress is told its client is gone: one
 * suspended for a computation would otherwise hold both until the computation ends. */
static void cut(ismd_conns *t, ismd_conn *c, const char *why, ismd_cut_reason metric)
{
    detach(t, c);
    c->cut = why;
    shutdown(c->fd, SHUT_RDWR);
    atomic_fetch_add(&t->m->connections_closed[metric], 1);
    if (c->phase == P_WORKING && c->req && !c->left_told && t->cfg.client_left) {
        c->left_told = true;
        t->cfg.client_left(t->cfg.ctx, c->req);
    }
}

/* ---- admission ----------------------------------------------------------------------- */

static ismd_conn *oldest(node *list)
{
    return node_empty(list) ? NULL : CONTAINER(list->next, ismd_conn, link);
}

static ismd_conn *newest(node *list)
{
    return node_empty(list) ? NULL : CONTAINER(list->prev, ismd_conn, link);
}

/* At the limit, a connection of h's arrives: the one to close in its place, or NULL (the new
 * one is refused). Only a holder with two more connections than h gives one up, so after the
 * exchange it still holds at least as many as h: no two addresses take turns. */
static ismd_conn *victim(ismd_conns *t, holder *h)
{
    holder *with_idle = NULL, *largest = NULL;
    for (node *n = t->holders.next; n != &t->holders; n = n->next) {
        holder *g = CONTAINER(n, holder, all);
        if (g->count < h->count + 2)
            continue;
        if (!node_empty(&g->idle) && (!with_idle || g->count > with_idle->count))
            with_idle = g;
        if (!largest || g->count > largest->count)
            largest = g;
    }
    if (with_idle)
        return oldest(&with_idle->idle);
    if (largest)
        return newest(&largest->busy);
    return oldest(&h->idle);
}

/* Refuses c: left open for a 503 while there is room, else closed now. Lock held. */
static void refuse(ismd_conns *t, ismd_conn *c)
{
    c->cut = "refused";
    atomic_fetch_add(&t->m->connections_closed[ISMD_CUT_REFUSED], 1);
    if (t->lingering < REFUSED_ROOM(t->cfg.max)) {
        c->linger = L_OPEN;
        t->lingering++;
    } else {
        shutdown(c->fd, SHUT_RDWR);
    }
}

/* Is h at its address's cap (a trusted proxy has none)? */
static bool at_address_cap(const ismd_conns *t, const holder *h)
{
    return t->cfg.per_address && h->count >= t->cfg.per_address &&
           !(t->cfg.trusted && ismd_address_listed(t->cfg.trusted, h->addr));
}

unsigned ismd_conns_refused_room(unsigned max)
{
    return REFUSED_ROOM(max);
}

ismd_conn *ismd_conns_opened(ismd_conns *t, int fd, const char *addr)
{
    ismd_conn *c = calloc(1, sizeof *c);
    if (!c)
        return NULL;
    c->fd = fd;
    snprintf(c->addr, sizeof c->addr, "%s", addr);
    c->phase = P_READY;
    c->since_ns = ism_now_ns();
    node_init(&c->link);
    pthread_mutex_lock(&t->lock);
    node_push(&t->conns, &c->all);
    holder *h = holder_get(t, addr);
    if (!h) {
        c->cut = "refused";
        shutdown(fd, SHUT_RDWR);
    } else if (at_address_cap(t, h)) {
        refuse(t, c);
    } else if (t->count < t->cfg.max) {
        attach(t, h, c);
    } else {
        ismd_conn *v = victim(t, h);
        if (v) {
            attach(t, h, c); /* first: v may be h's own last one */
            cut(t, v, "evicted", v->phase == P_READY ? ISMD_CUT_EVICTED_IDLE
                                                       : ISMD_CUT_EVICTED_BUSY);
        } else {
            holder_release(t, h);
            refuse(t, c);
        }
    }
    pthread_mutex_unlock(&t->lock);
    return c;
}

const char *ismd_conns_peer(const ismd_conn *c)
{
    return c ? c->addr : NULL;
}

void ismd_conns_closed(ismd_conns *t, ismd_conn *c)
{
    if (!c)
        return;
    pthread_mutex_lock(&t->lock);
    detach(t, c);
    node_unlink(&c->all);
    if (c->linger != L_NONE)
        t->lingering--;
    pthread_mutex_unlock(&t->lock);
    free(c);
}

bool ismd_conns_refused(ismd_conns *t, const ismd_conn *c)
{
    if (!c)
        return false;
    pthread_mutex_lock(&t->lock);
    bool open = c->linger == L_OPEN;
    pthread_mutex_unlock(&t->lock);
    return open;
}

/* ---- phases -------------------------------------------------------------------------- */

/* Moves c to phase p, into the list of its holder that p belongs to. Lock held. */
static void set_phase(ismd_conn *c, phase p)
{
    c->phase = p;
    c->since_ns = ism_now_ns();
    if (!c->h)
        return;
    node_unlink(&c->link);
    node_push(p == P_READY ? &c->h->idle : &c->h->busy, &c->link);
}

void ismd_conns_request(ismd_conns *t, ismd_conn *c, void *req, bool body)
{
    if (!c)
        return;
    pthread_mutex_lock(&t->lock);
    c->req = req;
    c->left_told = false;
    set_phase(c, body ? P_BODY : P_WORKING);
    pthread_mutex_unlock(&t->lock);
}

void ismd_conns_body_done(ismd_conns *t, ismd_conn *c)
{
    if (!c)
        return;
    pthread_mutex_lock(&t->lock);
    if (c->phase == P_BODY)
        set_phase(c, P_WORKING);
    pthread_mutex_unlock(&t->lock);
}

void ismd_conns_request_done(ismd_conns *t, ismd_conn *c)
{
    if (!c)
        return;
    pthread_mutex_lock(&t->lock);
    c->req = NULL;
    set_phase(c, P_READY);
    pthread_mutex_unlock(&t->lock);
}

const char *ismd_conns_cut_reason(ismd_conns *t, const ismd_conn *c)
{
    if (!c)
        return NULL;
    pthread_mutex_lock(&t->lock);
    const char *why = c->cut;
    pthread_mutex_unlock(&t->lock);
    return why;
}

/* ---- the watch thread ---------------------------------------------------------------- */

/* Did the peer close its end (or reset it)? Bytes waiting (a pipelined request) say no. */
static bool peer_closed(int fd)
{
    char b;
    ssize_t n = recv(fd, &b, 1, MSG_PEEK | MSG_DONTWAIT);
    if (n == 0)
        return true;
    return n < 0 && errno != EAGAIN && errno != EWOULDBLOCK && errno != EINTR;
}

static void sweep(ismd_conns *t, long long now, bool peek)
{
    long long header_ns = (long long)(t->cfg.header_s * 1e9);
    long long body_ns = (long long)(t->cfg.body_s * 1e9);
    for (node *n = t->conns.next; n != &t->conns; n = n->next) {
        ismd_conn *c = CONTAINER(n, ismd_conn, all);
        long long age = now - c->since_ns;
        if (c->linger == L_OPEN && c->phase == P_READY && age > REFUSED_WAIT_NS) {
            c->linger = L_COUNTED; /* no request came: closed without its 503 */
            shutdown(c->fd, SHUT_RDWR);
        }
        if (c->cut)
            continue;
        if (c->phase == P_READY && age > header_ns)
            cut(t, c, "header_deadline", ISMD_CUT_HEADER_DEADLINE);
        else if (c->phase == P_BODY && age > body_ns)
            cut(t, c, "body_deadline", ISMD_CUT_BODY_DEADLINE);
        else if (peek && c->phase == P_WORKING && c->req && !c->left_told &&
                 peer_closed(c->fd)) {
            c->left_told = true;
            if (t->cfg.client_left)
                t->cfg.client_left(t->cfg.ctx, c->req);
        }
    }
}

static void *watch_main(void *arg)
{
    ismd_conns *t = arg;
    unsigned tick = 0;
    pthread_mutex_lock(&t->lock);
    while (!t->stopping) {
        struct timespec until;
        clock_gettime(CLOCK_MONOTONIC, &until);
        long long ns = until.tv_nsec + TICK_NS;
        until.tv_sec += ns / 1000000000LL;
        until.tv_nsec = ns % 1000000000LL;
        pthread_cond_timedwait(&t->wake, &t->lock, &until);
        if (!t->stopping)
            sweep(t, ism_now_ns(), ++tick % PEEK_EVERY == 0);
    }
    pthread_mutex_unlock(&t->lock);
    return NULL;
}

ismd_conns *ismd_conns_start(const ismd_conns_config *cfg, ismd_metrics *metrics)
{
    ismd_conns *t = calloc(1, sizeof *t);
    if (!t)
        return NULL;
    t->cfg = *cfg;
    t->m = metrics;
    node_init(&t->holders);
    node_init(&t->conns);
    pthread_condattr_t ca;
    pthread_condattr_init(&ca);
    pthread_condattr_setclock(&ca, CLOCK_MONOTONIC);
    pthread_cond_init(&t->wake, &ca);
    pthread_condattr_destroy(&ca);
    pthread_mutex_init(&t->lock, NULL);
    if (pthread_create(&t->thread, NULL, watch_main, t) != 0) {
        ism_logf(ISM_LOG_ERROR, "thread_failed", "the connection watch thread did not start");
        pthread_cond_destroy(&t->wake);
        pthread_mutex_destroy(&t->lock);
        free(t);
        return NULL;
    }
    return t;
}

void ismd_conns_stop(ismd_conns *t)
{
    if (!t)
        return;
    pthread_mutex_lock(&t->lock);
    t->stopping = true;
    pthread_cond_signal(&t->wake);
    pthread_mutex_unlock(&t->lock);
    pthread_join(t->thread, NULL);
    while (!node_empty(&t->conns)) { /* none once libmicrohttpd has stopped */
        ismd_conn *c = CONTAINER(t->conns.next, ismd_conn, all);
        detach(t, c);
        node_unlink(&c->all);
        free(c);
    }
    pthread_cond_destroy(&t->wake);
    pthread_mutex_destroy(&t->lock);
    free(t);
}
