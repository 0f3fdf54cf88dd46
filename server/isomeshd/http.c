/* http.c — the request life cycle of http.h: libmicrohttpd set-up, the first call (501 for
 * an unknown Transfer-Encoding, route, then 404, 405, 401, 400, 413 from Content-Length,
 * 415), reading the body within --max-body,
 * answering on a later call (or closing when the client left a suspended request), one log
 * line and the metrics per request when MHD reports it complete, and the connection table's
 * view of every connection (conns.h). */
#include "server/isomeshd/http.h"

#include <ctype.h>
#include <errno.h>
#include <fcntl.h>
#include <netinet/in.h>
#include <netinet/tcp.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include <sys/resource.h>
#include <sys/socket.h>
#include <unistd.h>

#include "server/common/log.h"
#include "server/isomeshd/client_addr.h"
#include "server/isomeshd/errors.h"
#include "server/common/http_loops.h"
#include "server/isomeshd/own_conns.h"
#include "server/isomeshd/own_sender.h"
#include "server/isomeshd/request_log.h"
#include "server/isomeshd/respond.h"
#include "server/isomeshd/routes.h"

#define DISCARD_FACTOR 4 /* body bytes we swallow before giving up on a rejected request */

/* ---- request accessors --------------------------------------------------------------- */

static bool method_allowed(const char *allow, const char *method)
{
    size_t n = strlen(method);
    for (const char *p = allow; p && *p;) {
        size_t len = strcspn(p, ",");
        if (len == n && !strncmp(p, method, n))
            return true;
        p += len;
        while (*p == ',' || *p == ' ')
            p++;
    }
    return false;
}

static void early(ismd_req *r, unsigned status, const char *code, const char *msg)
{
    r->early_status = status;
    r->early_code = code;
    snprintf(r->early_msg, sizeof r->early_msg, "%s", msg);
}

/* Content-Type must be JSON (a missing one is taken as JSON). `curl -d @request.json`
 * labels its body application/x-www-form-urlencoded; that is accepted too, because the body
 * is parsed strictly as JSON either way — scripts work as written in the README. */
static bool json_content_type(const char *ct)
{
    if (!ct)
        return true;
    while (*ct == ' ')
        ct++;
    size_t n = strcspn(ct, "; ");
    return (n == 16 && strncasecmp(ct, "application/json", 16) == 0) ||
           (n == 33 && strncasecmp(ct, "application/x-www-form-urlencoded", 33) == 0);
}

typedef struct framing {
    int content_length, transfer_encoding;
} framing;

static enum MHD_Result count_framing(void *cls, enum MHD_ValueKind kind, const char *key,
                                     const char *value)
{
    (void)kind;
    (void)value;
    framing *f = cls;
    f->content_length += strcasecmp(key, MHD_HTTP_HEADER_CONTENT_LENGTH) == 0;
    f->transfer_encoding += strcasecmp(key, MHD_HTTP_HEADER_TRANSFER_ENCODING) == 0;
    return MHD_YES;
}

/* Two Content-Length headers, or one beside Transfer-Encoding: a proxy in front may frame the
 * body otherwise than libmicrohttpd does (request smuggling), so such a request is refused. */
static bool framing_conflict(struct MHD_Connection *c)
{
    framing f = {0, 0};
    MHD_get_connection_values(c, MHD_HEADER_KIND, count_framing, &f);
    return f.content_length > 1 || (f.content_length && f.transfer_encoding);
}

/* A Transfer-Encoding other than "chunked" (gzip, "gzip, chunked", anything unknown):
 * libmicrohttpd would read such a body until the client closes, so the request is answered
 * 501 before its body (RFC 9112 6.1: a server that does not understand a coding says so). */
static bool unknown_transfer_coding(ismd_req *r)
{
    const char *te = ismd_header(r, MHD_HTTP_HEADER_TRANSFER_ENCODING);
    if (!te)
        return false;
    te += strspn(te, " \t");
    size_t n = strcspn(te, " \t");
    return !(n == 7 && strncasecmp(te, "chunked", 7) == 0 && te[n + strspn(te + n, " \t")] == 0);
}

/* The first call: build the context, route, and reject what can be rejected before the body
 * arrives. Only a 413 from Content-Length is answered now (the body is never read). */
static enum MHD_Result first_call(ismd_server *s, struct MHD_Connection *conn, const char *url,
                                  const char *method, void **con_cls)
{
    ismd_req *r = calloc(1, sizeof *r);
    if (!r)
        return MHD_NO;
    r->srv = s;
    r->conn = conn;
    r->t0_ns = ism_now_ns();
    snprintf(r->method, sizeof r->method, "%s", method);
    snprintf(r->path, sizeof r->path, "%s", url);
    for (char *p = r->path; *p; p++)
        if ((unsigned char)*p < 0x20 || (unsigned char)*p == 0x7f)
            *p = '?';
    const union MHD_ConnectionInfo *ci = MHD_get_connection_info(conn, MHD_CONNECTION_INFO_SOCKET_CONTEXT);
    r->cn = ci ? ci->socket_context : NULL;
    ismd_conns_request(s->conns, r->cn, r, true); /* a body may follow until the next call */
    ismd_client_address(conn, ismd_conns_peer(r->cn), s->cfg->trusted_proxy, r->client,
                        sizeof r->client);
    ismd_auth_identify(s->auth, ismd_header(r, MHD_HTTP_HEADER_AUTHORIZATION), r->client, &r->who);
    *con_cls = r;
    atomic_fetch_add(&s->open_requests, 1);
    if (ismd_conns_refused(s->conns, r->cn)) {
        r->close_after = true;
        return ismd_respond_error(r, 503, "too_many_connections",
                                  "the server holds as many connections as it may (or as "
                                  "many of your address's as it may); retry shortly");
    }
    if (unknown_transfer_coding(r))
        return ismd_respond_error(r, 501, "not_implemented",
                                  "this Transfer-Encoding is not supported: send the body with "
                                  "Content-Length, or chunked");

    ismd_route_find(r, url);
    if (r->early_status)
        return MHD_YES;
    if (!strcmp(method, "OPTIONS"))
        return MHD_YES;
    if (!method_allowed(r->allow, method) &&
        !(!strcmp(method, "HEAD") && method_allowed(r->allow, "GET"))) {
        early(r, 405, "method_not_allowed", "this method is not allowed here (see Allow)");
        r->wants_body = false;
        return MHD_YES;
    }
    r->handler = ismd_route_handler(r, method, &r->wants_body);
    if (ismd_auth_route_needs_token(s->auth, r->route, method) &&
        ismd_auth_lacking(s->auth, &r->who)) {
        const char *message;
        const char *code = ismd_unauthorized(r, &message);
        early(r, 401, code, message); /* the body is never read */
        r->wants_body = false;
        return MHD_YES;
    }
    if (!r->wants_body)
        return MHD_YES;
    if (framing_conflict(conn)) {
        early(r, 400, "bad_request",
              "conflicting Content-Length or Transfer-Encoding headers: send one of them");
        r->wants_body = false;
        return MHD_YES;
    }
    const char *cl = ismd_header(r, MHD_HTTP_HEADER_CONTENT_LENGTH);
    if (cl) {
        char *end;
        unsigned long long n = strtoull(cl, &end, 10);
        if (n > s->cfg->max_body)
            return ismd_respond_body_too_large(r);
    }
    if (!json_content_type(ismd_header(r, MHD_HTTP_HEADER_CONTENT_TYPE))) {
        early(r, 415, "unsupported_media_type",
              "send the request as Content-Type: application/json");
        r->wants_body = false;
    }
    return MHD_YES;
}

/* Bytes of every request body that --upload-memory does not count: a request's own small
 * body is always received (ordinary requests are a few hundred bytes; a flood of large
 * uploads must not refuse them), so the bound on all bodies is --upload-memory plus this
 * much per connection (64 MB at the default 4000 connections). */
#define UPLOAD_FREE ((size_t)16 << 10)

/* The bytes of a buffer of cap bytes that --upload-memory counts. */
static long long upload_counted(size_t cap)
{
    return cap > UPLOAD_FREE ? (long long)(cap - UPLOAD_FREE) : 0;
}

/* Gives r's body buffer back (and its bytes to --upload-memory). */
static void drop_body(ismd_req *r)
{
    atomic_fetch_sub(&r->srv->metrics.upload_bytes, upload_counted(r->body_cap));
    free(r->body);
    r->body = NULL;
    r->body_len = r->body_cap = 0;
}

/* Takes what growing r's body buffer to cap bytes needs of --upload-memory; false (nothing
 * taken) when every body being received together would then hold more than it. */
static bool reserve_upload(ismd_req *r, size_t cap)
{
    ismd_server *s = r->srv;
    long long grow = upload_counted(cap) - upload_counted(r->body_cap);
    long long now = atomic_fetch_add(&s->metrics.upload_bytes, grow) + grow;
    if (now <= (long long)s->cfg->upload_memory)
        return true;
    atomic_fetch_sub(&s->metrics.upload_bytes, grow);
    return false;
}

static enum MHD_Result take_body(ismd_req *r, const char *data, size_t *size)
{
    size_t n = *size;
    *size = 0;
    size_t max = r->srv->cfg->max_body;
    if (!r->wants_body || r->body_too_big || r->uploads_full || r->status) {
        r->discarded += n;
        return r->discarded > DISCARD_FACTOR * max ? MHD_NO : MHD_YES;
    }
    if (r->body_len + n > max) {
        r->body_too_big = true;
        r->discarded += r->body_len + n;
        drop_body(r);
        return MHD_YES;
    }
    if (r->body_len + n + 1 > r->body_cap) {
        size_t cap = r->body_cap ? r->body_cap : 1024;
        while (cap < r->body_len + n + 1)
            cap *= 2;
        if (cap > max + 1)
            cap = max + 1;
        if (!reserve_upload(r, cap)) {
            r->uploads_full = true;
            r->discarded += r->body_len + n;
            drop_body(r);
            return MHD_YES;
        }
        char *b = realloc(r->body, cap);
        if (!b) {
            atomic_fetch_sub(&r->srv->metrics.upload_bytes,
                             upload_counted(cap) - upload_counted(r->body_cap));
            return MHD_NO;
        }
        r->body = b;
        r->body_cap = cap;
    }
    memcpy(r->body + r->body_len, data, n);
    r->body_len += n;
    r->body[r->body_len] = 0;
    return MHD_YES;
}

static enum MHD_Result on_request(void *cls, struct MHD_Connection *conn, const char *url,
                                  const char *method, const char *version,
                                  const char *upload_data, size_t *upload_size, void **con_cls)
{
    (void)version;
    ismd_server *s = cls;
    ismd_req *r = *con_cls;
    if (!r)
        return first_call(s, conn, url, method, con_cls);
    if (*upload_size)
        return take_body(r, upload_data, upload_size);
    if (r->client_left)
        return MHD_NO; /* nobody to answer: close */
    ismd_conns_body_done(s->conns, r->cn);
    if (r->status)
        return MHD_YES; /* already answered (a 413 on the first call) */
    if (r->ready) {
        r->ready = false;
        return r->on_ready(r);
    }
    if (r->early_status)
        return ismd_respond_error(r, r->early_status, r->early_code, r->early_msg);
    if (!strcmp(r->method, "OPTIONS"))
        return ismd_respond_preflight(r);
    if (r->body_too_big)
        return ismd_respond_body_too_large(r);
    if (r->uploads_full)
        return ismd_respond_error(r, 503, "uploads_full",
                                  "the server is receiving too many request bodies at once "
                                  "(--upload-memory); retry shortly");
    return r->handler(r);
}

/* ---- completion: log line, metrics, cleanup ------------------------------------------ */


static void on_completed(void *cls, struct MHD_Connection *conn, void **con_cls,
                         enum MHD_RequestTerminationCode toe)
{
    (void)conn;
    ismd_server *s = cls;
    ismd_req *r = *con_cls;
    if (!r)
        return;
    *con_cls = NULL;
    if (r->waiter.flight) { /* never expected: a completed request is not suspended */
        ismd_sched_lock(&s->sched);
        ismd_sched_detach(&s->sched, &r->waiter);
        ismd_sched_unlock(&s->sched);
    }
    ismd_conns_request_done(s->conns, r->cn);
    ismd_request_record(r, toe == MHD_REQUEST_TERMINATED_COMPLETED_OK,
                        ismd_conns_cut_reason(s->conns, r->cn));
    ism_blob_unref(r->r_body);
    ism_blob_unref(r->r_stats);
    ism_blob_unref(r->r_features);
    drop_body(r);
    free(r);
    atomic_fetch_sub(&s->open_requests, 1);
}

/* ---- URL unescaping: %XX, but an encoded NUL, '/' or '\' becomes a byte no route or path
 * check accepts (0x01), so such URLs always end in 404. ----------------------------------- */

static int hexval(char c)
{
    if (c >= '0' && c <= '9')
        return c - '0';
    c = (char)tolower((unsigned char)c);
    return c >= 'a' && c <= 'f' ? c - 'a' + 10 : -1;
}

static size_t unescape(void *cls, struct MHD_Connection *c, char *s)
{
    (void)cls;
    (void)c;
    char *w = s;
    for (const char *p = s; *p; p++) {
        int hi, lo;
        if (*p == '%' && (hi = hexval(p[1])) >= 0 && (lo = hexval(p[2])) >= 0) {
            int v = hi * 16 + lo;
            *w++ = (v == 0 || v == '/' || v == '\\') ? 1 : (char)v;
            p += 2;
        } else if (*p == '%') {
            *w++ = 1; /* a stray '%' */
        } else {
            *w++ = *p;
        }
    }
    *w = 0;
    return (size_t)(w - s);
}

static void mhd_log(void *cls, const char *fmt, va_list ap)
{
    (void)cls;
    char msg[512];
    vsnprintf(msg, sizeof msg, fmt, ap);
    size_t n = strlen(msg);
    while (n && (msg[n - 1] == '\n' || msg[n - 1] == ' '))
        msg[--n] = 0;
    ism_logf(ISM_LOG_WARN, "http_library", "%s", msg);
}

/* Unsent bytes one connection may leave queued in the kernel: a send stops there, and the
 * socket polls writable again only below it. Without a bound, autotuning lets every slow
 * reader's socket take up to tcp_wmem's maximum (4 MB here) per send: 450 slow readers of a
 * 7 MB mesh parked ~1.8 GB in the kernel (past the host's TCP memory-pressure mark) and the
 * polling thread spent seconds copying it (/healthz waited 5-11 s). Bytes in flight (the
 * congestion window) are not limited by this, so fast clients on long links keep their
 * speed. Nor does it cost throughput: without it (the kernel's default, no bound) a cached
 * 331 KB mesh at 256 connections cost the same, server and wrk CPU together 277 against 285
 * us per request by sendfile, 276 against 278 from memory (task-clock, medians of 3, bbr,
 * load 18-20). */
#define NOTSENT_LOWAT (256u << 10)
/* The own sender's unsent queue for a reader that keeps up (http_front.c adapt_unsent): twice
 * its wake-up's share (WAKE_BYTES, 2 MB), so that a sendfile is never cut short by the queue
 * before the share; the kernel's own bound on a socket's send buffer is tcp_wmem's 4 MB. */
#define OWN_UNSENT_MAX (4u << 20)
/* Connections libmicrohttpd may hold beyond --max-connections: those the connection table
 * closed and libmicrohttpd has not freed yet (an evicted connection waiting for a computation
 * lingers until its flight ends). Without room for them, libmicrohttpd's own limit (which
 * stops accepting: new clients wait unanswered in the backlog) could bite before the fair
 * one. */
#define CUT_ROOM(max) ((max) / 16u + 16u)
/* libmicrohttpd's memory per connection (its default: 32 KB): the request line and headers as
 * read, their parsed table, the answer's header block. It zeroes all of it after every
 * request: at 32 KB that memset was 7.9% of the daemon's CPU per cached mesh (perf, wrk 64
 * connections). Requests whose line and headers do not fit are answered 414 / 431, as
 * before, only sooner. */
#define CONNECTION_MEMORY (16u << 10)
/* With --own-sender, a connection that has waited this long for its next request goes to
 * libmicrohttpd (its entry in the connection table, conns.h, which counts it from its accept,
 * goes along: own_conns.h). A client that asks again within it (a script, a benchmark, a
 * viewer fetching meshes) stays with the own sender. */
#define OWN_SENDER_IDLE_S 0.5
/* Kernel queue of connections not yet accepted (a burst of new clients waits here). */
#define LISTEN_BACKLOG 1024u

/* libmicrohttpd reports a connection's start and end: its entry in the connection table,
 * which decides its admission (conns.h). */
static void on_connection(void *cls, struct MHD_Connection *conn, void **socket_context,
                          enum MHD_ConnectionNotificationCode code)
{
    ismd_server *s = cls;
    if (code == MHD_CONNECTION_NOTIFY_CLOSED) {
        ismd_conns_closed(s->conns, *socket_context);
        *socket_context = NULL;
        return;
    }
    ismd_conn *own = ismd_own_adopt(); /* handed over by the own sender: already counted */
    if (own) {
        *socket_context = own;
        return;
    }
    const union MHD_ConnectionInfo *ci = MHD_get_connection_info(conn, MHD_CONNECTION_INFO_CONNECTION_FD);
    char addr[64];
    ismd_peer_address(conn, addr, sizeof addr);
    *socket_context = ci ? ismd_conns_opened(s->conns, ci->connect_fd, addr) : NULL;
}

/* The connection table found that the client of r closed its connection (table lock held).
 * A request waiting for a flight leaves it — the computation stops when nobody else waits
 * for it (single flight: another request or a job keeps it) — and is resumed, to be closed
 * without an answer. */
static void client_left(void *ctx, void *req)
{
    ismd_server *s = ctx;
    ismd_req *r = req;
    ismd_sched_lock(&s->sched);
    if (r->suspended && r->waiter.flight) {
        ismd_sched_detach(&s->sched, &r->waiter);
        r->client_left = true;
        r->suspended = false;
        atomic_fetch_sub(&s->metrics.suspended_connections, 1);
        atomic_fetch_add(&s->metrics.clients_left, 1);
        ism_http_resume(s->loops, r->conn);
    }
    ismd_sched_unlock(&s->sched);
}

/* Descriptors a connection may hold at once: its socket and the cache file its answer is
 * sent from (respond.c: large bodies, or any mesh while many connections are open). */
#define FDS_PER_CONNECTION 2u
/* Descriptors beside the connections': workers' pipes, cache files being written or kept open
 * for sending (server/common/fd_keep.c, 64), logs. */
#define FDS_BESIDE 256u

/* Grows the process's descriptor table now to hold n descriptors (at most RLIMIT_NOFILE).
 * The kernel grows it on demand, doubling, and in a multi-threaded process each growth waits
 * for an RCU grace period (expand_fdtable -> synchronize_rcu) while every thread that opens
 * or accepts a descriptor waits for it: measured, 450 slow readers arriving together (a
 * socket and a cache file each) held both polling threads in D state (expand_files,
 * synchronize_rcu) and /healthz waited 0.2-1.5 s at load ~20. The table never shrinks, so
 * growing it once at the start (a few hundred KB) takes that wait out of serving. */
static void reserve_descriptors(int any_fd, unsigned n)
{
    struct rlimit rl;
    if (getrlimit(RLIMIT_NOFILE, &rl) == 0 && rl.rlim_cur != RLIM_INFINITY && n > rl.rlim_cur)
        n = (unsigned)rl.rlim_cur;
    if (n < 2)
        return;
    int fd = fcntl(any_fd, F_DUPFD_CLOEXEC, (int)n - 1); /* the table covers fd, so n slots */
    if (fd >= 0)
        close(fd);
}

/* Polling threads per core. One per core served a cached mesh with the fewest wake-ups (0.2
 * context switches per request at 16-256 connections), but on a loaded machine (load ~20 on
 * 2 cores) a new client arriving behind 450 slow readers waited 50-300 ms for one of the two
 * threads (/healthz p99, test_http_concurrency); two per core: 50-125 ms, and 0.3-0.4
 * switches per request; four per core: 10-55 ms, but 1.1 switches per request at 256
 * connections. */
#define THREADS_PER_CORE 2u
/* With the own sender (--own-sender): one per core, as nginx's workers. Its threads do not
 * copy (sendfile) and give a connection at most WAKE_BYTES per wake-up (http_front.c), and new
 * connections are spread evenly over them, so each wakes for more requests. Measured, cached
 * 331 KB mesh, wrk -t2 at 16 / 64 / 256 connections, medians of 3 rounds at load 17-27,
 * voluntary context switches per request: 2 threads 0.29 / 0.17 / 0.12, 4 threads 0.62 / 0.40
 * / 0.28 (the front before the even spread, 4 threads of which 2-3 got connections: 0.30 /
 * 0.22 / 0.34), nginx's 2 workers 0.31 / 0.16 / 0.07; CPU per request the same within noise.
 * The price: /healthz beside 450 slow readers of the 7 MB OBJ at load 17 has a p99 of 16-26 ms
 * against 10-12 with 4 threads (bench_http's slow-reader rows). */
#define OWN_THREADS_PER_CORE 1u

/* Whether the own sender runs (--own-sender, on by default). Not behind a --trusted-proxy
 * nor with --private: its hook (own_sender.c) is never started there, as it would have to
 * leave every request to libmicrohttpd (X-Real-IP names the client; a token is needed), and a
 * front would only add a peek and a hand-over to each connection and halve the polling
 * threads. */
static bool own_sender_runs(const ismd_config *cfg)
{
    return cfg->own_sender && !cfg->trusted_proxy[0] && !cfg->private_mode;
}

/* The thread model (http_loops.c): THREADS_PER_CORE polling threads per core, each with its
 * own libmicrohttpd daemon and epoll set on the shared listening socket (--http-threads may
 * ask for more). Why epoll: poll() walks every connection of its thread on each pass
 * (measured, 256 connections: 124 us of CPU per 307 KB answer with 2 poll threads against
 * 112 us with epoll, nginx 82 us). Why so few threads: each extra thread wakes for fewer
 * connections (the 35 threads the 4,000-connection limit needed before http_loops.c: 1.1-5.4
 * context switches per request at 256 connections, nginx 0.02-0.4), and a connection in a
 * long copy holds up its thread only until NOTSENT_LOWAT is queued. */
static unsigned http_threads(const ismd_config *cfg)
{
    long cores = sysconf(_SC_NPROCESSORS_ONLN);
    unsigned n = (own_sender_runs(cfg) ? OWN_THREADS_PER_CORE : THREADS_PER_CORE) *
                 (cores > 0 ? (unsigned)cores : 1u);
    return (unsigned)cfg->http_threads > n ? (unsigned)cfg->http_threads : n;
}

/* --tcp-congestion: set on the listening socket, which every accepted socket inherits it from.
 * Why offer it: with the system's bbr and no fq qdisc (Debian's default qdisc is
 * pfifo_fast; loopback has none), TCP paces every socket itself with a high-resolution timer
 * per send burst. Measured on this project's VM (kernel 6.18, bbr, cached 331 KB mesh, wrk
 * at 256 connections, load 16-21, five runs of each, medians of 2-3 rounds, CPU us per
 * request from task-clock): the daemon 84-98 with bbr against 62-82 with cubic or reno,
 * wrk's side 114-176 against 93-123, both together 203-277 against 158-205 (nginx 146-169);
 * the timer's softirq and lock work (perf: _raw_spin_unlock_irqrestore under tcp_write_xmit,
 * 24 us per request on wrk's side) goes away. nginx on the same host with bbr barely pays
 * it (1-3 us). The cause (strace, then a throwaway epoll server sending the same bytes each
 * way, wrk at 256 connections, bbr, medians of 3, server + wrk CPU us per request, load
 * 17-19): libmicrohttpd 0.9.75 sends a file answer's 364-byte header block on its own and
 * pushes it (sendto, then TCP_CORK off and on) before the 128 KB sendfile calls. That alone
 * costs 234 against 132 with the headers held back (MSG_MORE); libmicrohttpd's whole sequence
 * 267-314, nginx 139-189. Only a sender of our own could keep the headers back (see
 * respond.c: 0.9.75 writes them itself). Not the default: towards far clients over lossy
 * links bbr is the better choice. */
static bool set_congestion(int listen_fd, const char *name)
{
    if (!name[0])
        return true;
    if (setsockopt(listen_fd, IPPROTO_TCP, TCP_CONGESTION, name, (socklen_t)strlen(name)) == 0)
        return true;
    ism_logf(ISM_LOG_ERROR, "http_start_failed",
             "--tcp-congestion %s: %s (the kernel's choice is in "
             "/proc/sys/net/ipv4/tcp_allowed_congestion_control)",
             name, strerror(errno));
    return false;
}

bool ismd_http_start(ismd_server *s, int listen_fd)
{
    s->listen_fd = listen_fd;
    if (!set_congestion(listen_fd, s->cfg->tcp_congestion))
        return false;
    unsigned lowat = NOTSENT_LOWAT; /* inherited by every accepted socket */
    if (setsockopt(listen_fd, IPPROTO_TCP, TCP_NOTSENT_LOWAT, &lowat, sizeof lowat) != 0)
        ism_logf(ISM_LOG_WARN, "socket_option", "TCP_NOTSENT_LOWAT: %s", strerror(errno));
    ismd_conns_config cc = {
        .max = s->cfg->max_conns,
        .per_address = (unsigned)s->cfg->client_conns,
        .trusted = s->cfg->trusted_proxy,
        .header_s = s->cfg->header_timeout_s,
        .body_s = s->cfg->body_timeout_s,
        .client_left = client_left,
        .ctx = s,
    };
    s->conns = ismd_conns_start(&cc, &s->metrics);
    if (!s->conns)
        return false;
    unsigned limit = s->cfg->max_conns + CUT_ROOM(s->cfg->max_conns) +
                     ismd_conns_refused_room(s->cfg->max_conns);
    /* the own sender holds at most max_conns more (each thread its share), idle ones for
     * OWN_SENDER_IDLE_S before libmicrohttpd's table sees them */
    unsigned threads = http_threads(s->cfg);
    unsigned own = own_sender_runs(s->cfg) ? s->cfg->max_conns : 0;
    reserve_descriptors(listen_fd, FDS_PER_CONNECTION * (limit + own) + FDS_BESIDE);
    struct MHD_OptionItem opts[] = {
        {MHD_OPTION_EXTERNAL_LOGGER, (intptr_t)mhd_log, s},
        {MHD_OPTION_NOTIFY_COMPLETED, (intptr_t)on_completed, s},
        {MHD_OPTION_UNESCAPE_CALLBACK, (intptr_t)unescape, s},
        {MHD_OPTION_CONNECTION_TIMEOUT, s->cfg->conn_timeout_s, NULL},
        {MHD_OPTION_NOTIFY_CONNECTION, (intptr_t)on_connection, s},
        {MHD_OPTION_LISTEN_BACKLOG_SIZE, LISTEN_BACKLOG, NULL},
        {MHD_OPTION_CONNECTION_MEMORY_LIMIT, CONNECTION_MEMORY, NULL},
        {MHD_OPTION_SIGPIPE_HANDLED_BY_APP, 1, NULL},
        {MHD_OPTION_END, 0, NULL},
    };
    /* s->loops is set before any thread runs: resumes (other threads) read it. */
    s->loops = ism_http_loops_new(threads);
    ism_front_hooks front = {
        .answer = ismd_own_answer,
        .done = ismd_own_done,
        .opened = ismd_own_opened,
        .busy = ismd_own_busy,
        .closed = ismd_own_closed,
        .handing = ismd_own_handing,
        .cls = s,
        .max_conns = own / threads + 1,
        .idle_s = OWN_SENDER_IDLE_S,
        .stall_s = s->cfg->conn_timeout_s,
        .unsent_min = NOTSENT_LOWAT,
        .unsent_max = OWN_UNSENT_MAX,
    };
    if (!s->loops || !ism_http_loops_start(s->loops, MHD_ALLOW_SUSPEND_RESUME | MHD_USE_ERROR_LOG,
                                           listen_fd, limit, on_request, s, opts,
                                           own ? &front : NULL)) {
        ism_logf(ISM_LOG_ERROR, "http_start_failed", "libmicrohttpd did not start");
        ism_http_loops_stop(s->loops);
        s->loops = NULL;
        ismd_conns_stop(s->conns);
        s->conns = NULL;
        return false;
    }
    return true;
}

void ismd_http_quiesce(ismd_server *s)
{
    if (!s->loops)
        return;
    ism_http_loops_quiesce(s->loops);
    if (s->listen_fd >= 0)
        shutdown(s->listen_fd, SHUT_RDWR); /* refuse new connections now; closed after the stop */
}

void ismd_http_stop(ismd_server *s, double max_s)
{
    if (!s->loops)
        return;
    long long until = ism_now_ns() + (long long)(max_s * 1e9);
    while (atomic_load(&s->open_requests) > 0 && ism_now_ns() < until)
        usleep(10000);
    ism_http_loops_stop(s->loops);
    s->loops = NULL;
    ismd_conns_stop(s->conns);
    s->conns = NULL;
    if (s->listen_fd >= 0)
        close(s->listen_fd);
    s->listen_fd = -1;
}
