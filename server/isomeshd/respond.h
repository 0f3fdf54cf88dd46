/* respond.h — answering a request: responses that share a blob's bytes, and helpers that
 * add the common headers, record the status and size for the log and the metrics, and queue
 * the response. Each returns what the handler returns. */
#ifndef ISMD_RESPOND_H
#define ISMD_RESPOND_H

#include "server/isomeshd/http_types.h"

/* Adds CORS and nosniff headers, records status and size, queues and releases resp. */
enum MHD_Result ismd_send(ismd_req *r, unsigned status, struct MHD_Response *resp);
/* A header of an answer, to whatever writes it (libmicrohttpd's response, or own_sender.c's
 * header block). */
typedef void (*ismd_add_header)(void *ctx, const char *name, const char *value);
/* Adds a header to the libmicrohttpd response ctx. */
void ismd_add_to_response(void *ctx, const char *name, const char *value);
/* The headers ismd_send adds to every answer (CORS as configured, nosniff), in order. */
void ismd_common_headers(const ismd_config *cfg, ismd_add_header add, void *ctx);
/* The response for cached entry name whose bytes are b: from its file in the disk cache
 * (libmicrohttpd sends it with sendfile, no copy through user space) when b is large and the
 * file holds exactly b's bytes (cache_disk.h compares them whenever the file changed), else
 * from b's bytes. NULL when out of memory. */
struct MHD_Response *ismd_response_cached(ismd_server *s, const char *name, ism_blob *b,
                                          const char *content_type);
/* A response sharing b's bytes (b gets one more reference, dropped when MHD is done). */
struct MHD_Response *ismd_response_blob(ism_blob *b, const char *content_type);
struct MHD_Response *ismd_response_text(const char *text, const char *content_type);
enum MHD_Result ismd_respond_error(ismd_req *r, unsigned status, const char *code,
                                   const char *message);
/* An error whose JSON body is already made (e.g. the pipeline's). */
enum MHD_Result ismd_respond_error_blob(ismd_req *r, unsigned status, ism_blob *json);
enum MHD_Result ismd_respond_json(ismd_req *r, unsigned status, const char *json);
/* 401 with WWW-Authenticate: the caller needs a (valid) bearer token. */
enum MHD_Result ismd_respond_unauthorized(ismd_req *r);
/* 503, 429 or 500 for a computation the scheduler refused (ismd_sched_submit's answer). */
enum MHD_Result ismd_respond_refused(ismd_req *r, ismd_submit st);

/* The code and message of a 401 for r's caller (a missing or an invalid token); counts the
 * rejection. */
const char *ismd_unauthorized(ismd_req *r, const char **message);
/* 204 to an OPTIONS request: Allow, and the CORS preflight headers when CORS is on. */
enum MHD_Result ismd_respond_preflight(ismd_req *r);
/* 413: the body is over --max-body. */
enum MHD_Result ismd_respond_body_too_large(ismd_req *r);

#endif
