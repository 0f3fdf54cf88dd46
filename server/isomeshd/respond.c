/* respond.c — the response helpers of respond.h: responses sharing a blob's bytes, the
 * common headers (CORS, nosniff, Retry-After, Allow, WWW-Authenticate, no-store on errors),
 * the JSON error bodies, and the status recorded for the log and the metrics. */
#include "server/isomeshd/respond.h"

#include <stdio.h>
#include <string.h>
#include <unistd.h>

#include "server/common/cache_disk.h"

#include "server/isomeshd/errors.h"
#include "server/isomeshd/request_log.h"

static void free_blob_cb(void *cls)
{
    ism_blob_unref(cls);
}

struct MHD_Response *ismd_response_blob(ism_blob *b, const char *content_type)
{
    struct MHD_Response *resp = MHD_create_response_from_buffer_with_free_callback_cls(
        b->len, b->data, free_blob_cb, ism_blob_ref(b));
    if (!resp) {
        ism_blob_unref(b);
        return NULL;
    }
    if (content_type)
        MHD_add_response_header(resp, MHD_HTTP_HEADER_CONTENT_TYPE, content_type);
    return resp;
}

/* Bodies at least this large are sent from their disk cache file when it is there. Measured
 * (wrk, 16 connections, loopback, load ~28, CPU of the daemon per request): a 5.2 MB STL
 * 1.24-1.42 ms by sendfile vs 1.73-2.01 ms from memory, a 7 MB OBJ 1.90-1.97 vs 2.77-3.07;
 * a 330 KB Draco mesh no better (100-151 us vs 96-135 us, and fewer req/s): the file's
 * open, fstat, header read and close, and libmicrohttpd writing the headers apart from the
 * body, cost what the copy saved. Nor does keeping the file open (a descriptor per cached
 * body, dup'ed per response): the same 330 KB mesh, wrk 16 connections, 6 alternating runs
 * at a load of ~28, daemon CPU per request medians: from memory 80 us (74-98), sendfile with
 * the file opened per request 120 (106-152), from a kept descriptor 97 (90-105). The copy
 * into the socket (_copy_from_iter, 30% of the daemon's CPU in perf) is gone, but the
 * kernel's sendfile path (a pipe of page-cache pages, per page confirm and release) costs
 * more than the copy at this size on loopback. Nor at 256 connections, where the copy costs
 * most (perf record -g: _copy_from_iter 34 us per request at 16 connections, 48 at 256, into
 * socket pages no longer in cache; libmicrohttpd alone from memory grows 97 -> 145 us, nginx
 * by sendfile 77 -> 96): by sendfile, task-clock 160-170 us per request against 136-140 from
 * memory (load ~30): counted (perf stat, syscall tracepoints) libmicrohttpd 0.9.75 answers a
 * request from a file in 12 system calls (recv, the headers apart, three sendfile calls of
 * 128 KB, three TCP_CORK/NODELAY setsockopt, open, fstat, pread, close), from memory in 2
 * (recv, one sendmsg of headers and body). */
#define SENDFILE_MIN ((size_t)1 << 20)
/* Smaller bodies go from memory at any number of connections. libmicrohttpd 0.9.75 sends a
 * body it must read (from a file, a callback or an iovec) after pushing its header block
 * alone: connection.c 3943-3976 calls MHD_send_hdr_and_body_ without the body and with
 * complete_response false, so push_hdr is set (mhd_send.c 949-955) and the 364-byte block
 * leaves as a segment of its own before the first sendfile; a body in memory goes out in the
 * same sendmsg as the header block (mhd_send.c 1047-1062). Under the system's bbr without the
 * fq qdisc (http.c set_congestion) that lone segment costs the reader a wake-up, and both
 * sides pacing work and tail loss probes. Until 2026-11-27 bodies from 64 KB went from their
 * file once 128 connections were open (to keep the copy out of cold socket pages). Measured
 * against memory (cached 331 KB mesh, 256 connections, wrk -t2 5 s, bbr, medians of 4
 * alternated rounds beside nginx, load 11-15; counters from /proc/net/snmp and netstat per
 * request, both ends of loopback; CPU from task-clock): segments 14.9 -> 11.4 (nginx 10.3),
 * tail loss probes 0.89 -> 0.41 (0.26), wrk's CPU us 153 -> 104 (85), the daemon's 77 -> 83
 * (48: the copy), both 230 -> 187 (133). Kernel memory per slow reader stays bounded by
 * NOTSENT_LOWAT (http.c).
 *
 * Why not an own sender (the header block held back with MSG_MORE, then one sendfile, as nginx
 * does): libmicrohttpd 0.9.75 always writes the header block and the body of an answer
 * itself. Its header block always carries its own Content-Length of the response's size
 * (connection.c build_header_response, 2163-2176), which an application's header only
 * doubles (response.c 544, MHD_RF_INSANITY_HEADER_CONTENT_LENGTH); it leaves the body out
 * only for HEAD, 304, 204 and 1xx (is_reply_body_needed, 1731-1752; MHD_RF_HEAD_ONLY_RESPONSE
 * came in 1.0.0). Taking the socket over is the upgrade path, which requires a 101 answer
 * (MHD_queue_response, 5145) and ends the connection for libmicrohttpd (no keep-alive after
 * it). Suspending and writing the answer ourselves leaves libmicrohttpd an answer of its own
 * to write when resumed. Nor does a newer libmicrohttpd change it: 1.0.1 and its master of
 * 2025-04 push a file answer's header block alone the same way (connection.c 6695-6709,
 * mhd_send.c 961-962). Nor does corking the socket around its file answer help: once a
 * body of more than one 128 KB sendfile chunk (MHD_SENFILE_CHUNK_, mhd_send.c 69) has been
 * sent, libmicrohttpd takes the socket for corked and pushes each later header block by
 * setting TCP_NODELAY (post_send_setopt), which sends it whatever the cork. What an own sender
 * would give (a throwaway epoll server answering the same 331 KB file, 4 threads, wrk -t2 5 s,
 * bbr, medians of 3, load 25-27, server + wrk CPU us per request): the header block held back
 * with MSG_MORE, then sendfile: 64 connections p99 83 ms (nginx 79), req/s 2.0x nginx's,
 * 117 us (96); 256: p99 234 (292), 1.45x, 130 (117); the same server pushing the block
 * alone first: 64: p99 118, 193 us; 256: p99 383, 227 us. */

struct MHD_Response *ismd_response_cached(ismd_server *s, const char *name, ism_blob *b,
                                          const char *content_type)
{
    long long offset = 0;
    bool from_file = b->len >= SENDFILE_MIN;
    int fd = from_file && s->disk
                 ? ism_cache_disk_open_payload(s->disk, name, b->data, b->len, &offset)
                 : -1;
    if (fd < 0)
        return ismd_response_blob(b, content_type);
    struct MHD_Response *resp =
        MHD_create_response_from_fd_at_offset64(b->len, fd, (uint64_t)offset);
    if (!resp) {
        close(fd);
        return NULL;
    }
    atomic_fetch_add(&s->metrics.sendfile_responses, 1);
    if (content_type)
        MHD_add_response_header(resp, MHD_HTTP_HEADER_CONTENT_TYPE, content_type);
    return resp;
}

struct MHD_Response *ismd_response_text(const char *text, const char *content_type)
{
    ism_blob *b = ism_blob_from_str(text);
    if (!b)
        return NULL;
    struct MHD_Response *resp = ismd_response_blob(b, content_type);
    ism_blob_unref(b);
    return resp;
}

void ismd_add_to_response(void *ctx, const char *name, const char *value)
{
    MHD_add_response_header(ctx, name, value);
}

void ismd_common_headers(const ismd_config *cfg, ismd_add_header add, void *ctx)
{
    if (cfg->cors_origin[0]) {
        add(ctx, MHD_HTTP_HEADER_ACCESS_CONTROL_ALLOW_ORIGIN, cfg->cors_origin);
        add(ctx, "Access-Control-Expose-Headers",
            "ETag, Location, X-Cache, Server-Timing, Retry-After, WWW-Authenticate");
        if (strcmp(cfg->cors_origin, "*") != 0)
            add(ctx, MHD_HTTP_HEADER_VARY, "Origin");
    }
    add(ctx, "X-Content-Type-Options", "nosniff");
}

enum MHD_Result ismd_send(ismd_req *r, unsigned status, struct MHD_Response *resp)
{
    if (!resp)
        return MHD_NO;
    ismd_common_headers(r->srv->cfg, ismd_add_to_response, resp);
    ismd_request_answered(r, status);
    enum MHD_Result ok = MHD_queue_response(r->conn, status, resp);
    MHD_destroy_response(resp);
    return ok;
}

static enum MHD_Result respond_blob_sized(ismd_req *r, unsigned status, ism_blob *b,
                                          const char *ctype)
{
    struct MHD_Response *resp = ismd_response_blob(b, ctype);
    r->bytes = b->len;
    if (resp && (status == 503 || status == 429))
        MHD_add_response_header(resp, MHD_HTTP_HEADER_RETRY_AFTER, "5");
    if (resp && status == 405 && r->allow)
        MHD_add_response_header(resp, MHD_HTTP_HEADER_ALLOW, r->allow);
    if (resp && status == 401)
        MHD_add_response_header(resp, MHD_HTTP_HEADER_WWW_AUTHENTICATE,
                                ismd_auth_challenge(&r->who));
    if (resp && status >= 400)
        MHD_add_response_header(resp, MHD_HTTP_HEADER_CACHE_CONTROL, "no-store");
    if (resp && r->close_after)
        MHD_add_response_header(resp, MHD_HTTP_HEADER_CONNECTION, "close");
    return ismd_send(r, status, resp);
}

enum MHD_Result ismd_respond_error_blob(ismd_req *r, unsigned status, ism_blob *json)
{
    return respond_blob_sized(r, status, json, "application/json");
}

enum MHD_Result ismd_respond_error(ismd_req *r, unsigned status, const char *code,
                                   const char *message)
{
    ism_blob *b = ismd_error_json(code, message, NULL);
    if (!b)
        return MHD_NO;
    enum MHD_Result ok = ismd_respond_error_blob(r, status, b);
    ism_blob_unref(b);
    return ok;
}

enum MHD_Result ismd_respond_json(ismd_req *r, unsigned status, const char *json)
{
    ism_blob *b = ism_blob_from_str(json);
    if (!b)
        return MHD_NO;
    enum MHD_Result ok = respond_blob_sized(r, status, b, "application/json");
    ism_blob_unref(b);
    return ok;
}

const char *ismd_unauthorized(ismd_req *r, const char **message)
{
    atomic_fetch_add(&r->srv->metrics.rejected_unauthorized, 1);
    if (r->who.state == ISMD_AUTH_INVALID) {
        *message = "this bearer token is not valid here (mistyped, or revoked)";
        return "invalid_token";
    }
    *message = "this server needs a bearer token: send `Authorization: Bearer TOKEN` "
               "(its administrator makes one with `isomeshd token add NAME`)";
    return "unauthorized";
}

enum MHD_Result ismd_respond_unauthorized(ismd_req *r)
{
    const char *message;
    const char *code = ismd_unauthorized(r, &message);
    return ismd_respond_error(r, 401, code, message);
}

enum MHD_Result ismd_respond_refused(ismd_req *r, ismd_submit st)
{
    switch (st) {
    case ISMD_SUBMIT_QUEUE_FULL:
        return ismd_respond_error(r, 503, "queue_full",
                                  "every worker is busy and the queue is full; retry later");
    case ISMD_SUBMIT_CLIENT_LIMIT:
        return ismd_respond_error(r, 429, "too_many_requests",
                                  "too many computations of yours are queued or running "
                                  "(--user-jobs); wait for one to finish");
    case ISMD_SUBMIT_DRAINING:
        return ismd_respond_error(r, 503, "shutting_down", "the server is shutting down");
    default:
        return ismd_respond_error(r, 500, "out_of_memory", "the server ran out of memory");
    }
}


enum MHD_Result ismd_respond_preflight(ismd_req *r)
{
    struct MHD_Response *resp = MHD_create_response_from_buffer(0, "", MHD_RESPMEM_PERSISTENT);
    if (!resp)
        return MHD_NO;
    MHD_add_response_header(resp, MHD_HTTP_HEADER_ALLOW, r->allow);
    if (r->srv->cfg->cors_origin[0]) {
        MHD_add_response_header(resp, "Access-Control-Allow-Methods", r->allow);
        MHD_add_response_header(resp, "Access-Control-Allow-Headers",
                                "Content-Type, If-None-Match, Authorization, Accept");
        MHD_add_response_header(resp, "Access-Control-Max-Age", "600");
    }
    return ismd_send(r, 204, resp);
}


enum MHD_Result ismd_respond_body_too_large(ismd_req *r)
{
    char msg[128];
    snprintf(msg, sizeof msg, "the request body is over the limit of %zu bytes (--max-body)",
             r->srv->cfg->max_body);
    return ismd_respond_error(r, 413, "body_too_large", msg);
}
