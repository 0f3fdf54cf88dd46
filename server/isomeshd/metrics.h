/* metrics.h — isomeshd's counters, gauges and histograms (lock-free atomics, updated from any
 * thread) and their rendering in the Prometheus text exposition format for GET /metrics. */
#ifndef ISMD_METRICS_H
#define ISMD_METRICS_H

#include <stdatomic.h>
#include <stddef.h>

#include "server/common/cache.h"

/* Routes as they appear in the "route" label. */
typedef enum ismd_route {
    ISMD_R_MESH, ISMD_R_JOBS, ISMD_R_JOB, ISMD_R_JOB_EVENTS, ISMD_R_MESH_FILE,
    ISMD_R_MESH_STATS, ISMD_R_MESH_FEATURES, ISMD_R_PRESETS, ISMD_R_OPENAPI, ISMD_R_SCHEMA,
    ISMD_R_HEALTHZ, ISMD_R_READYZ, ISMD_R_METRICS, ISMD_R_STATIC, ISMD_R_VENDOR, ISMD_R_OTHER,
    ISMD_R_SWEEP, ISMD_R_BOX, ISMD_R_POINT, ISMD_R_THUMBNAIL, ISMD_R_COUNT
} ismd_route;

const char *ismd_route_label(ismd_route r);

#define ISMD_NSTATUS 22       /* tracked status codes + "other" */
#define ISMD_LAT_BUCKETS 17   /* request latency buckets incl. +Inf */
#define ISMD_POLY_BUCKETS 14  /* computation time buckets incl. +Inf */

typedef enum ismd_restart_reason {
    ISMD_RESTART_CRASH, ISMD_RESTART_DEADLINE, ISMD_RESTART_CANCEL, ISMD_RESTART_PROTOCOL,
    ISMD_RESTART_PREEMPT,
    ISMD_RESTART_COUNT
} ismd_restart_reason;

typedef enum ismd_outcome {
    ISMD_OUT_OK, ISMD_OUT_REJECTED, ISMD_OUT_ERROR, ISMD_OUT_DEADLINE, ISMD_OUT_CRASH,
    ISMD_OUT_CANCELED, ISMD_OUT_COUNT
} ismd_outcome;

/* Why the connection table (conns.h) closed a connection. */
typedef enum ismd_cut_reason {
    ISMD_CUT_REFUSED, ISMD_CUT_EVICTED_IDLE, ISMD_CUT_EVICTED_BUSY, ISMD_CUT_HEADER_DEADLINE,
    ISMD_CUT_BODY_DEADLINE,
    ISMD_CUT_COUNT
} ismd_cut_reason;

typedef struct ismd_histogram {
    atomic_ullong bucket[ISMD_LAT_BUCKETS]; /* non-cumulative counts */
    atomic_ullong count;
    atomic_ullong sum_us;
} ismd_histogram;

typedef struct ismd_metrics {
    atomic_ullong requests[ISMD_R_COUNT][ISMD_NSTATUS];
    ismd_histogram latency[ISMD_R_COUNT];
    atomic_ullong response_bytes;
    atomic_ullong mesh_hits, mesh_misses;    /* mesh lookups answered from cache or not */
    atomic_ullong gzip_on_store;             /* features documents gzipped as they were stored
                                                (the worker pool's thread) */
    atomic_ullong gzip_on_request;           /* ... gzipped by the HTTP thread (an entry stored
                                                without its gzip bytes: once per entry) */
    atomic_ullong computations_started;      /* worker jobs dispatched to a new computation */
    atomic_ullong computations[ISMD_OUT_COUNT];
    atomic_ullong singleflight_joins;        /* requests that joined a computation in flight */
    atomic_ullong cluster_submitted;         /* computations put on the cluster queue here */
    atomic_ullong cluster_taken;             /* entries of the cluster queue computed here */
    atomic_ullong cluster_reclaimed;         /* of them, re-claimed from a silent daemon */
    atomic_ullong preemptions;               /* computations sent back to their user's line so
                                                a user with nothing running got a worker */
    atomic_ullong worker_restarts[ISMD_RESTART_COUNT];
    atomic_ullong worker_spawn_failures;
    ismd_histogram polygonise;               /* worker wall time per finished computation */
    atomic_ullong polygonisations;           /* computations that polygonised a surface */
    atomic_ullong stored_encodings;          /* computations encoded from a stored surface */
    atomic_ullong rejected_queue_full, rejected_client_limit, rejected_unauthorized;
    atomic_ullong connections_closed[ISMD_CUT_COUNT]; /* by the connection table (conns.h) */
    atomic_ullong clients_left;              /* requests waiting for a computation whose
                                                client closed its connection */
    /* gauges */
    atomic_llong queue_depth, queue_capacity;
    atomic_llong cluster_queue_depth;        /* --cluster: entries waiting in the whole service */
    atomic_llong workers_total, workers_ready, workers_busy;
    atomic_llong workers_storing;            /* answered, their new surface still coming */
    atomic_llong flights_held;               /* waiting for another's polygonisation of their
                                                surface (worker_pool.c) */
    atomic_llong jobs_active, event_streams, suspended_connections;
    atomic_llong connections;                /* open, as the connection table counts them */
    atomic_llong upload_bytes;               /* request body buffers (--upload-memory) */
    atomic_ullong sendfile_responses;        /* bodies sent from their disk cache file */
    atomic_ullong own_memory_responses;      /* the own sender's from memory (no sound file) */
    struct ism_redis_counters *redis;        /* the shared tier's figures (NULL: no --redis) */
} ismd_metrics;

void ismd_metrics_init(ismd_metrics *m);
/* Counts a request of route r answered with status (requests_total): called when the answer
 * is queued, before its bytes leave, so a client that has read an answer always finds it
 * counted (libmicrohttpd's completion callback runs after the last byte left, and another
 * polling thread can serve the client's next request, /metrics, before it). A request never
 * answered (408: its body came too slowly; 499: the client left) is counted when it ends. */
void ismd_metrics_count(ismd_metrics *m, ismd_route r, unsigned status);
/* Adds a finished request's duration (seconds, until its answer left or it was given up)
 * and the body bytes it sent. */
void ismd_metrics_served(ismd_metrics *m, ismd_route r, double seconds, size_t bytes);
void ismd_metrics_polygonise(ismd_metrics *m, double seconds);

/* Renders everything (and the cache tiers' counters) as Prometheus text into a malloc'd
 * string; *len gets its length. NULL when out of memory. */
char *ismd_metrics_render(ismd_metrics *m, const ism_cache *cache, size_t *len);

#endif
