/* own_sender.c — the cached mesh GETs that isomeshd's own sender answers (own_sender.h,
 * http_front.h, --own-sender): which requests it takes, the header block it writes for them
 * (the headers libmicrohttpd would send for the same answer, from the same functions:
 * routes_mesh.c ismd_mesh_headers, respond.c ismd_common_headers), and their log line and
 * metrics (request_log.h). It takes a request only when nothing in it could
 * change the answer: GET of /v1/meshes/{key}.{fmt} over HTTP/1.1, no query or escapes, only
 * the headers below, and the mesh cached (its bytes in memory, or on disk); where
 * a token could be needed or a trusted proxy names the client, http.c (own_sender_runs) does
 * not start it. Everything else — HEAD, If-None-Match, Range, a body, a mesh to compute — is
 * libmicrohttpd's, as before.
 *
 * The body goes from the cache file (sendfile) when the disk tier finds it sound, else from
 * the mesh's bytes in memory: a connection handed to libmicrohttpd stays there for good, so
 * declining a cached mesh whose file is merely not ready (written after the answer, checked
 * only once settled: cache_disk.h) gave libmicrohttpd every connection a client opened in
 * the moment after a computation (a burst of 16 right after the POST: all of them, for
 * their whole life, split unevenly over its loops, 0.5x the req/s: notes/http18.md). */
#include "server/isomeshd/own_sender.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include <time.h>
#include <unistd.h>

#include "core/util/clock.h"
#include "proto/request.h"
#include "server/common/cache_disk.h"
#include "server/isomeshd/conns.h"
#include "server/isomeshd/request_log.h"
#include "server/isomeshd/respond.h"
#include "server/isomeshd/routes.h"

#define PREFIX "GET /v1/meshes/"
#define PREFIX_LEN (sizeof PREFIX - 1)
#define VERSION " HTTP/1.1\r\n"
#define VERSION_LEN (sizeof VERSION - 1)

/* A request header that cannot change a cached mesh's answer (any other — If-None-Match,
 * Range, Authorization, X-Forwarded-For, Content-Length, Expect, ... — leaves the request to
 * libmicrohttpd); Connection only as keep-alive. */
static bool harmless(const char *name, size_t n, const char *value, size_t vn)
{
    static const char *const names[] = {"host",          "user-agent",      "accept",
                                        "accept-encoding", "accept-language", "cache-control",
                                        "pragma",        "referer",         "origin"};
    if (n == 10 && !strncasecmp(name, "connection", 10))
        return vn == 10 && !strncasecmp(value, "keep-alive", 10);
    for (size_t i = 0; i < sizeof names / sizeof names[0]; i++)
        if (strlen(names[i]) == n && !strncasecmp(name, names[i], n))
            return true;
    return false;
}

/* The header lines of head (after its request line) are all harmless, one of them Host. */
static bool headers_harmless(const char *p, const char *end)
{
    int hosts = 0;
    while (p < end) {
        const char *eol = memchr(p, '\r', (size_t)(end - p));
        if (!eol || eol + 1 >= end || eol[1] != '\n')
            return false;
        if (eol == p)
            return hosts == 1; /* the empty line */
        const char *colon = memchr(p, ':', (size_t)(eol - p));
        if (!colon || colon == p || *p == ' ' || *p == '\t')
            return false; /* malformed, or a folded line */
        const char *v = colon + 1, *ve = eol;
        while (v < ve && (*v == ' ' || *v == '\t'))
            v++;
        while (ve > v && (ve[-1] == ' ' || ve[-1] == '\t'))
            ve--;
        if (!harmless(p, (size_t)(colon - p), v, (size_t)(ve - v)))
            return false;
        hosts += (colon - p == 4 && !strncasecmp(p, "host", 4));
        p = eol + 2;
    }
    return false;
}

typedef struct block {
    char *buf;
    size_t len, cap;
    bool full;
} block;

static void put(block *b, const char *s, size_t n)
{
    if (b->len + n > b->cap) {
        b->full = true;
        return;
    }
    memcpy(b->buf + b->len, s, n);
    b->len += n;
}

static void add_line(void *ctx, const char *name, const char *value)
{
    block *b = ctx;
    put(b, name, strlen(name));
    put(b, ": ", 2);
    put(b, value, strlen(value));
    put(b, "\r\n", 2);
}

/* "Date: Fri, 27 Nov 2026 05:42:40 GMT\r\n" as libmicrohttpd writes it (RFC 9110's IMF-fixdate,
 * whatever the locale). It changes once a second: each polling thread formats it then, not on
 * every answer (the cached-hit path has no snprintf, as routes_mesh.c's timing_of). */
static void date_line(block *b)
{
    static const char days[7][4] = {"Sun", "Mon", "Tue", "Wed", "Thu", "Fri", "Sat"};
    static const char months[12][4] = {"Jan", "Feb", "Mar", "Apr", "May", "Jun",
                                       "Jul", "Aug", "Sep", "Oct", "Nov", "Dec"};
    static _Thread_local time_t last = (time_t)-1;
    static _Thread_local char line[64];
    static _Thread_local int n;
    time_t now = time(NULL);
    if (now != last) {
        struct tm tm;
        gmtime_r(&now, &tm);
        n = snprintf(line, sizeof line, "Date: %s, %02d %s %04d %02d:%02d:%02d GMT\r\n",
                     days[tm.tm_wday], tm.tm_mday, months[tm.tm_mon], tm.tm_year + 1900,
                     tm.tm_hour, tm.tm_min, tm.tm_sec);
        last = now;
    }
    put(b, line, (size_t)n);
}

/* The body's descriptor goes back: lent by the disk tier's kept files (no syscall; the file
 * stays open while any answer still sends from it, even once evicted), or closed; a body
 * from memory lets its blob go. */
static void release_body(ismd_req *r, int fd)
{
    if (r->lease)
        ism_fd_keep_give_back(r->lease);
    else if (fd >= 0)
        close(fd);
    r->lease = NULL;
    ism_blob_unref(r->r_body);
    r->r_body = NULL;
}

bool ismd_own_answer(void *cls, const char *head, size_t len, void *conn, ism_front_answer *a)
{
    ismd_server *s = cls;
    const char *end = head + len;
    if (len < PREFIX_LEN || memcmp(head, PREFIX, PREFIX_LEN) != 0 || !s->disk)
        return false;
    const char *key = head + PREFIX_LEN;
    const char *sp = memchr(key, ' ', (size_t)(end - key));
    if (!sp || sp - key < ISM_KEY_HEX_LEN + 2 || key[ISM_KEY_HEX_LEN] != '.' ||
        (size_t)(end - sp) < VERSION_LEN || memcmp(sp, VERSION, VERSION_LEN) != 0)
        return false;
    char fmt[8];
    size_t fmt_len = (size_t)(sp - key) - ISM_KEY_HEX_LEN - 1;
    if (fmt_len >= sizeof fmt)
        return false;
    memcpy(fmt, key + ISM_KEY_HEX_LEN + 1, fmt_len);
    fmt[fmt_len] = 0;
    if (ism_format_lookup(fmt) < 0 || !headers_harmless(sp + VERSION_LEN, end))
        return false;
    ismd_req *r = calloc(1, sizeof *r);
    if (!r)
        return false;
    r->srv = s;
    r->t0_ns = ism_now_ns();
    memcpy(r->key, key, ISM_KEY_HEX_LEN);
    r->key[ISM_KEY_HEX_LEN] = 0;
    memcpy(r->fmt, fmt, fmt_len + 1);
    char name[ISM_CACHE_NAME_MAX];
    long long offset = 0;
    int fd = -1;
    if (ism_key_valid(r->key) && ism_cache_name(name, r->key, r->fmt) &&
        (r->r_body = ism_cache_get(&s->cache, name, NULL)))
        fd = ism_cache_disk_borrow_payload(s->disk, name, r->r_body->data, r->r_body->len,
                                           &offset, &r->lease);
    if (!r->r_body) { /* not cached: libmicrohttpd's (it counts the lookup) */
        free(r);
        return false;
    }
    atomic_fetch_add(&s->metrics.mesh_hits, 1);
    atomic_fetch_add(fd >= 0 ? &s->metrics.sendfile_responses : &s->metrics.own_memory_responses,
                     1);
    r->route = ISMD_R_MESH_FILE;
    r->cache = "hit";
    r->bytes = r->r_body->len;
    snprintf(r->method, sizeof r->method, "GET");
    snprintf(r->path, sizeof r->path, "%.*s", (int)(sp - key + 11), key - 11);
    const char *peer = ismd_conns_peer(conn); /* formatted once, at accept (own_conns.c) */
    snprintf(r->client, sizeof r->client, "%s", peer ? peer : "-");
    block b = {a->head, 0, sizeof a->head, false};
    put(&b, "HTTP/1.1 200 OK\r\n", 17);
    date_line(&b);
    ismd_mesh_headers(r, add_line, &b);
    ismd_common_headers(s->cfg, add_line, &b);
    char length[32];
    snprintf(length, sizeof length, "%zu", r->r_body->len);
    add_line(&b, "Content-Length", length);
    put(&b, "\r\n", 2);
    if (b.full) { /* a CORS origin of hundreds of bytes: libmicrohttpd's */
        release_body(r, fd);
        free(r);
        return false;
    }
    a->head_len = b.len;
    a->fd = fd;
    a->offset = offset;
    a->len = r->r_body->len;
    if (fd < 0) { /* from memory: the blob is held until done (as libmicrohttpd holds it) */
        a->mem = r->r_body->data;
    } else { /* from the file: holding the blob until done would keep an evicted mesh in
              * memory, outside the cache's budget, for as long as the reader stalls */
        ism_blob_unref(r->r_body);
        r->r_body = NULL;
    }
    a->ctx = r;
    ismd_request_answered(r, 200);
    /* open until done, as libmicrohttpd's requests: a stop lets the answers under way finish
     * (ismd_http_stop waits for them, bounded) */
    atomic_fetch_add(&s->open_requests, 1);
    return true;
}

void ismd_own_done(void *cls, ism_front_answer *a, bool sent)
{
    (void)cls;
    ismd_req *r = a->ctx;
    release_body(r, a->fd);
    ismd_request_record(r, sent, NULL);
    atomic_fetch_sub(&r->srv->open_requests, 1);
    free(r);
}
