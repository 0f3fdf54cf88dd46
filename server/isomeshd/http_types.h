/* http_types.h — the state isomeshd's HTTP front shares with its routes and answers: the
 * server every route sees and the per-request context (http.h runs them), and reading a
 * request's headers and query. Types and two inline readers only, so respond.h, routes.h and
 * flight_wait.h need not include http.h, whose http.c calls them. */
#ifndef ISMD_HTTP_TYPES_H
#define ISMD_HTTP_TYPES_H

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
    struct ism_http_loops *loops; /* the polling threads (server/common/http_loops.h) */
    atomic_bool draining;
    atomic_long open_requests;   /* contexts created and not yet completed */
    int listen_fd;
} ismd_server;

/* What a suspended request does when its flight ends. */
typedef enum ismd_want { ISMD_WANT_MESH, ISMD_WANT_STATS, ISMD_WANT_FEATURES } ismd_want;

typedef struct ismd_req ismd_req;
typedef enum MHD_Result (*ismd_handler)(ismd_req *r);
typedef struct ismd_route_def ismd_route_def; /* a line of the route table (routes.c) */

struct ismd_req {
    ismd_server *srv;
    struct MHD_Connection *conn;
    ismd_conn *cn;             /* its entry in the connection table (NULL: out of memory) */
    bool client_left;          /* closed while waiting for a flight: end without answering */
    bool close_after;          /* the answer closes the connection (Connection: close) */
    const ismd_route_def *def;  /* its route */
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
    bool uploads_full;         /* refused: the bodies of all requests hit --upload-memory */
    /* an error decided on the first call, answered once the body is read */
    unsigned early_status;
    const char *early_code;
    char early_msg[256];
    const char *allow;         /* Allow header for 405 / OPTIONS */
    /* route parameters */
    char key[65];
    char fmt[8];
    char id[40];
    const char *preset;        /* a known preset's name (static storage) */
    ismd_want want;
    bool links;                /* answer with the key and URLs (JSON), not the mesh */
    ismd_handler handler;      /* the route's answer, run once the body is in */
    ismd_handler on_ready;     /* answers after a flight resumed us */
    /* waiting for a flight */
    ismd_waiter waiter;
    bool suspended, ready;
    unsigned r_status;
    ism_blob *r_body, *r_stats, *r_features;
    struct ism_fd_lease *lease; /* the own sender's body descriptor, when lent (fd_keep.h) */
    const char *r_ctype;
    double queue_ms, worker_ms, parse_ms;
    char timing[256];
    /* for the log line */
    unsigned status;           /* the answer's (0: none yet; set once, and counted then) */
    size_t bytes;
    const char *cache;         /* "hit", "miss", NULL */
};

/* A request header value or NULL. */
static inline const char *ismd_header(ismd_req *r, const char *name)
{
    return MHD_lookup_connection_value(r->conn, MHD_HEADER_KIND, name);
}

/* A query argument or NULL. */
static inline const char *ismd_query(ismd_req *r, const char *name)
{
    return MHD_lookup_connection_value(r->conn, MHD_GET_ARGUMENT_KIND, name);
}

#endif
