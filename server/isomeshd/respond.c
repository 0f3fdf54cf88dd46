/* respond.c — the response helpers of respond.h: responses sharing a blob's bytes, the
 * common headers (CORS, nosniff, Retry-After, Allow, WWW-Authenticate, no-store on errors),
 * the JSON error bodies, and the status recorded for the log and the metrics. */
#include "server/isomeshd/respond.h"

#include <stdio.h>
#include <string.h>
#include <unistd.h>

#include "server/common/cache_disk.h"

#include "server/isomeshd/errors.h"

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
/* Smaller bodies (from SENDFILE_BUSY_MIN) go from their file too while at least
 * BUSY_CONNECTIONS connections are open: their answers wait in the kernel together (a request
 * is complete for libmicrohttpd once its answer is queued: at 256 connections under 128 were
 * ever in progress), the copy then writes into socket pages no longer in cache, and the
 * file's pages, shared by every answer, stay in it. Measured with the file kept open
 * (cache_disk.c: no open, fstat of the header or pread per send), 330 KB mesh, wrk beside
 * nginx in the same run, load 20-23, daemon CPU us per request: at 256 connections memory
 * 177/174/146/163, sendfile 160/145/142/154 (nginx 92-98; libmicrohttpd alone 126-138 from
 * memory, 85-106 by sendfile); at 16 sendfile still costs more (118/115/124 against
 * 93/87/109), at 64 about the same (126/138/103 against 127/116/142). Counting the reader's
 * CPU too (wrk's, on loopback: the kernel's receive and ACK work lands on either side; perf
 * stat task-clock of both, medians of 3 x 5 s, 256 connections, load 17-21): with the system's
 * bbr, sendfile 285 us per request together against 278 from memory (the copy saved here
 * comes back as pacing work on the reader's side, http.c set_congestion); with
 * --tcp-congestion cubic 162 against 187.
 *
 * Why not an own sender (the headers, then one sendfile of the whole body, as nginx does):
 * libmicrohttpd 0.9.75 always writes the header block and the body of an answer itself. Its
 * header block always carries its own Content-Length of the response's size (connection.c
 * build_header_response: "Content-Length" from r->total_size, lines 2163-2176), which an
 * application's header only doubles (response.c 544: allowed by
 * MHD_RF_INSANITY_HEADER_CONTENT_LENGTH, then sent beside it); it leaves the body out only
 * for HEAD, 304, 204 and 1xx (is_reply_body_needed, 1731-1752); MHD_RF_HEAD_ONLY_RESPONSE
 * came in 1.0.0. Taking the socket over is the upgrade path, which requires a 101 answer
 * (MHD_queue_response, 5145) and ends the connection for libmicrohttpd (no keep-alive after
 * it). Suspending and writing the answer ourselves leaves libmicrohttpd an answer of its
 * own to write when resumed. Its file answers send 128 KB per sendfile call
 * (MHD_SENFILE_CHUNK_, mhd_send.c 69) with a TCP_CORK/NODELAY setsockopt around each. */
#define SENDFILE_BUSY_MIN ((size_t)64 << 10)
#define BUSY_CONNECTIONS 128

struct MHD_Response *ismd_response_cached(ismd_server *s, const char *name, ism_blob *b,
                                          const char *content_type)
{
    long long offset = 0;
    bool from_file = b->len >= SENDFILE_MIN ||
                     (b->len >= SENDFILE_BUSY_MIN &&
                      atomic_load(&s->metrics.connections) >= BUSY_CONNECTIONS);
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

enum MHD_Result ismd_send(ismd_req *r, unsigned status, struct MHD_Response *resp)
{
    if (!resp)
        return MHD_NO;
    const ismd_config *cfg = r->srv->cfg;
    if (cfg->cors_origin[0]) {
        MHD_add_response_header(resp, MHD_HTTP_HEADER_ACCESS_CONTROL_ALLOW_ORIGIN, cfg->cors_origin);
        MHD_add_response_header(resp, "Access-Control-Expose-Headers",
                                "ETag, Location, X-Cache, Server-Timing, Retry-After, "
                                "WWW-Authenticate");
        if (strcmp(cfg->cors_origin, "*") != 0)
            MHD_add_response_header(resp, MHD_HTTP_HEADER_VARY, "Origin");
    }
    MHD_add_response_header(resp, "X-Content-Type-Options", "nosniff");
    r->status = status;
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
