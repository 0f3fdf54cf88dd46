/* metrics.c — the figures of metrics.h: recording (relaxed atomics, no locks) and the
 * Prometheus text rendering (HELP/TYPE lines, cumulative histogram buckets). */
#include "server/isomeshd/metrics.h"

#include "server/common/cache_redis.h"
#include "server/common/log.h"

#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static const char *const ROUTE_LABELS[ISMD_R_COUNT] = {
    "/v1/mesh", "/v1/jobs", "/v1/jobs/{id}", "/v1/jobs/{id}/events",
    "/v1/meshes/{key}.{format}", "/v1/meshes/{key}/stats", "/v1/meshes/{key}/features",
    "/v1/presets", "/v1/openapi.yaml", "/v1/request.schema.json", "/healthz", "/readyz",
    "/metrics", "static", "/vendor/three", "other", "/v1/sweep", "/v1/box", "/v1/point",
    "/v1/presets/{name}/thumbnail.png",
};

static const unsigned STATUSES[ISMD_NSTATUS - 1] = {200, 202, 204, 206, 304, 400, 401, 403, 404,
                                                    405, 408, 413, 415, 422, 429, 431, 499,
                                                    500, 501, 503, 504};

static const double LAT_BOUNDS[ISMD_LAT_BUCKETS - 1] = {
    0.0005, 0.001, 0.0025, 0.005, 0.01, 0.025, 0.05, 0.1, 0.25, 0.5, 1, 2.5, 5, 10, 30, 60};
static const double POLY_BOUNDS[ISMD_POLY_BUCKETS - 1] = {
    0.01, 0.025, 0.05, 0.1, 0.25, 0.5, 1, 2.5, 5, 10, 30, 60, 300};

static const char *const RESTART_LABELS[ISMD_RESTART_COUNT] = {"crash", "deadline", "cancel",
                                                                "protocol", "preempt"};
static const char *const CUT_LABELS[ISMD_CUT_COUNT] = {
    "refused", "evicted_idle", "evicted_busy", "header_deadline", "body_deadline"};
static const char *const OUTCOME_LABELS[ISMD_OUT_COUNT] = {"ok", "rejected", "error",
                                                           "deadline", "crash", "canceled"};

const char *ismd_route_label(ismd_route r)
{
    return r < ISMD_R_COUNT ? ROUTE_LABELS[r] : "other";
}

void ismd_metrics_init(ismd_metrics *m)
{
    memset(m, 0, sizeof *m);
}

static size_t status_slot(unsigned status)
{
    for (size_t i = 0; i < ISMD_NSTATUS - 1; i++)
        if (STATUSES[i] == status)
            return i;
    return ISMD_NSTATUS - 1;
}

static void observe(ismd_histogram *h, const double *bounds, size_t nb, double seconds)
{
    size_t i = 0;
    while (i < nb && seconds > bounds[i])
        i++;
    atomic_fetch_add_explicit(&h->bucket[i], 1, memory_order_relaxed);
    atomic_fetch_add_explicit(&h->count, 1, memory_order_relaxed);
    double us = seconds * 1e6;
    atomic_fetch_add_explicit(&h->sum_us, us > 0 ? (unsigned long long)us : 0, memory_order_relaxed);
}

static ismd_route known_route(ismd_route r)
{
    return r < ISMD_R_COUNT ? r : ISMD_R_OTHER;
}

void ismd_metrics_count(ismd_metrics *m, ismd_route r, unsigned status)
{
    atomic_fetch_add_explicit(&m->requests[known_route(r)][status_slot(status)], 1,
                              memory_order_relaxed);
}

void ismd_metrics_served(ismd_metrics *m, ismd_route r, double seconds, size_t bytes)
{
    observe(&m->latency[known_route(r)], LAT_BOUNDS, ISMD_LAT_BUCKETS - 1, seconds);
    atomic_fetch_add_explicit(&m->response_bytes, bytes, memory_order_relaxed);
}

void ismd_metrics_polygonise(ismd_metrics *m, double seconds)
{
    observe(&m->polygonise, POLY_BOUNDS, ISMD_POLY_BUCKETS - 1, seconds);
}

/* ---- rendering ----------------------------------------------------------------------- */

typedef struct out {
    char *s;
    size_t len, cap;
    int failed;
} out;

static void emit(out *o, const char *fmt, ...) __attribute__((format(printf, 2, 3)));
static void emit(out *o, const char *fmt, ...)
{
    if (o->failed)
        return;
    for (;;) {
        va_list ap;
        va_start(ap, fmt);
        int n = vsnprintf(o->s + o->len, o->cap - o->len, fmt, ap);
        va_end(ap);
        if (n < 0) {
            o->failed = 1;
            return;
        }
        if ((size_t)n < o->cap - o->len) {
            o->len += (size_t)n;
            return;
        }
        size_t cap = o->cap * 2 + (size_t)n;
        char *s = realloc(o->s, cap);
        if (!s) {
            o->failed = 1;
            return;
        }
        o->s = s;
        o->cap = cap;
    }
}

static unsigned long long ld(atomic_ullong *a)
{
    return atomic_load_explicit(a, memory_order_relaxed);
}

static void header(out *o, const char *name, const char *type, const char *help)
{
    emit(o, "# HELP %s %s\n# TYPE %s %s\n", name, help, name, type);
}

static void histogram(out *o, const char *name, const char *labels, ismd_histogram *h,
                      const double *bounds, size_t nb)
{
    unsigned long long cum = 0;
    const char *sep = *labels ? "," : "";
    for (size_t i = 0; i <= nb; i++) {
        cum += ld(&h->bucket[i]);
        if (i < nb)
            emit(o, "%s_bucket{%s%sle=\"%g\"} %llu\n", name, labels, sep, bounds[i], cum);
        else
            emit(o, "%s_bucket{%s%sle=\"+Inf\"} %llu\n", name, labels, sep, cum);
    }
    const char *open = *labels ? "{" : "", *close = *labels ? "}" : "";
    emit(o, "%s_sum%s%s%s %.6f\n", name, open, labels, close, ld(&h->sum_us) / 1e6);
    emit(o, "%s_count%s%s%s %llu\n", name, open, labels, close, ld(&h->count));
}

static void gauge(out *o, const char *name, const char *help, long long v)
{
    header(o, name, "gauge", help);
    emit(o, "%s %lld\n", name, v);
}

static void render_cache(out *o, const ism_cache *cache)
{
    static const struct {
        const char *name, *type, *help;
        size_t off;
    } F[] = {
        {"isomesh_cache_tier_hits_total", "counter", "Lookups answered by this cache tier.",
         offsetof(ism_cache_counters, hits)},
        {"isomesh_cache_tier_misses_total", "counter", "Lookups this cache tier could not answer.",
         offsetof(ism_cache_counters, misses)},
        {"isomesh_cache_tier_stores_total", "counter", "Entries written to this cache tier.",
         offsetof(ism_cache_counters, stores)},
        {"isomesh_cache_store_failures_total", "counter",
         "Entries not stored (disk full or unwritable, write queue full).",
         offsetof(ism_cache_counters, store_failures)},
        {"isomesh_cache_corrupt_total", "counter",
         "Cache entries that failed their checksum and were dropped.",
         offsetof(ism_cache_counters, corrupt)},
        {"isomesh_cache_evictions_total", "counter", "Entries evicted to stay within budget.",
         offsetof(ism_cache_counters, evictions)},
        {"isomesh_cache_bytes", "gauge", "Bytes held by the cache tier (where known).",
         offsetof(ism_cache_counters, bytes)},
        {"isomesh_cache_entries", "gauge", "Entries held by the cache tier (where known).",
         offsetof(ism_cache_counters, entries)},
    };
    for (size_t f = 0; f < sizeof F / sizeof F[0]; f++) {
        header(o, F[f].name, F[f].type, F[f].help);
        for (size_t t = 0; t < cache->ntiers; t++) {
            ism_cache_tier *tier = cache->tiers[t];
            atomic_ullong *v = (atomic_ullong *)((char *)&tier->counters + F[f].off);
            emit(o, "%s{tier=\"%s\"} %llu\n", F[f].name, tier->name, ld(v));
        }
    }
}

/* The shared tier (cache_redis.h); its hits, misses and stores are in the tier="redis" lines. */
static void render_redis(out *o, struct ism_redis_counters *c)
{
    gauge(o, "isomesh_redis_up", "1 while the shared Redis cache is connected.", c->up);
    gauge(o, "isomesh_redis_asking", "Computations asking Redis or awaiting another daemon's.",
          c->asking);
    static const struct {
        const char *name, *help;
        size_t off;
    } F[] = {
        {"isomesh_redis_connects_total", "Connections made to Redis.",
         offsetof(ism_redis_counters, connects)},
        {"isomesh_redis_outages_total", "Times Redis became unreachable (each logged once).",
         offsetof(ism_redis_counters, outages)},
        {"isomesh_redis_errors_total", "Failed Redis connects and commands.",
         offsetof(ism_redis_counters, errors)},
        {"isomesh_redis_locks_acquired_total", "Computations this daemon took on for the service.",
         offsetof(ism_redis_counters, locks_acquired)},
        {"isomesh_redis_lock_waits_total",
         "Computations found running on another daemon and awaited.",
         offsetof(ism_redis_counters, lock_waits)},
        {"isomesh_redis_lock_takeovers_total",
         "Awaited computations taken over (the lock was released or expired).",
         offsetof(ism_redis_counters, lock_takeovers)},
        {"isomesh_redis_locks_lost_total", "Locks that expired while their computation ran.",
         offsetof(ism_redis_counters, locks_lost)},
        {"isomesh_redis_stale_locks_total",
         "Locks without a daemon's expiry (set by hand or a bug) found and removed.",
         offsetof(ism_redis_counters, stale_locks)},
        {"isomesh_redis_fallbacks_total",
         "Computations done here without asking Redis (it was unreachable).",
         offsetof(ism_redis_counters, fallbacks)},
    };
    for (size_t i = 0; i < sizeof F / sizeof F[0]; i++) {
        header(o, F[i].name, "counter", F[i].help);
        emit(o, "%s %llu\n", F[i].name, ld((atomic_ullong *)((char *)c + F[i].off)));
    }
}

char *ismd_metrics_render(ismd_metrics *m, const ism_cache *cache, size_t *len)
{
    out o = {.cap = 16384};
    o.s = malloc(o.cap);
    if (!o.s)
        return NULL;
    o.s[0] = 0;

    header(&o, "isomesh_http_requests_total", "counter",
           "HTTP requests by route and status (counted when answered).");
    for (int r = 0; r < ISMD_R_COUNT; r++)
        for (int s = 0; s < ISMD_NSTATUS; s++) {
            unsigned long long v = ld(&m->requests[r][s]);
            if (!v)
                continue;
            if (s < ISMD_NSTATUS - 1)
                emit(&o, "isomesh_http_requests_total{route=\"%s\",status=\"%u\"} %llu\n",
                     ROUTE_LABELS[r], STATUSES[s], v);
            else
                emit(&o, "isomesh_http_requests_total{route=\"%s\",status=\"other\"} %llu\n",
                     ROUTE_LABELS[r], v);
        }
    header(&o, "isomesh_http_request_duration_seconds", "histogram",
           "Time from request to response sent, by route.");
    for (int r = 0; r < ISMD_R_COUNT; r++) {
        if (!ld(&m->latency[r].count))
            continue;
        char labels[96];
        snprintf(labels, sizeof labels, "route=\"%s\"", ROUTE_LABELS[r]);
        histogram(&o, "isomesh_http_request_duration_seconds", labels, &m->latency[r],
                  LAT_BOUNDS, ISMD_LAT_BUCKETS - 1);
    }
    header(&o, "isomesh_http_response_bytes_total", "counter", "Response bytes queued.");
    emit(&o, "isomesh_http_response_bytes_total %llu\n", ld(&m->response_bytes));

    header(&o, "isomesh_cache_hits_total", "counter",
           "Mesh, stats and features lookups answered from the cache.");
    emit(&o, "isomesh_cache_hits_total %llu\n", ld(&m->mesh_hits));
    header(&o, "isomesh_cache_misses_total", "counter",
           "Mesh, stats and features lookups that needed a computation.");
    emit(&o, "isomesh_cache_misses_total %llu\n", ld(&m->mesh_misses));
    header(&o, "isomesh_features_gzip_total", "counter",
           "Features documents gzipped, once per cache entry: as the result was stored, or by "
           "the HTTP thread for an entry stored without its gzip bytes.");
    emit(&o, "isomesh_features_gzip_total{where=\"store\"} %llu\n", ld(&m->gzip_on_store));
    emit(&o, "isomesh_features_gzip_total{where=\"request\"} %llu\n", ld(&m->gzip_on_request));
    render_cache(&o, cache);
    if (m->redis)
        render_redis(&o, m->redis);

    header(&o, "isomesh_computations_started_total", "counter",
           "Computations started (identical requests in flight share one).");
    emit(&o, "isomesh_computations_started_total %llu\n", ld(&m->computations_started));
    header(&o, "isomesh_computations_total", "counter", "Finished computations by outcome.");
    for (int i = 0; i < ISMD_OUT_COUNT; i++)
        emit(&o, "isomesh_computations_total{outcome=\"%s\"} %llu\n", OUTCOME_LABELS[i],
             ld(&m->computations[i]));
    header(&o, "isomesh_singleflight_joins_total", "counter",
           "Requests that joined an identical computation already in flight.");
    emit(&o, "isomesh_singleflight_joins_total %llu\n", ld(&m->singleflight_joins));
    header(&o, "isomesh_cluster_submitted_total", "counter",
           "Computations this daemon put on the cluster queue (--cluster).");
    emit(&o, "isomesh_cluster_submitted_total %llu\n", ld(&m->cluster_submitted));
    header(&o, "isomesh_cluster_taken_total", "counter",
           "Cluster queue entries this daemon took to compute.");
    emit(&o, "isomesh_cluster_taken_total %llu\n", ld(&m->cluster_taken));
    header(&o, "isomesh_cluster_reclaimed_total", "counter",
           "Cluster queue entries taken over from a daemon that stopped heart-beating.");
    emit(&o, "isomesh_cluster_reclaimed_total %llu\n", ld(&m->cluster_reclaimed));
    header(&o, "isomesh_preemptions_total", "counter",
           "Computations sent back to their user's line so that a user with nothing running, "
           "or below half the workers, got a worker.");
    emit(&o, "isomesh_preemptions_total %llu\n", ld(&m->preemptions));
    header(&o, "isomesh_polygonise_seconds", "histogram",
           "Worker wall time per finished computation (polygonise, analyse, encode).");
    histogram(&o, "isomesh_polygonise_seconds", "", &m->polygonise, POLY_BOUNDS,
              ISMD_POLY_BUCKETS - 1);
    header(&o, "isomesh_polygonisations_total", "counter",
           "Finished computations that polygonised their surface (one per surface and "
           "accuracy; other formats, bits and attributes are encoded from the stored surface).");
    emit(&o, "isomesh_polygonisations_total %llu\n", ld(&m->polygonisations));
    header(&o, "isomesh_stored_encodings_total", "counter",
           "Finished computations encoded from a stored computed surface (no polygonisation).");
    emit(&o, "isomesh_stored_encodings_total %llu\n", ld(&m->stored_encodings));
    header(&o, "isomesh_rejected_total", "counter",
           "Requests refused before queueing: queue_full (503), client_limit (a user's "
           "--user-jobs, 429), unauthorized (401).");
    emit(&o, "isomesh_rejected_total{reason=\"queue_full\"} %llu\n", ld(&m->rejected_queue_full));
    emit(&o, "isomesh_rejected_total{reason=\"client_limit\"} %llu\n", ld(&m->rejected_client_limit));
    emit(&o, "isomesh_rejected_total{reason=\"unauthorized\"} %llu\n", ld(&m->rejected_unauthorized));

    header(&o, "isomesh_worker_restarts_total", "counter", "Worker processes replaced, by reason.");
    for (int i = 0; i < ISMD_RESTART_COUNT; i++)
        emit(&o, "isomesh_worker_restarts_total{reason=\"%s\"} %llu\n", RESTART_LABELS[i],
             ld(&m->worker_restarts[i]));
    header(&o, "isomesh_connections_closed_total", "counter",
           "Connections the daemon closed itself: refused or evicted at --max-connections "
           "(fair across addresses), or past --header-timeout / --body-timeout.");
    for (int i = 0; i < ISMD_CUT_COUNT; i++)
        emit(&o, "isomesh_connections_closed_total{reason=\"%s\"} %llu\n", CUT_LABELS[i],
             ld(&m->connections_closed[i]));
    header(&o, "isomesh_clients_left_total", "counter",
           "Requests waiting for a computation whose connection closed: by the client, or "
           "evicted at --max-connections (the computation stops when no other request or job "
           "waits for it).");
    emit(&o, "isomesh_clients_left_total %llu\n", ld(&m->clients_left));
    header(&o, "isomesh_worker_spawn_failures_total", "counter", "Failed worker starts.");
    emit(&o, "isomesh_worker_spawn_failures_total %llu\n", ld(&m->worker_spawn_failures));

    header(&o, "isomesh_log_lines_dropped_total", "counter",
           "Log lines dropped because the log reader fell behind.");
    emit(&o, "isomesh_log_lines_dropped_total %llu\n", ism_log_dropped());

    gauge(&o, "isomesh_queue_depth", "Computations waiting for a worker.", m->queue_depth);
    gauge(&o, "isomesh_cluster_queue_depth",
          "--cluster: computations waiting in the whole service's queue (Redis), counted "
          "every second.", m->cluster_queue_depth);
    gauge(&o, "isomesh_queue_capacity", "Most computations that may wait.", m->queue_capacity);
    gauge(&o, "isomesh_workers", "Worker process slots.", m->workers_total);
    gauge(&o, "isomesh_workers_ready", "Workers running and ready.", m->workers_ready);
    gauge(&o, "isomesh_workers_busy", "Workers computing a mesh.", m->workers_busy);
    gauge(&o, "isomesh_workers_storing",
          "Workers whose answer went out and whose newly computed surface is still being "
          "stored (the mesh's Redis writes wait for it).", m->workers_storing);
    gauge(&o, "isomesh_flights_held",
          "Computations waiting for another worker's polygonisation of their surface, to be "
          "encoded from it once stored.", m->flights_held);
    gauge(&o, "isomesh_jobs_active", "Jobs (POST /v1/jobs) queued or running.", m->jobs_active);
    gauge(&o, "isomesh_event_streams", "Open job event streams.", m->event_streams);
    gauge(&o, "isomesh_connections", "Open HTTP connections (at most --max-connections).",
          m->connections);
    header(&o, "isomesh_sendfile_responses_total", "counter",
           "Cached bodies sent from their disk cache file (sendfile) instead of memory.");
    emit(&o, "isomesh_sendfile_responses_total %llu\n",
         (unsigned long long)atomic_load(&m->sendfile_responses));
    header(&o, "isomesh_own_memory_responses_total", "counter",
           "Cached meshes the own sender sent from memory: their disk file missing, not yet "
           "written or not yet checked (a moment after the computation).");
    emit(&o, "isomesh_own_memory_responses_total %llu\n",
         (unsigned long long)atomic_load(&m->own_memory_responses));
    gauge(&o, "isomesh_upload_bytes",
          "Bytes held by request bodies (at most --upload-memory).", m->upload_bytes);
    gauge(&o, "isomesh_suspended_connections", "Connections waiting for a computation.",
          m->suspended_connections);
    if (o.failed) {
        free(o.s);
        return NULL;
    }
    *len = o.len;
    return o.s;
}
