/* http.h — isomeshd's HTTP front: the server state every route sees, the per-request context,
 * libmicrohttpd set-up (--http-threads polling threads, suspend/resume), the request life cycle
 * (first call: route, 413/415 checks; body calls; answer on a later call), and the response
 * helpers that add the common headers, record the status for the log and the metrics.
 *
 * A request that needs a computation joins or starts a flight (sched.h) and suspends its
 * connection; the flight's end resumes it and the handler's next call answers. Nothing in the
 * MHD threads ever blocks on a worker. Handlers run on any of the polling threads at once:
 * what they share is behind the scheduler lock, the cache tiers' locks or atomics. */
#ifndef ISMD_HTTP_H
#define ISMD_HTTP_H

#include <microhttpd.h>
#include <stdatomic.h>
#include <stdbool.h>

#include "server/common/blob.h"
#include "server/common/cache.h"
#include "server/common/pipeline.h"
#include "server/isomeshd/auth.h"
#include "server/isomeshd/config.h"
#include "server/isomeshd/conns.h"
#include "server/isomeshd/metrics.h"
#include "server/isomeshd/sched.h"
#include "server/isomeshd/static_files.h"

typedef struct ismd_pool ismd_pool;
typedef struct ismd_jobs ismd_jobs;
typedef struct ismd_shared ismd_shared;

typedef struct ismd_server {
    const ismd_config *cfg;
    ismd_metrics metrics;
    ism_cache cache;
    ism_cache_tier *disk;
    ism_cache_tier *redis;       /* the shared tier (cache_redis.h); NULL without --redis */
    ismd_shared *shared;         /* its stage on the computation path (shared_cache.h) */
    ismd_sched sched;
    ismd_pool *pool;
    ismd_jobs *jobs;
    ismd_auth *auth;             /* bearer tokens (auth.h); disabled without --tokens */
    ismd_conns *conns;           /* open connections: fair limit, deadlines (conns.h) */
    ism_pipeline_limits limits;
    ismd_static web, vendor;
    ism_blob *openapi, *schema, *presets;
    struct MHD_Daemon *mhd;
    atomic_bool draining;
    atomic_long open_requests;   /* contexts created and not yet completed */
    int listen_fd;
} ismd_server;

/* What a suspended request does when its flight ends. */
typedef enum ismd_want { ISMD_WANT_MESH, ISMD_WANT_STATS, ISMD_WANT_FEATURES } ismd_want;

typedef struct ismd_req ismd_req;
typedef enum MHD_Result (*ismd_handler)(ismd_req *r);

struct ismd_req {
    ismd_server *srv;
    struct MHD_Connection *conn;
    ismd_conn *cn;             /* its entry in the connection table (NULL: out of memory) */
    bool client_left;          /* closed while waiting for a flight: end without answering */
    ismd_route route;
    char method[8];
    char path[512];            /* URL path, truncated for the log */
    char client[64];
    ismd_identity who;         /* the caller: token user or client address (auth.h) */
    long long t0_ns;
    /* body */
    char *body;
    size_t body_len, body_cap, discarded;
    bool wants_body, body_too_big;
    /* an error decided on the first call, answered once the body is read */
    unsigned early_status;
    const char *early_code;
    char early_msg[256];
    const char *allow;         /* Allow header for 405 / OPTIONS */
    /* route parameters */
    char key[65];
    char fmt[8];
    char id[40];
    ismd_want want;
    bool links;                /* answer with the key and URLs (JSON), not the mesh */
    ismd_handler handler;      /* the route's answer, run once the body is in */
    ismd_handler on_ready;     /* answers after a flight resumed us */
    /* waiting for a flight */
    ismd_waiter waiter;
    bool suspended, ready;
    unsigned r_status;
    ism_blob *r_body, *r_stats, *r_features;
    const char *r_ctype;
    double queue_ms, worker_ms, parse_ms;
    char timing[256];
    /* for the log line */
    unsigned status;
    size_t bytes;
    const char *cache;         /* "hit", "miss", NULL */
};

/* Starts MHD on an already listening socket. False on failure (logged). */
bool ismd_http_start(ismd_server *s, int listen_fd);
/* Stops accepting new connections (closes the listening socket). */
void ismd_http_quiesce(ismd_server *s);
/* Waits up to max_s seconds for open requests to finish, then stops MHD. */
void ismd_http_stop(ismd_server *s, double max_s);

/* ---- response helpers (queue the response; return what the handler returns) ---------- */

/* Adds CORS and nosniff headers, records status and size, queues and releases resp. */
enum MHD_Result ismd_send(ismd_req *r, unsigned status, struct MHD_Response *resp);
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
/* The body of POST /v1/mesh or /v1/jobs parsed, checked and keyed (?format= too): fills
 * r->key and r->fmt and returns the canonical request; NULL when it was refused (answered,
 * *ret what to return) or memory ran out (*ret MHD_NO). */
ism_blob *ismd_keyed_request(ismd_req *r, enum MHD_Result *ret);
/* 503, 429 or 500 for a computation the scheduler refused (ismd_sched_submit's answer). */
enum MHD_Result ismd_respond_refused(ismd_req *r, ismd_submit st);

/* Joins or starts the flight for key.fmt (request = canonical request JSON) and suspends
 * the connection; on_ready answers once it ends. A memory-cache hit found under the lock
 * answers at once through on_ready as well. Errors (429, 503) are answered here. */
enum MHD_Result ismd_wait_for(ismd_req *r, const char *key, const char *fmt,
                              ism_blob *request, ismd_handler on_ready);

/* The done callback of a request's waiter (r->waiter): keeps the result in r (r_status,
 * r_body, ...) and resumes the suspended connection, whose next call runs r->on_ready.
 * Scheduler lock held. For waits other than a flight's (a lookup in Redis: cluster.h). */
void ismd_req_done(ismd_waiter *w, const ismd_result *res);

/* A request header value or NULL. */
const char *ismd_header(ismd_req *r, const char *name);
/* A query argument or NULL. */
const char *ismd_query(ismd_req *r, const char *name);

/* Why ismd_job_start refused a job. */
typedef struct ismd_job_refusal {
    bool table_full;           /* the jobs table (submit: CLIENT_LIMIT = the user's share) */
    ismd_submit submit;        /* else the scheduler's answer */
} ismd_job_refusal;

/* Starts a job for r->key.r->fmt (canonical: its request): answered from the cache, or its
 * computation joined or queued, and recorded in Redis with --cluster. Returns the job with
 * the scheduler's lock held (the caller answers, then unlocks), or NULL (lock not held) with
 * the reason in why (routes_jobs.c). */
struct ismd_job;
struct ismd_job *ismd_job_start(ismd_req *r, ism_blob *canonical, ismd_job_refusal *why);
/* The 429 or 503 for a refused job. */
enum MHD_Result ismd_respond_job_refused(ismd_req *r, const ismd_job_refusal *why);

/* ---- routes (routes_*.c) ------------------------------------------------------------- */

enum MHD_Result ismd_route_mesh_post(ismd_req *r);       /* POST /v1/mesh */
enum MHD_Result ismd_route_mesh_get(ismd_req *r);        /* GET /v1/meshes/{key}.{fmt} */
enum MHD_Result ismd_route_mesh_json(ismd_req *r);       /* GET /v1/meshes/{key}/stats|features */
enum MHD_Result ismd_route_jobs_post(ismd_req *r);       /* POST /v1/jobs */
enum MHD_Result ismd_route_jobs_list(ismd_req *r);       /* GET /v1/jobs */
enum MHD_Result ismd_route_sweep(ismd_req *r);           /* POST /v1/sweep */
enum MHD_Result ismd_route_job_get(ismd_req *r);         /* GET /v1/jobs/{id} */
enum MHD_Result ismd_route_job_delete(ismd_req *r);      /* DELETE /v1/jobs/{id} */
enum MHD_Result ismd_route_job_events(ismd_req *r);      /* GET /v1/jobs/{id}/events */
enum MHD_Result ismd_route_doc(ismd_req *r);             /* presets, openapi, schema */
enum MHD_Result ismd_route_box(ismd_req *r);             /* POST /v1/box */
enum MHD_Result ismd_route_point(ismd_req *r);           /* POST /v1/point?at=X,Y,Z */
enum MHD_Result ismd_route_health(ismd_req *r);          /* /healthz, /readyz */
enum MHD_Result ismd_route_metrics(ismd_req *r);         /* /metrics */
enum MHD_Result ismd_route_static(ismd_req *r);          /* the viewer and /vendor/three */

#endif
