/* worker_pool.c — the pool thread of worker_pool.h: its epoll loop over the workers' pipes
 * (non-blocking frame I/O), dispatch from the queue, results into the cache, deadlines,
 * cancellation, preemption, crash detection, respawn with back-off, shutdown. One surface is
 * polygonised once even when several formats of it are asked for at once: a flight whose
 * surface another worker is polygonising is held (still "running" for the scheduler, on no
 * worker) until that computation ends and its surface is stored (the SURFACE frame after the
 * RESULT: the flight is answered first), then encoded from the stored surface. Starting a
 * process is worker_spawn.h's; Server-Timing entries from the stats server_timing.h's. */
#include "server/isomeshd/worker_pool.h"

#include <assert.h>
#include <errno.h>
#include <limits.h>
#include <math.h>
#include <pthread.h>
#include <signal.h>
#include <stdatomic.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/epoll.h>
#include <sys/eventfd.h>
#include <sys/wait.h>
#include <unistd.h>

#include "proto/computed.h"
#include "proto/frame.h"
#include "proto/request.h"
#include "server/common/gzip_body.h"
#include "server/common/pipeline.h"
#include "server/common/log.h"
#include "server/isomeshd/errors.h"
#include "server/isomeshd/server_timing.h"
#include "server/isomeshd/worker_spawn.h"

#define QUICK_DEATH_NS 1000000000LL       /* a worker dying sooner than this backs off */
#define MAX_BACKOFF_NS 5000000000LL
#define STOP_WAIT_NS 2000000000LL          /* workers get this long to exit on EOF */
#define MAX_EXPIRED 64
#define START_TIMEOUT_NS 15000000000LL     /* a worker silent this long after exec is killed */
/* A worker whose announced SURFACE frame has not arrived this long after its RESULT is killed
 * (the surface then not stored): the frame ceiling's 1 GB crosses a pipe in ~1-2 s even at
 * load 9 (5.5 MB in 5-11 ms), so only a stuck worker waits this long. */
#define SURFACE_WAIT_NS 60000000000LL
/* The mesh's entries written to the remote tiers after its surface, at most (the RESULT's
 * mesh, stats, features and request). */
#define LATER_MAX 4
/* Tests only (ISOMESHD_TEST_SURFACE_GATE, a path): a SURFACE frame is stored only once that
 * file exists (looked at this often), so that a test holds a worker in W_STORING for as long
 * as it needs, whatever the machine's speed. */
#define GATE_POLL_MS 10

/* W_STORING: the flight answered, its newly computed surface still crossing the pipe in the
 * SURFACE frame the RESULT announced (frame.h surface_len); no new job until it is stored.
 * Meanwhile the mesh's entries are in the local tiers only: their remote writes (Redis) wait
 * for the surface's, so that another daemon that finds the mesh there finds the surface too
 * (and encodes other formats from it), and the shared stage keeps the flight's lock until
 * they are made (sched.h storing). */
typedef enum wstate { W_EMPTY, W_STARTING, W_IDLE, W_BUSY, W_STORING, W_DYING } wstate;

/* A flight held until its surface, being polygonised by another worker, is stored. */
typedef struct held {
    ismd_flight *f;
    char surface[65];
} held;

typedef struct worker {
    int slot;
    wstate state;
    pid_t pid;
    int to_fd, from_fd;        /* daemon's ends: requests in, results out */
    bool want_out;             /* EPOLLOUT registered on to_fd */
    ism_frame_reader rd;
    ismd_flight *flight;
    char surface[65];          /* the surface key of flight */
    bool polygonising;         /* flight computes its surface (none was stored) */
    uint64_t storing_job;      /* W_STORING: the job whose SURFACE frame comes next, */
    uint32_t storing_len;      /* its announced length, */
    long long storing_until_ns; /* and when waiting for it ends (SURFACE_WAIT_NS) */
    char storing_name[ISM_CACHE_NAME_MAX]; /* the flight's name in sched's storing list, or "" */
    char later_names[LATER_MAX][ISM_CACHE_NAME_MAX]; /* its entries' remote writes, waiting */
    ism_blob *later[LATER_MAX];
    int nlater;
    bool gated;                /* its SURFACE frame arrived, held by the test gate */
    ism_blob *gated_surface;
    unsigned char *out;        /* request frame being written */
    size_t out_len, out_off;
    long long spawned_ns, respawn_at_ns;
    int quick_deaths;
} worker;

struct ismd_pool {
    ismd_pool_config cfg;
    ismd_sched *sched;
    ism_cache *cache;
    ismd_metrics *metrics;
    worker *w;
    int n;
    int epfd, evfd;
    pthread_t thread;
    held *held;                /* flights waiting for another's polygonisation of their surface */
    size_t nheld, held_cap;
    atomic_bool stopping;
    long long stop_deadline_ns;
    char *gate;                /* ISOMESHD_TEST_SURFACE_GATE, or NULL */
    bool gate_waiting;         /* a surface waits for it */
};

#define EV_WAKE UINT64_MAX
#define EV_READ(slot) ((uint64_t)(slot) << 1)
#define EV_WRITE(slot) (((uint64_t)(slot) << 1) | 1)

/* ---- bookkeeping --------------------------------------------------------------------- */

static void publish_workers(ismd_pool *p)
{
    long long ready = 0, busy = 0, storing = 0;
    for (int i = 0; i < p->n; i++) {
        ready += p->w[i].state == W_IDLE || p->w[i].state == W_BUSY ||
                 p->w[i].state == W_STORING;
        busy += p->w[i].state == W_BUSY; /* a job's, not a surface being stored */
        storing += p->w[i].state == W_STORING;
    }
    atomic_store(&p->metrics->workers_ready, ready);
    atomic_store(&p->metrics->workers_busy, busy);
    atomic_store(&p->metrics->workers_storing, storing);
    atomic_store(&p->metrics->flights_held, (long long)p->nheld);
}

static void wake(void *ctx)
{
    ismd_pool *p = ctx;
    uint64_t one = 1;
    ssize_t r = write(p->evfd, &one, sizeof one);
    (void)r; /* EAGAIN means a wake-up is already pending */
}

/* ---- spawning ------------------------------------------------------------------------ */

static unsigned char *surface_alloc(ism_frame_type type, size_t len,
                                    void (**release)(unsigned char *payload));

static bool spawn(ismd_pool *p, worker *w)
{
    ismd_worker_proc proc;
    if (!ismd_worker_spawn(p->cfg.worker_path, p->cfg.job_memory, &proc))
        return false;
    w->pid = proc.pid;
    w->to_fd = proc.to_fd;
    w->from_fd = proc.from_fd;
    w->want_out = false;
    w->state = W_STARTING;
    w->flight = NULL;
    w->spawned_ns = ism_now_ns();
    ism_frame_reader_init(&w->rd, ISM_FRAME_MAX_PAYLOAD);
    w->rd.alloc = surface_alloc;
    struct epoll_event ev = {.events = EPOLLIN, .data.u64 = EV_READ(w->slot)};
    epoll_ctl(p->epfd, EPOLL_CTL_ADD, w->from_fd, &ev);
    return true;
}

static void respawn_due(ismd_pool *p, long long now)
{
    for (int i = 0; i < p->n; i++) {
        worker *w = &p->w[i];
        if (w->state != W_EMPTY || w->respawn_at_ns > now)
            continue;
        if (!spawn(p, w)) {
            atomic_fetch_add(&p->metrics->worker_spawn_failures, 1);
            ism_logf(ISM_LOG_ERROR, "worker_spawn_failed", "%s: %s", p->cfg.worker_path,
                     strerror(errno));
            w->respawn_at_ns = now + MAX_BACKOFF_NS;
        }
    }
    publish_workers(p);
}

/* ---- ending a worker ----------------------------------------------------------------- */

static void close_to_fd(ismd_pool *p, worker *w)
{
    if (w->to_fd < 0)
        return;
    if (w->want_out)
        epoll_ctl(p->epfd, EPOLL_CTL_DEL, w->to_fd, NULL);
    close(w->to_fd);
    w->to_fd = -1;
    w->want_out = false;
    free(w->out);
    w->out = NULL;
    w->out_len = w->out_off = 0;
}

/* w leaves W_STORING: its surface (NULL when none came: the worker died or is being
 * stopped) goes into every tier, then its mesh's entries into the remote ones, and the
 * flight leaves sched's storing list. The remote tiers write in the order they are given
 * (one queue, one connection), so Redis has the surface before the mesh. */
static void end_storing(ismd_pool *p, worker *w, ism_blob *surface)
{
    char name[ISM_CACHE_NAME_MAX];
    if (surface && ism_cache_name(name, w->surface, ISM_COMPUTED_EXT))
        ism_cache_put(p->cache, name, surface);
    for (int i = 0; i < w->nlater; i++) {
        ism_cache_put_remote(p->cache, w->later_names[i], w->later[i]);
        ism_blob_unref(w->later[i]);
        w->later[i] = NULL;
    }
    w->nlater = 0;
    if (w->storing_name[0]) {
        ismd_sched_lock(p->sched);
        ismd_sched_storing_end(p->sched, w->storing_name);
        ismd_sched_unlock(p->sched);
        w->storing_name[0] = 0;
    }
    ism_blob_unref(w->gated_surface);
    w->gated_surface = NULL;
    w->gated = false;
}

/* Kills w (its flight, if any, must already be finished); EOF on its pipe completes it. */
static void kill_worker(ismd_pool *p, worker *w, ismd_restart_reason why)
{
    if (w->state == W_EMPTY || w->state == W_DYING)
        return;
    if (w->state == W_STORING)
        end_storing(p, w, NULL);
    kill(w->pid, SIGKILL);
    close_to_fd(p, w);
    w->state = W_DYING;
    w->flight = NULL;
    atomic_fetch_add(&p->metrics->worker_restarts[why], 1);
    static const char *const names[] = {"crash", "deadline", "cancel", "protocol", "preempt"};
    ism_log_field f[] = {ISM_LI("pid", w->pid), ISM_LS("reason", names[why])};
    ism_log_fields(ISM_LOG_WARN, "worker_killed", f, 2);
    publish_workers(p);
}

/* Fails the flight w computes (its waiters get the error) and forgets it. */
static void fail_flight(ismd_pool *p, worker *w, unsigned status, const char *code,
                        const char *message, ismd_outcome outcome)
{
    ismd_sched_lock(p->sched);
    ismd_sched_fail(p->sched, w->flight, status, code, message, outcome);
    ismd_sched_unlock(p->sched);
    w->flight = NULL;
}

/* The worker's result pipe closed: reap it, fail its flight, schedule the replacement. */
static void worker_gone(ismd_pool *p, worker *w)
{
    epoll_ctl(p->epfd, EPOLL_CTL_DEL, w->from_fd, NULL);
    close(w->from_fd);
    w->from_fd = -1;
    close_to_fd(p, w);
    ism_frame_reader_free(&w->rd);
    int status = 0;
    while (waitpid(w->pid, &status, 0) < 0 && errno == EINTR)
        ;
    char how[128];
    ismd_worker_describe_exit(status, how, sizeof how);
    long long now = ism_now_ns();
    if (w->state == W_STORING) /* died after its answer, before its surface */
        end_storing(p, w, NULL);
    bool intended = w->state == W_DYING;
    if (!intended) {
        atomic_fetch_add(&p->metrics->worker_restarts[ISMD_RESTART_CRASH], 1);
        ism_log_field f[] = {ISM_LI("pid", w->pid), ISM_LS("how", how),
                             ISM_LS("job", w->flight ? w->flight->name : NULL)};
        ism_log_fields(ISM_LOG_ERROR, "worker_died", f, 3);
    }
    if (w->flight) {
        char msg[256];
        snprintf(msg, sizeof msg, "the worker computing this mesh %s; it has been replaced",
                 how);
        fail_flight(p, w, 500, "worker_crashed", msg, ISMD_OUT_CRASH);
    }
    bool quick = !intended && now - w->spawned_ns < QUICK_DEATH_NS;
    w->quick_deaths = quick ? w->quick_deaths + 1 : 0;
    long long backoff = 0;
    if (w->quick_deaths) {
        backoff = 50000000LL << (w->quick_deaths < 7 ? w->quick_deaths : 7);
        if (backoff > MAX_BACKOFF_NS)
            backoff = MAX_BACKOFF_NS;
    }
    w->respawn_at_ns = now + backoff;
    w->state = W_EMPTY;
    w->pid = 0;
    publish_workers(p);
}

/* ---- frames from a worker ------------------------------------------------------------ */

static void protocol_error(ismd_pool *p, worker *w, const char *what)
{
    ism_log_field f[] = {ISM_LI("pid", w->pid), ISM_LS("error", what)};
    ism_log_fields(ISM_LOG_ERROR, "worker_protocol_error", f, 2);
    if (w->flight)
        fail_flight(p, w, 500, "worker_protocol",
                    "the worker sent a malformed answer; it has been replaced", ISMD_OUT_CRASH);
    kill_worker(p, w, ISMD_RESTART_PROTOCOL);
}

static void release_blob_data(unsigned char *data)
{
    ism_blob_unref(ism_blob_of_data(data));
}

/* The workers' frame readers' allocator: a SURFACE frame is read straight into a blob, which
 * cache_computed hands to the cache as it is (no copy of the 5.5 MB of a 100k-triangle
 * surface: /tmp/http17 notes, the copy and its page faults 3-8 ms at load 9). */
static unsigned char *surface_alloc(ism_frame_type type, size_t len,
                                    void (**release)(unsigned char *payload))
{
    ism_blob *b = type == ISM_FRAME_SURFACE ? ism_blob_new(len) : NULL;
    if (!b)
        return NULL;
    *release = release_blob_data;
    return b->data;
}

/* A newly computed surface (a SURFACE frame's payload), as a new reference to the blob it
 * was read into, to go into every tier under its surface key, so any format of it, on any
 * daemon sharing the tiers, is encoded from it. NULL for a payload not in a blob
 * (surface_alloc's ism_blob_new failed: out of memory): a copy would need as much again. */
static ism_blob *surface_of(const ism_frame *fr)
{
    if (!fr->len || fr->release != release_blob_data)
        return NULL;
    return ism_blob_ref(ism_blob_of_data(fr->payload));
}

/* One entry of a result: into every tier, or (later: its surface follows) into the local
 * tiers now and into w's list for the remote ones (end_storing). */
static void cache_entry(ismd_pool *p, worker *w, bool later, const char *key, const char *ext,
                        ism_blob *b)
{
    char name[ISM_CACHE_NAME_MAX];
    if (!b || !ism_cache_name(name, key, ext))
        return;
    if (!later) {
        ism_cache_put(p->cache, name, b);
        return;
    }
    /* cache_result's LATER_MAX calls per result, and every exit from W_STORING (end_storing)
     * empties the list */
    assert(w->nlater < LATER_MAX);
    ism_cache_put_local(p->cache, name, b);
    memcpy(w->later_names[w->nlater], name, sizeof name);
    w->later[w->nlater++] = ism_blob_ref(b);
}

static void cache_result(ismd_pool *p, worker *w, bool later, ism_blob *body, ism_blob *stats,
                         ism_blob *features, ism_blob *canonical)
{
    const ismd_flight *f = w->flight;
    cache_entry(p, w, later, f->key, f->fmt, body);
    cache_entry(p, w, later, f->key, "stats.json", stats);
    cache_entry(p, w, later, f->key, "features.json", features);
    cache_entry(p, w, later, f->key, "request.json", canonical);
    /* the features' gzip bytes, made here once rather than on the HTTP thread per request
     * (gzip_body.h); local tiers only: a peer that fetches the plain entry makes its own */
    if (features && features->len >= ISM_GZIP_MIN_BODY) {
        ism_blob *gz = ism_cache_put_features_gzip(p->cache, f->key, features);
        if (gz)
            atomic_fetch_add(&p->metrics->gzip_on_store, 1);
        ism_blob_unref(gz);
    }
}

/* Answers w's flight with r; w then waits for the surface_len bytes of its SURFACE frame
 * (W_STORING), or is idle when none follows. A flight whose entries wait for that surface
 * (cache_result's later) goes on sched's storing list in the same hold of its lock: whoever
 * sees it finished sees it storing. */
static void finish_busy(ismd_pool *p, worker *w, ismd_result *r, ismd_outcome o,
                        uint32_t surface_len)
{
    ismd_flight *f = w->flight;
    w->storing_job = f->id;
    ismd_sched_lock(p->sched);
    bool listed = surface_len && w->nlater && ismd_sched_storing_begin(p->sched, f->name);
    if (listed)
        memcpy(w->storing_name, f->name, sizeof w->storing_name);
    r->queue_ms = (f->started_ns - f->submitted_ns) / 1e6;
    ismd_sched_finish(p->sched, f, r, o);
    ismd_sched_unlock(p->sched);
    if (!listed) /* out of memory for the list: written now, the surface after them */
        end_storing(p, w, NULL);
    w->flight = NULL;
    w->state = surface_len ? W_STORING : W_IDLE;
    w->storing_len = surface_len;
    w->storing_until_ns = ism_now_ns() + SURFACE_WAIT_NS;
    publish_workers(p);
}

/* The test gate (GATE_POLL_MS) is open: no gate, or its file exists. */
static bool gate_open(const ismd_pool *p)
{
    return !p->gate || access(p->gate, F_OK) == 0;
}

static void stored(ismd_pool *p, worker *w, ism_blob *surface)
{
    end_storing(p, w, surface);
    w->state = W_IDLE;
    publish_workers(p);
}

static void on_surface(ismd_pool *p, worker *w, const ism_frame *fr)
{
    if (w->state != W_STORING || w->gated || fr->job != w->storing_job ||
        fr->len != w->storing_len) {
        protocol_error(p, w, "surface for no answered job");
        return;
    }
    ism_blob *b = surface_of(fr);
    if (!gate_open(p)) { /* stored by gated_due once the gate opens */
        w->gated = true;
        w->gated_surface = b;
        return;
    }
    stored(p, w, b);
    ism_blob_unref(b);
}

/* Surfaces held by the test gate, stored once it opens. True while some still wait. */
static bool gated_due(ismd_pool *p)
{
    bool open = gate_open(p), waiting = false;
    for (int i = 0; i < p->n; i++) {
        worker *w = &p->w[i];
        if (w->state != W_STORING || !w->gated)
            continue;
        if (!open) {
            waiting = true;
            continue;
        }
        ism_blob *b = w->gated_surface;
        w->gated_surface = NULL;
        stored(p, w, b);
        ism_blob_unref(b);
    }
    return waiting;
}

static void on_result(ismd_pool *p, worker *w, const ism_frame *fr)
{
    ism_frame_result fres;
    if (!ism_frame_result_decode(fr, &fres)) {
        protocol_error(p, w, "undecodable result");
        return;
    }
    ismd_flight *f = w->flight;
    ismd_result r = {.status = fres.status, .worker_ms = fres.worker_us / 1000.0};
    ismd_metrics_polygonise(p->metrics, fres.worker_us / 1e6);
    if (fres.status == 200)
        atomic_fetch_add(fres.polygonised ? &p->metrics->polygonisations
                                          : &p->metrics->stored_encodings, 1);
    ism_blob *stats = NULL, *features = NULL, *canonical = NULL;
    ismd_outcome o = ISMD_OUT_OK;
    uint32_t surface_len = 0; /* a SURFACE frame follows (not after a key mismatch: a
                                 protocol error then, the worker is replaced) */
    if (fres.status == 200 && (strcmp(fres.key, f->key) != 0 || strcmp(fres.format, f->fmt) != 0)) {
        ism_logf(ISM_LOG_ERROR, "worker_key_mismatch", "asked for %s, got %s.%s", f->name,
                 fres.key, fres.format);
        r.status = 500;
        r.body = ismd_error_json("key_mismatch",
                                 "the worker computed a different mesh than the one asked for",
                                 NULL);
        r.content_type = "application/json";
        o = ISMD_OUT_ERROR;
    } else if (fres.status == 200) {
        r.body = ism_blob_copy(fres.body, fres.body_len);
        r.content_type = ism_format_mime_of(f->fmt);
        surface_len = fres.surface_len;
        /* the key the SURFACE frame is stored under: the worker's (it may differ from the
         * one the daemon keyed the flight's request with, never for a polygonised one) */
        memcpy(w->surface, fres.surface_key, sizeof w->surface);
        if (fres.stats_len)
            stats = ism_blob_copy(fres.stats, fres.stats_len);
        if (fres.features_len)
            features = ism_blob_copy(fres.features, fres.features_len);
        if (fres.canonical_len)
            canonical = ism_blob_copy(fres.canonical, fres.canonical_len);
        if (!r.body) {
            r.status = 500;
            r.body = ismd_error_json("out_of_memory", "the server ran out of memory", NULL);
            r.content_type = "application/json";
            o = ISMD_OUT_ERROR;
        } else {
            cache_result(p, w, surface_len > 0, r.body, stats, features,
                         canonical ? canonical : f->request);
            r.stats = stats;
            r.features = features;
            if (fres.polygonised) /* an encoding alone: the stats' phases are not this run's */
                ismd_server_timing(stats, r.timing, sizeof r.timing);
        }
    } else {
        r.body = ism_blob_copy(fres.body, fres.body_len);
        r.content_type = "application/json";
        o = fres.status == 400 || fres.status == 422 ? ISMD_OUT_REJECTED : ISMD_OUT_ERROR;
    }
    finish_busy(p, w, &r, o, surface_len);
    ism_blob_unref(r.body);
    ism_blob_unref(stats);
    ism_blob_unref(features);
    ism_blob_unref(canonical);
}

static void on_error_frame(ismd_pool *p, worker *w, const ism_frame *fr)
{
    ism_frame_cursor c;
    ism_frame_cursor_init(&c, fr->payload, fr->len);
    uint32_t status = ism_frame_get_u32(&c);
    size_t len;
    const unsigned char *json = ism_frame_get_bytes(&c, &len);
    if (c.failed || status < 400 || status > 599) {
        protocol_error(p, w, "undecodable error frame");
        return;
    }
    ismd_result r = {.status = status, .content_type = "application/json"};
    r.body = ism_blob_copy(json, len);
    finish_busy(p, w, &r, ISMD_OUT_ERROR, 0);
    ism_blob_unref(r.body);
}

static void on_frame(ismd_pool *p, worker *w, const ism_frame *fr)
{
    switch (fr->type) {
    case ISM_FRAME_HELLO:
        if (w->state != W_STARTING) {
            protocol_error(p, w, "unexpected hello");
            return;
        }
        w->state = W_IDLE;
        publish_workers(p);
        return;
    case ISM_FRAME_PROGRESS: {
        if (w->state != W_BUSY || fr->job != w->flight->id || fr->len != 4) {
            protocol_error(p, w, "progress for no running job");
            return;
        }
        ism_frame_cursor c;
        ism_frame_cursor_init(&c, fr->payload, fr->len);
        double frac = ism_frame_get_u32(&c) / 1e6;
        ismd_sched_lock(p->sched);
        ismd_sched_progress(p->sched, w->flight, frac > 1 ? 1 : frac);
        ismd_sched_unlock(p->sched);
        return;
    }
    case ISM_FRAME_RESULT:
    case ISM_FRAME_ERROR:
        if (w->state != W_BUSY || fr->job != w->flight->id) {
            protocol_error(p, w, "answer for no running job");
            return;
        }
        if (fr->type == ISM_FRAME_RESULT)
            on_result(p, w, fr);
        else
            on_error_frame(p, w, fr);
        return;
    case ISM_FRAME_SURFACE:
        on_surface(p, w, fr);
        return;
    default:
        protocol_error(p, w, "unexpected frame type");
    }
}

static void on_readable(ismd_pool *p, worker *w)
{
    for (;;) {
        if (w->state == W_EMPTY)
            return;
        ism_frame fr = {0};
        ism_frame_status st = ism_frame_read_fd(&w->rd, w->from_fd, &fr);
        if (st == ISM_FRAME_AGAIN)
            return;
        if (st == ISM_FRAME_OK) {
            if (w->state != W_DYING)
                on_frame(p, w, &fr);
            ism_frame_free(&fr);
            continue;
        }
        if (st == ISM_FRAME_EOF || st == ISM_FRAME_TRUNCATED || st == ISM_FRAME_IO_ERROR ||
            w->state == W_DYING) {
            worker_gone(p, w);
            return;
        }
        protocol_error(p, w, ism_frame_status_name(st));
        /* keep reading: the next read sees EOF once the killed worker is gone */
    }
}

/* ---- requests to a worker ------------------------------------------------------------ */

static void flush_out(ismd_pool *p, worker *w)
{
    while (w->out && w->out_off < w->out_len) {
        ssize_t n = write(w->to_fd, w->out + w->out_off, w->out_len - w->out_off);
        if (n > 0) {
            w->out_off += (size_t)n;
            continue;
        }
        if (n < 0 && errno == EINTR)
            continue;
        if (n < 0 && (errno == EAGAIN || errno == EWOULDBLOCK)) {
            if (!w->want_out) {
                struct epoll_event ev = {.events = EPOLLOUT, .data.u64 = EV_WRITE(w->slot)};
                epoll_ctl(p->epfd, EPOLL_CTL_ADD, w->to_fd, &ev);
                w->want_out = true;
            }
            return;
        }
        /* EPIPE: the worker is gone; its result pipe reports EOF next. */
        close_to_fd(p, w);
        return;
    }
    free(w->out);
    w->out = NULL;
    w->out_len = w->out_off = 0;
    if (w->want_out) {
        epoll_ctl(p->epfd, EPOLL_CTL_DEL, w->to_fd, NULL);
        w->want_out = false;
    }
}

/* The stored computed surface of a flight's request (its surface key's entry), or NULL;
 * surface gets the surface key ("" when the request does not key). */
static ism_blob *stored_surface(ismd_pool *p, const ismd_flight *f, char surface[65])
{
    surface[0] = 0;
    if (!f->request)
        return NULL;
    ism_pipeline_limits lim;
    ism_pipeline_limits_default(&lim);
    lim.max_depth = p->cfg.max_depth;
    ism_pipeline_result pr;
    char name[ISM_CACHE_NAME_MAX];
    bool keyed = ism_pipeline_key((const char *)f->request->data, f->request->len, f->fmt, &lim,
                                  &pr) &&
                 ism_cache_name(name, pr.surface_key, ISM_COMPUTED_EXT);
    if (keyed)
        memcpy(surface, pr.surface_key, 65);
    ism_pipeline_result_free(&pr);
    return keyed ? ism_cache_get(p->cache, name, NULL) : NULL;
}

/* The job timeout in whole milliseconds for the worker (0: none; clamped to the field). */
static uint32_t job_timeout_ms(double seconds)
{
    double ms = floor(seconds * 1e3);
    return !(ms > 0) ? 0 : ms >= (double)UINT32_MAX ? UINT32_MAX : (uint32_t)ms;
}

static bool encode_request(ismd_pool *p, worker *w, const ismd_flight *f, ism_blob *stored)
{
    ism_frame_job job = {
        .max_depth = (uint32_t)p->cfg.max_depth,
        .threads = (uint32_t)p->cfg.threads,
        .max_triangles = p->cfg.max_triangles,
        .max_memory = p->cfg.job_memory ? p->cfg.job_memory / 4 * 3 : 0,
        .timeout_ms = job_timeout_ms(p->sched->job_timeout_s),
        .json = f->request->data,
        .json_len = f->request->len,
        .computed = stored ? stored->data : NULL,
        .computed_len = stored ? stored->len : 0,
    };
    snprintf(job.format, sizeof job.format, "%s", f->fmt);
    ism_frame_builder b = {0};
    bool ok = ism_frame_job_encode(&job, &b);
    if (ok) {
        ism_frame_part part = {b.data, b.len};
        ok = ism_frame_encode(ISM_FRAME_REQUEST, f->id, &part, 1, &w->out, &w->out_len);
        w->out_off = 0;
    }
    ism_frame_builder_free(&b);
    return ok;
}

/* ---- flights held behind their surface's polygonisation ------------------------------- */

static bool polygonising(const ismd_pool *p, const char *surface)
{
    for (int i = 0; i < p->n; i++)
        if (((p->w[i].state == W_BUSY && p->w[i].flight && p->w[i].polygonising) ||
             p->w[i].state == W_STORING) &&
            !strcmp(p->w[i].surface, surface))
            return true;
    return false;
}

static bool hold(ismd_pool *p, ismd_flight *f, const char *surface)
{
    if (p->nheld == p->held_cap) {
        size_t cap = p->held_cap ? 2 * p->held_cap : 16;
        held *h = realloc(p->held, cap * sizeof *h);
        if (!h)
            return false;
        p->held = h;
        p->held_cap = cap;
    }
    p->held[p->nheld].f = f;
    memcpy(p->held[p->nheld].surface, surface, 65);
    p->nheld++;
    return true;
}

static void unhold_at(ismd_pool *p, size_t i)
{
    p->held[i] = p->held[--p->nheld];
}

/* Forgets f if it is held (it is being finished). */
static void unhold(ismd_pool *p, const ismd_flight *f)
{
    for (size_t i = 0; i < p->nheld; i++)
        if (p->held[i].f == f) {
            unhold_at(p, i);
            return;
        }
}

/* The next flight for an idle worker, with its stored surface (or NULL) and surface key: a
 * held flight whose surface is no longer being polygonised first, then the queue's next; a
 * queued flight whose surface a busy worker is polygonising is held instead. */
static ismd_flight *next_flight(ismd_pool *p, ism_blob **stored, char surface[65])
{
    for (size_t i = 0; i < p->nheld; i++)
        if (!polygonising(p, p->held[i].surface)) {
            ismd_flight *f = p->held[i].f;
            unhold_at(p, i);
            *stored = stored_surface(p, f, surface);
            return f;
        }
    for (;;) {
        ismd_sched_lock(p->sched);
        ismd_flight *f = ismd_sched_next(p->sched);
        ismd_sched_unlock(p->sched);
        if (!f)
            return NULL;
        /* running now: only this thread finishes it, so it stays valid without the lock */
        *stored = stored_surface(p, f, surface);
        if (*stored || !surface[0] || !polygonising(p, surface) || !hold(p, f, surface))
            return f;
    }
}

static void dispatch(ismd_pool *p)
{
    for (int i = 0; i < p->n; i++) {
        worker *w = &p->w[i];
        if (w->state != W_IDLE)
            continue;
        ism_blob *stored = NULL;
        char surface[65];
        ismd_flight *f = next_flight(p, &stored, surface);
        if (!f)
            break;
        bool ok = encode_request(p, w, f, stored);
        ism_blob_unref(stored);
        if (!ok) {
            ismd_sched_lock(p->sched);
            ismd_sched_fail(p->sched, f, 500, "out_of_memory", "the server ran out of memory",
                            ISMD_OUT_ERROR);
            ismd_sched_unlock(p->sched);
            i--; /* the worker is still idle */
            continue;
        }
        w->flight = f;
        w->polygonising = stored == NULL;
        memcpy(w->surface, surface, sizeof w->surface);
        w->state = W_BUSY;
        flush_out(p, w);
    }
    publish_workers(p);
}

/* ---- deadlines and cancellation ------------------------------------------------------ */

static worker *worker_of(ismd_pool *p, const ismd_flight *f)
{
    for (int i = 0; i < p->n; i++)
        if (p->w[i].state == W_BUSY && p->w[i].flight == f)
            return &p->w[i];
    return NULL;
}

/* Every worker busy and a user with nothing running waits: the scheduler names a flight of a
 * user holding several workers; it goes back to its line and its worker is returned (to be
 * stopped). Scheduler lock held. */
static worker *preempt(ismd_pool *p)
{
    for (int i = 0; i < p->n; i++)
        if (p->w[i].state != W_BUSY || !p->w[i].flight)
            return NULL; /* a worker is or will soon be free */
    ismd_flight *f = ismd_sched_preempt_victim(p->sched);
    worker *w = f ? worker_of(p, f) : NULL;
    if (!w)
        return NULL;
    ism_log_field lf[] = {ISM_LS("job", f->name), ISM_LS("user", f->user)};
    ism_log_fields(ISM_LOG_INFO, "computation_preempted", lf, 2);
    ismd_sched_requeue(p->sched, f);
    w->flight = NULL;
    return w;
}

static void enforce(ismd_pool *p, long long now)
{
    ismd_flight *expired[MAX_EXPIRED];
    worker *doomed[MAX_EXPIRED + 256];
    ismd_restart_reason why[MAX_EXPIRED + 256];
    size_t nd = 0;
    ismd_sched_lock(p->sched);
    size_t ne = ismd_sched_expire(p->sched, now, expired, MAX_EXPIRED);
    for (size_t i = 0; i < ne; i++) {
        worker *w = worker_of(p, expired[i]);
        unhold(p, expired[i]);
        char msg[160];
        snprintf(msg, sizeof msg, "the computation ran past its deadline of %g s "
                 "(--job-timeout); its worker was stopped", p->sched->job_timeout_s);
        ismd_sched_fail(p->sched, expired[i], 504, "deadline_exceeded", msg, ISMD_OUT_DEADLINE);
        if (w) {
            w->flight = NULL;
            doomed[nd] = w;
            why[nd++] = ISMD_RESTART_DEADLINE;
        }
    }
    for (int i = 0; i < p->n && nd < sizeof doomed / sizeof doomed[0]; i++) {
        worker *w = &p->w[i];
        if (w->state == W_BUSY && w->flight && (w->flight->nwaiters == 0 || w->flight->canceled)) {
            if (w->flight->nwaiters == 0)
                ismd_sched_finish(p->sched, w->flight, &(ismd_result){.status = 499},
                                  ISMD_OUT_CANCELED);
            else
                ismd_sched_fail(p->sched, w->flight, 499, "canceled", "the job was canceled",
                                ISMD_OUT_CANCELED);
            w->flight = NULL;
            doomed[nd] = w;
            why[nd++] = ISMD_RESTART_CANCEL;
        }
    }
    for (size_t i = 0; i < p->nheld;) {
        ismd_flight *f = p->held[i].f;
        if (f->nwaiters > 0 && !f->canceled) {
            i++;
            continue;
        }
        unhold_at(p, i);
        if (f->nwaiters == 0)
            ismd_sched_finish(p->sched, f, &(ismd_result){.status = 499}, ISMD_OUT_CANCELED);
        else
            ismd_sched_fail(p->sched, f, 499, "canceled", "the job was canceled", ISMD_OUT_CANCELED);
    }
    worker *taken = preempt(p);
    if (taken && nd < sizeof doomed / sizeof doomed[0]) {
        doomed[nd] = taken;
        why[nd++] = ISMD_RESTART_PREEMPT;
    }
    ismd_sched_unlock(p->sched);
    for (size_t i = 0; i < nd; i++)
        kill_worker(p, doomed[i], why[i]);
    for (int i = 0; i < p->n; i++) {
        worker *w = &p->w[i];
        if (w->state == W_STARTING && now - w->spawned_ns > START_TIMEOUT_NS) {
            ism_log_field f = ISM_LI("pid", w->pid);
            ism_log_fields(ISM_LOG_ERROR, "worker_start_timeout", &f, 1);
            kill_worker(p, w, ISMD_RESTART_PROTOCOL);
        } else if (w->state == W_STORING && now > w->storing_until_ns) {
            ism_log_field f = ISM_LI("pid", w->pid);
            ism_log_fields(ISM_LOG_ERROR, "worker_surface_timeout", &f, 1);
            kill_worker(p, w, ISMD_RESTART_PROTOCOL);
        }
    }
}

/* ---- the thread ---------------------------------------------------------------------- */

static int next_timeout_ms(ismd_pool *p, long long now)
{
    long long next = now + 1000000000LL;
    ismd_sched_lock(p->sched);
    long long d = ismd_sched_next_deadline(p->sched);
    ismd_sched_unlock(p->sched);
    if (d < next)
        next = d;
    for (int i = 0; i < p->n; i++)
        if (p->w[i].state == W_EMPTY && p->w[i].respawn_at_ns < next)
            next = p->w[i].respawn_at_ns;
    if (atomic_load(&p->stopping) && next > now + 50000000LL)
        next = now + 50000000LL;
    if (p->gate_waiting && next > now + GATE_POLL_MS * 1000000LL)
        next = now + GATE_POLL_MS * 1000000LL;
    long long ms = (next - now + 999999) / 1000000;
    return ms < 0 ? 0 : ms > 1000 ? 1000 : (int)ms;
}

/* Workers with a job or a surface to store (a stop waits for both, up to its deadline). */
static int busy_count(ismd_pool *p)
{
    int n = 0;
    for (int i = 0; i < p->n; i++)
        n += p->w[i].state == W_BUSY || p->w[i].state == W_STORING;
    return n;
}

static int alive_count(ismd_pool *p)
{
    int n = 0;
    for (int i = 0; i < p->n; i++)
        n += p->w[i].state != W_EMPTY;
    return n;
}

/* Stop: fail what still runs, close every request pipe (workers exit on EOF), wait a little,
 * then SIGKILL the stragglers. */
static void stop_all(ismd_pool *p)
{
    ismd_sched_lock(p->sched);
    while (p->nheld) {
        ismd_flight *f = p->held[0].f;
        unhold_at(p, 0);
        ismd_sched_fail(p->sched, f, 503, "shutting_down",
                        "the server is shutting down; retry on another instance", ISMD_OUT_CANCELED);
    }
    ismd_sched_unlock(p->sched);
    for (int i = 0; i < p->n; i++) {
        worker *w = &p->w[i];
        if (w->state == W_BUSY && w->flight) {
            fail_flight(p, w, 503, "shutting_down",
                        "the server is shutting down; retry on another instance",
                        ISMD_OUT_CANCELED);
            kill_worker(p, w, ISMD_RESTART_CANCEL);
        } else if (w->state != W_EMPTY) {
            if (w->state == W_STORING)
                end_storing(p, w, NULL);
            close_to_fd(p, w);
            w->state = W_DYING; /* exits on EOF; not counted as a restart */
        }
    }
    long long until = ism_now_ns() + STOP_WAIT_NS;
    struct epoll_event evs[64];
    while (alive_count(p) > 0) {
        long long now = ism_now_ns();
        if (now >= until) {
            for (int i = 0; i < p->n; i++)
                if (p->w[i].state != W_EMPTY)
                    kill(p->w[i].pid, SIGKILL);
            until = LLONG_MAX;
        }
        int n = epoll_wait(p->epfd, evs, 64, 100);
        for (int k = 0; k < n; k++) {
            uint64_t d = evs[k].data.u64;
            if (d != EV_WAKE && !(d & 1) && (int)(d >> 1) < p->n)
                on_readable(p, &p->w[d >> 1]);
        }
    }
}

static void *pool_main(void *arg)
{
    ismd_pool *p = arg;
    struct epoll_event evs[64];
    for (;;) {
        long long now = ism_now_ns();
        bool stopping = atomic_load(&p->stopping);
        if (!stopping)
            respawn_due(p, now);
        int n = epoll_wait(p->epfd, evs, 64, next_timeout_ms(p, now));
        for (int k = 0; k < n; k++) {
            uint64_t d = evs[k].data.u64;
            if (d == EV_WAKE) {
                uint64_t v;
                ssize_t r = read(p->evfd, &v, sizeof v);
                (void)r;
                continue;
            }
            worker *w = &p->w[d >> 1];
            if (d & 1)
                flush_out(p, w);
            else
                on_readable(p, w);
        }
        now = ism_now_ns();
        p->gate_waiting = p->gate && gated_due(p);
        enforce(p, now);
        if (atomic_load(&p->stopping) && (busy_count(p) == 0 || now >= p->stop_deadline_ns)) {
            stop_all(p);
            return NULL;
        }
        dispatch(p);
    }
}

ismd_pool *ismd_pool_start(const ismd_pool_config *cfg, ismd_sched *sched, ism_cache *cache,
                           ismd_metrics *metrics)
{
    if (access(cfg->worker_path, X_OK) != 0) {
        ism_logf(ISM_LOG_ERROR, "worker_missing", "%s: %s (build it with `make build`)",
                 cfg->worker_path, strerror(errno));
        return NULL;
    }
    if (ISMD_SANITIZER_BUILD && cfg->job_memory)
        ism_logf(ISM_LOG_WARN, "job_memory_ignored",
                 "AddressSanitizer build: workers run without RLIMIT_AS");
    ismd_pool *p = calloc(1, sizeof *p);
    if (!p)
        return NULL;
    p->cfg = *cfg;
    p->sched = sched;
    p->cache = cache;
    p->metrics = metrics;
    p->n = cfg->workers;
    p->w = calloc((size_t)p->n, sizeof *p->w);
    p->epfd = epoll_create1(EPOLL_CLOEXEC);
    p->evfd = eventfd(0, EFD_CLOEXEC | EFD_NONBLOCK);
    const char *gate = getenv("ISOMESHD_TEST_SURFACE_GATE");
    if (gate && *gate)
        p->gate = strdup(gate);
    if (!p->w || p->epfd < 0 || p->evfd < 0 || (gate && *gate && !p->gate))
        goto fail;
    for (int i = 0; i < p->n; i++) {
        p->w[i].slot = i;
        p->w[i].state = W_EMPTY;
        p->w[i].to_fd = p->w[i].from_fd = -1;
    }
    struct epoll_event ev = {.events = EPOLLIN, .data.u64 = EV_WAKE};
    epoll_ctl(p->epfd, EPOLL_CTL_ADD, p->evfd, &ev);
    atomic_store(&metrics->workers_total, p->n);
    ismd_sched_lock(sched);
    sched->wake = wake;
    sched->wake_ctx = p;
    ismd_sched_unlock(sched);
    if (pthread_create(&p->thread, NULL, pool_main, p) != 0)
        goto fail;
    return p;
fail:
    if (p->epfd >= 0)
        close(p->epfd);
    if (p->evfd >= 0)
        close(p->evfd);
    free(p->w);
    free(p->gate);
    free(p);
    return NULL;
}

void ismd_pool_stop(ismd_pool *p, double grace_s)
{
    ismd_sched_lock(p->sched);
    ismd_sched_drain(p->sched);
    ismd_sched_unlock(p->sched);
    p->stop_deadline_ns = ism_now_ns() + (long long)(grace_s * 1e9);
    atomic_store(&p->stopping, true);
    wake(p);
    pthread_join(p->thread, NULL);
    ismd_sched_lock(p->sched);
    p->sched->wake = NULL;
    ismd_sched_unlock(p->sched);
    close(p->epfd);
    close(p->evfd);
    free(p->held);
    free(p->w);
    free(p->gate);
    free(p);
}
