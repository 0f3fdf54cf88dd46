/* jobs.c — the jobs table and job event streams of jobs.h: random ids, state changes driven
 * by the flight (progress, done), cancellation, JSON views, expiry of finished jobs, and the
 * server-sent-event content reader that suspends when it has nothing new to say. */
#include "server/isomeshd/jobs.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/random.h>
#include <time.h>

#define NBUCKETS 1024
#define USER_BUCKETS 256
#define MAX_JOBS 10000       /* job records of all users together */
#define USER_JOBS_KEPT 1000  /* records of one user: a flood of posts by one user evicts only
                                its own finished records, never anybody else's */
#define JOB_TTL_NS (30LL * 60 * 1000000000LL) /* finished jobs are kept 30 minutes */

typedef struct stream stream;

/* How many records one user has in the table (exists while it has any). */
typedef struct juser {
    struct juser *next;
    size_t n;
    char user[64];
} juser;

struct ismd_job {
    ismd_waiter waiter;
    ismd_jobs *owner;
    char id[33], key[65], fmt[8];
    char user[64];             /* who created it */
    ismd_job_state state;
    double progress;
    unsigned status;
    ism_blob *stats, *error;
    long long created_ns, finished_ns;
    long long started_ns;      /* when its computation began running (0: not yet, or cached) */
    long long started_unix_ms; /* the same instant on the wall clock */
    time_t created_unix;
    unsigned version;
    int refs;                  /* the table + each stream */
    bool in_table;
    stream *streams;
    ismd_job *hnext, *lprev, *lnext;
};

struct stream {
    stream *next;
    ismd_job *job;
    ismd_jobs *jobs;
    ismd_sched *sched;
    struct MHD_Connection *conn;
    ism_http_loops *loops; /* the polling threads serving conn */
    bool suspended, finished;
    unsigned sent_version;
    char *pending;
    size_t pending_len, pending_off;
};

struct ismd_jobs {
    ismd_metrics *metrics;
    ismd_job *buckets[NBUCKETS];
    ismd_job *oldest, *newest;
    size_t count;
    juser *users[USER_BUCKETS];
    bool closing;
};

static const char *const STATE_NAMES[] = {"queued", "running", "done", "failed", "canceled"};

bool ismd_job_state_parse(const char *s, ismd_job_state *out)
{
    for (int i = 0; i <= ISMD_JOB_CANCELED; i++)
        if (!strcmp(s, STATE_NAMES[i])) {
            *out = (ismd_job_state)i;
            return true;
        }
    return false;
}

ismd_jobs *ismd_jobs_new(ismd_metrics *metrics)
{
    ismd_jobs *j = calloc(1, sizeof *j);
    if (j)
        j->metrics = metrics;
    return j;
}

static void job_unref(ismd_job *job)
{
    if (--job->refs > 0)
        return;
    ism_blob_unref(job->stats);
    ism_blob_unref(job->error);
    free(job);
}

static size_t bucket_of(const char *id)
{
    size_t h = 5381;
    for (; *id; id++)
        h = h * 33 + (unsigned char)*id;
    return h % NBUCKETS;
}

static juser **juser_slot(ismd_jobs *j, const char *user)
{
    juser **u = &j->users[bucket_of(user) % USER_BUCKETS];
    while (*u && strcmp((*u)->user, user) != 0)
        u = &(*u)->next;
    return u;
}

static size_t user_records(ismd_jobs *j, const char *user)
{
    juser *u = *juser_slot(j, user);
    return u ? u->n : 0;
}

/* Counts one record more (+1) or less (-1) for user; false when out of memory. */
static bool user_count(ismd_jobs *j, const char *user, int delta)
{
    juser **slot = juser_slot(j, user);
    if (!*slot) {
        if (delta < 0 || !(*slot = calloc(1, sizeof **slot)))
            return false;
        snprintf((*slot)->user, sizeof (*slot)->user, "%s", user);
    }
    juser *u = *slot;
    u->n = delta < 0 ? u->n - 1 : u->n + 1;
    if (u->n == 0) {
        *slot = u->next;
        free(u);
    }
    return true;
}

/* The user with the most records (NULL when the table is empty). */
static const char *heaviest_user(const ismd_jobs *j)
{
    const juser *best = NULL;
    for (size_t b = 0; b < USER_BUCKETS; b++)
        for (const juser *u = j->users[b]; u; u = u->next)
            if (!best || u->n > best->n)
                best = u;
    return best ? best->user : NULL;
}

static void table_remove(ismd_jobs *j, ismd_job *job)
{
    user_count(j, job->user, -1);
    ismd_job **p = &j->buckets[bucket_of(job->id)];
    while (*p && *p != job)
        p = &(*p)->hnext;
    if (*p)
        *p = job->hnext;
    if (job->lprev)
        job->lprev->lnext = job->lnext;
    else
        j->oldest = job->lnext;
    if (job->lnext)
        job->lnext->lprev = job->lprev;
    else
        j->newest = job->lprev;
    j->count--;
    job->in_table = false;
    job_unref(job);
}

void ismd_jobs_free(ismd_jobs *j)
{
    while (j->oldest)
        table_remove(j, j->oldest);
    free(j);
}

static bool finished(const ismd_job *job)
{
    return job->state >= ISMD_JOB_DONE;
}

/* Drops expired finished jobs. */
static void sweep(ismd_jobs *j, long long now)
{
    ismd_job *job = j->oldest;
    while (job) {
        ismd_job *next = job->lnext;
        if (finished(job) && now - job->finished_ns > JOB_TTL_NS)
            table_remove(j, job);
        job = next;
    }
}

/* Drops the oldest finished record of user; false when all of its records are live. */
static bool evict_oldest_of(ismd_jobs *j, const char *user)
{
    for (ismd_job *job = j->oldest; job; job = job->lnext)
        if (finished(job) && !strcmp(job->user, user)) {
            table_remove(j, job);
            return true;
        }
    return false;
}

/* Makes room for one more record of user: past its own cap, its own oldest finished record
 * goes; with the whole table full, one of the user holding the most records (the one who
 * filled it). Live (queued or running) records are never dropped. */
static ismd_jobs_refusal make_room(ismd_jobs *j, const char *user)
{
    if (user_records(j, user) >= USER_JOBS_KEPT && !evict_oldest_of(j, user))
        return ISMD_JOBS_USER_FULL;
    if (j->count >= MAX_JOBS) {
        const char *heavy = heaviest_user(j);
        if (!heavy || !evict_oldest_of(j, heavy))
            return ISMD_JOBS_TABLE_FULL;
    }
    return ISMD_JOBS_OK;
}

/* Wakes every suspended stream of job. */
static void notify(ismd_job *job)
{
    job->version++;
    for (stream *st = job->streams; st; st = st->next)
        if (st->suspended) {
            st->suspended = false;
            ism_http_resume(st->loops, st->conn);
        }
}

static void mark_finished(ismd_job *job)
{
    job->finished_ns = ism_now_ns();
    atomic_fetch_sub(&job->owner->metrics->jobs_active, 1);
    notify(job);
}

static void job_progress(ismd_waiter *w, double fraction, bool running)
{
    ismd_job *job = (ismd_job *)w;
    if (running && !job->started_ns && w->flight) {
        job->started_ns = w->flight->started_ns;
        job->started_unix_ms = w->flight->started_unix_ms;
    }
    job->state = running ? ISMD_JOB_RUNNING : ISMD_JOB_QUEUED;
    job->progress = fraction;
    notify(job);
}

static void job_done(ismd_waiter *w, const ismd_result *r)
{
    ismd_job *job = (ismd_job *)w;
    if (r->status == 200) {
        job->state = ISMD_JOB_DONE;
        job->progress = 1;
        ism_blob_set(&job->stats, r->stats);
    } else if (r->status == 499) {
        job->state = ISMD_JOB_CANCELED;
    } else {
        job->state = ISMD_JOB_FAILED;
        job->status = r->status;
        ism_blob_set(&job->error, r->body);
    }
    mark_finished(job);
}

ismd_job *ismd_jobs_create(ismd_jobs *j, const char *key, const char *fmt, const char *user,
                           ismd_jobs_refusal *why)
{
    long long now = ism_now_ns();
    sweep(j, now);
    if ((*why = make_room(j, user)) != ISMD_JOBS_OK)
        return NULL;
    *why = ISMD_JOBS_TABLE_FULL; /* out of memory from here on */
    ismd_job *job = calloc(1, sizeof *job);
    if (!job)
        return NULL;
    unsigned char rnd[16];
    if (getrandom(rnd, sizeof rnd, 0) != (ssize_t)sizeof rnd || !user_count(j, user, +1)) {
        free(job);
        return NULL;
    }
    *why = ISMD_JOBS_OK;
    for (int i = 0; i < 16; i++)
        snprintf(job->id + 2 * i, 3, "%02x", rnd[i]);
    snprintf(job->key, sizeof job->key, "%s", key);
    snprintf(job->fmt, sizeof job->fmt, "%s", fmt);
    snprintf(job->user, sizeof job->user, "%s", user);
    job->owner = j;
    job->state = ISMD_JOB_QUEUED;
    job->created_ns = now;
    job->created_unix = time(NULL);
    job->version = 1;
    job->refs = 1;
    job->in_table = true;
    job->waiter.done = job_done;
    job->waiter.progress = job_progress;
    size_t b = bucket_of(job->id);
    job->hnext = j->buckets[b];
    j->buckets[b] = job;
    job->lprev = j->newest;
    if (j->newest)
        j->newest->lnext = job;
    else
        j->oldest = job;
    j->newest = job;
    j->count++;
    atomic_fetch_add(&j->metrics->jobs_active, 1);
    return job;
}

ismd_waiter *ismd_job_waiter(ismd_job *job)
{
    return &job->waiter;
}

void ismd_jobs_submitted(ismd_job *job)
{
    const ismd_flight *f = job->waiter.flight;
    if (f && f->running) {
        job->state = ISMD_JOB_RUNNING;
        job->progress = f->progress;
        job->started_ns = f->started_ns;
        job->started_unix_ms = f->started_unix_ms;
    }
}

void ismd_jobs_discard(ismd_jobs *j, ismd_job *job)
{
    if (!finished(job))
        atomic_fetch_sub(&j->metrics->jobs_active, 1);
    job->state = ISMD_JOB_CANCELED;
    table_remove(j, job);
}

void ismd_jobs_complete_cached(ismd_jobs *j, ismd_job *job, ism_blob *stats)
{
    (void)j;
    job->state = ISMD_JOB_DONE;
    job->progress = 1;
    ism_blob_set(&job->stats, stats);
    mark_finished(job);
}

ismd_job *ismd_jobs_find(ismd_jobs *j, const char *id)
{
    for (ismd_job *job = j->buckets[bucket_of(id)]; job; job = job->hnext)
        if (!strcmp(job->id, id))
            return job;
    return NULL;
}

const char *ismd_job_id(const ismd_job *job)
{
    return job->id;
}

const char *ismd_job_user(const ismd_job *job)
{
    return job->user;
}

bool ismd_job_canceled(const ismd_job *job)
{
    return job->state == ISMD_JOB_CANCELED;
}

bool ismd_jobs_cancel(ismd_jobs *j, ismd_sched *s, ismd_job *job)
{
    (void)j;
    if (finished(job))
        return false;
    ismd_sched_detach(s, &job->waiter);
    job->state = ISMD_JOB_CANCELED;
    mark_finished(job);
    return true;
}

void ismd_jobs_revoke(ismd_jobs *j, ismd_job *job)
{
    (void)j;
    if (!finished(job) || job->state == ISMD_JOB_CANCELED)
        return;
    job->state = ISMD_JOB_CANCELED;
    job->status = 0;
    ism_blob_set(&job->stats, NULL);
    ism_blob_set(&job->error, NULL);
    notify(job);
}

static json_t *json_from_blob(const ism_blob *b)
{
    return b ? json_loadb((const char *)b->data, b->len, 0, NULL) : NULL;
}

json_t *ismd_job_view_json(const ismd_job_view *v)
{
    char url[128];
    json_t *o = json_object();
    if (!o)
        return NULL;
    json_object_set_new(o, "id", json_string(v->id));
    json_object_set_new(o, "state", json_string(STATE_NAMES[v->state]));
    json_object_set_new(o, "progress", json_real(v->progress));
    json_object_set_new(o, "key", json_string(v->key));
    json_object_set_new(o, "format", json_string(v->fmt));
    char created[32];
    struct tm tm;
    gmtime_r(&v->created_unix, &tm);
    strftime(created, sizeof created, "%Y-%m-%dT%H:%M:%SZ", &tm);
    json_object_set_new(o, "created", json_string(created));
    json_object_set_new(o, "user", json_string(v->user));
    if (v->started_unix_ms) {
        long long ms = v->started_unix_ms;
        time_t secs = (time_t)(ms / 1000);
        char started[40], whole[32];
        gmtime_r(&secs, &tm);
        strftime(whole, sizeof whole, "%Y-%m-%dT%H:%M:%S", &tm);
        snprintf(started, sizeof started, "%s.%03dZ", whole, (int)(ms % 1000));
        json_object_set_new(o, "started", json_string(started));
        json_object_set_new(o, "queue_ms", json_real(v->queue_ms));
    }
    snprintf(url, sizeof url, "/v1/jobs/%s", v->id);
    json_object_set_new(o, "url", json_string(url));
    snprintf(url, sizeof url, "/v1/jobs/%s/events", v->id);
    json_object_set_new(o, "events_url", json_string(url));
    if (v->state == ISMD_JOB_DONE) {
        snprintf(url, sizeof url, "/v1/meshes/%s.%s", v->key, v->fmt);
        json_object_set_new(o, "mesh_url", json_string(url));
        snprintf(url, sizeof url, "/v1/meshes/%s/stats", v->key);
        json_object_set_new(o, "stats_url", json_string(url));
        snprintf(url, sizeof url, "/v1/meshes/%s/features", v->key);
        json_object_set_new(o, "features_url", json_string(url));
        json_t *stats = json_from_blob(v->stats);
        if (stats)
            json_object_set_new(o, "stats", stats);
    }
    if (v->state == ISMD_JOB_FAILED) {
        json_object_set_new(o, "status", json_integer(v->status));
        json_t *err = json_from_blob(v->error);
        json_t *inner = err ? json_object_get(err, "error") : NULL;
        if (inner)
            json_object_set(o, "error", inner);
        json_decref(err);
    }
    return o;
}

json_t *ismd_job_json(const ismd_job *job)
{
    ismd_job_view v = {
        .id = job->id, .key = job->key, .fmt = job->fmt, .user = job->user,
        .state = job->state, .progress = job->progress, .created_unix = job->created_unix,
        .started_unix_ms = job->started_ns ? job->started_unix_ms : 0,
        .queue_ms = (job->started_ns - job->created_ns) / 1e6,
        .status = job->status, .stats = job->stats, .error = job->error,
    };
    return ismd_job_view_json(&v);
}

json_t *ismd_jobs_list_json(const ismd_jobs *j, const char *user, size_t max)
{
    json_t *list = json_array();
    json_t *o = list ? json_pack("{s:o}", "jobs", list) : NULL;
    if (!o)
        return NULL;
    bool truncated = false;
    for (const ismd_job *job = j->newest; job; job = job->lprev) {
        if (user && strcmp(job->user, user) != 0)
            continue;
        if (json_array_size(list) == max) {
            truncated = true;
            break;
        }
        json_t *one = ismd_job_json(job);
        if (one)
            json_object_del(one, "stats");
        if (!one || json_array_append_new(list, one) != 0) {
            json_decref(o);
            return NULL;
        }
    }
    json_object_set_new(o, "truncated", json_boolean(truncated));
    return o;
}

/* ---- event streams ------------------------------------------------------------------- */

/* Formats the job's current state as one event into st->pending. */
static bool format_event(stream *st)
{
    const ismd_job *job = st->job;
    json_t *data;
    if (finished(job)) {
        data = ismd_job_json(job);
    } else {
        data = json_pack("{s:s, s:s, s:f}", "id", job->id, "state", STATE_NAMES[job->state],
                         "progress", job->progress);
    }
    char *text = data ? json_dumps(data, JSON_COMPACT) : NULL;
    json_decref(data);
    if (!text)
        return false;
    const char *name = finished(job) ? STATE_NAMES[job->state] : "progress";
    size_t cap = strlen(text) + strlen(name) + 32;
    free(st->pending);
    st->pending = malloc(cap);
    if (!st->pending) {
        free(text);
        return false;
    }
    int n = snprintf(st->pending, cap, "event: %s\ndata: %s\n\n", name, text);
    free(text);
    st->pending_len = n > 0 ? (size_t)n : 0;
    st->pending_off = 0;
    return true;
}

static ssize_t stream_read(void *cls, uint64_t pos, char *buf, size_t max)
{
    (void)pos;
    stream *st = cls;
    ssize_t n;
    ismd_sched_lock(st->sched);
    for (;;) {
        if (st->pending_off < st->pending_len) {
            size_t k = st->pending_len - st->pending_off;
            if (k > max)
                k = max;
            memcpy(buf, st->pending + st->pending_off, k);
            st->pending_off += k;
            n = (ssize_t)k;
            break;
        }
        if (st->finished) {
            n = MHD_CONTENT_READER_END_OF_STREAM;
            break;
        }
        if (st->job->version != st->sent_version) {
            st->sent_version = st->job->version;
            if (finished(st->job))
                st->finished = true;
            if (!format_event(st)) {
                n = MHD_CONTENT_READER_END_WITH_ERROR;
                break;
            }
            continue;
        }
        if (st->jobs->closing) {
            n = MHD_CONTENT_READER_END_OF_STREAM;
            break;
        }
        st->suspended = true; /* resumed by notify() or ismd_jobs_close_streams() */
        MHD_suspend_connection(st->conn);
        n = 0;
        break;
    }
    ismd_sched_unlock(st->sched);
    return n;
}

static void stream_free(void *cls)
{
    stream *st = cls;
    ismd_sched_lock(st->sched);
    stream **p = &st->job->streams;
    while (*p && *p != st)
        p = &(*p)->next;
    if (*p)
        *p = st->next;
    atomic_fetch_sub(&st->jobs->metrics->event_streams, 1);
    job_unref(st->job);
    ismd_sched_unlock(st->sched);
    free(st->pending);
    free(st);
}

struct MHD_Response *ismd_jobs_stream(ismd_jobs *j, ismd_sched *s, ismd_job *job,
                                      struct MHD_Connection *conn, ism_http_loops *loops)
{
    stream *st = calloc(1, sizeof *st);
    if (!st)
        return NULL;
    st->job = job;
    st->jobs = j;
    st->sched = s;
    st->conn = conn;
    st->loops = loops;
    st->sent_version = job->version - 1; /* the first read sends the current state */
    struct MHD_Response *resp =
        MHD_create_response_from_callback(MHD_SIZE_UNKNOWN, 4096, stream_read, st, stream_free);
    if (!resp) {
        free(st);
        return NULL;
    }
    job->refs++;
    st->next = job->streams;
    job->streams = st;
    atomic_fetch_add(&j->metrics->event_streams, 1);
    MHD_add_response_header(resp, MHD_HTTP_HEADER_CONTENT_TYPE, "text/event-stream");
    MHD_add_response_header(resp, MHD_HTTP_HEADER_CACHE_CONTROL, "no-store");
    MHD_add_response_header(resp, "X-Accel-Buffering", "no");
    return resp;
}

void ismd_jobs_close_streams(ismd_jobs *j)
{
    j->closing = true;
    for (ismd_job *job = j->oldest; job; job = job->lnext)
        for (stream *st = job->streams; st; st = st->next)
            if (st->suspended) {
                st->suspended = false;
                ism_http_resume(st->loops, st->conn);
            }
}
