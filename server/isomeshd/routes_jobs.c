/* routes_jobs.c — the job routes: POST /v1/jobs (202 with the job), GET /v1/jobs (the
 * caller's jobs; every job for an admin token), GET /v1/jobs/{id}, DELETE /v1/jobs/{id}
 * (cancel: its owner or an admin when tokens are on), GET /v1/jobs/{id}/events (server-sent
 * events). With --cluster, a job this daemon does not hold is looked up in Redis (cluster.h):
 * GET /v1/jobs/{id}, its events and DELETE work through any daemon of the service (a DELETE
 * there lets go of that job only, as on the daemon holding it). */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "server/isomeshd/cluster.h"
#include "server/isomeshd/flight_wait.h"
#include "server/isomeshd/http_types.h"
#include "server/isomeshd/respond.h"
#include "server/isomeshd/routes.h"
#include "server/isomeshd/jobs.h"
#include "server/isomeshd/shared_cache.h"

#define JOBS_LIST_MAX 500 /* newest jobs shown by GET /v1/jobs */
#define REMOTE_EVENTS_RETRY_MS 1000 /* an event stream of another daemon's job is one event
                                       (its state now); the browser asks again this soon */

/* Answers with the job's JSON (lock held by the caller: the JSON is built under it). */
static enum MHD_Result answer_job_locked(ismd_req *r, unsigned status, ismd_job *job,
                                         bool location)
{
    json_t *o = ismd_job_json(job);
    char *text = o ? json_dumps(o, JSON_COMPACT) : NULL;
    json_decref(o);
    char loc[80];
    snprintf(loc, sizeof loc, "/v1/jobs/%s", ismd_job_id(job));
    ismd_sched_unlock(&r->srv->sched);
    if (!text)
        return MHD_NO;
    ism_blob *b = ism_blob_from_str(text);
    free(text);
    if (!b)
        return MHD_NO;
    struct MHD_Response *resp = ismd_response_blob(b, "application/json");
    r->bytes = b->len;
    ism_blob_unref(b);
    if (!resp)
        return MHD_NO;
    if (location)
        MHD_add_response_header(resp, MHD_HTTP_HEADER_LOCATION, loc);
    MHD_add_response_header(resp, MHD_HTTP_HEADER_CACHE_CONTROL, "no-store");
    return ismd_send(r, status, resp);
}

/* 200 with o as the body, never cached. */
static enum MHD_Result send_json(ismd_req *r, const json_t *o)
{
    char *text = json_dumps(o, JSON_COMPACT);
    ism_blob *b = text ? ism_blob_from_str(text) : NULL;
    free(text);
    struct MHD_Response *resp = b ? ismd_response_blob(b, "application/json") : NULL;
    r->bytes = b ? b->len : 0;
    ism_blob_unref(b);
    if (!resp)
        return MHD_NO;
    MHD_add_response_header(resp, MHD_HTTP_HEADER_CACHE_CONTROL, "no-store");
    return ismd_send(r, 200, resp);
}

static enum MHD_Result job_not_found(ismd_req *r)
{
    return ismd_respond_error(r, 404, "unknown_job", "no job with this id (finished jobs are "
                                                     "kept for 30 minutes)");
}

/* 202 for a new job (lock held, released); with --cluster it is recorded in Redis too, so
 * that every daemon can answer for it. */
static enum MHD_Result accepted_locked(ismd_req *r, ismd_job *job)
{
    return answer_job_locked(r, 202, job, true);
}

ismd_job *ismd_job_start(ismd_req *r, ism_blob *canonical, ismd_job_refusal *why)
{
    ismd_server *s = r->srv;
    char name[ISM_CACHE_NAME_MAX], sname[ISM_CACHE_NAME_MAX];
    ism_cache_name(name, r->key, r->fmt);
    ism_cache_name(sname, r->key, "stats.json");
    ism_blob *hit = ism_cache_get(&s->cache, name, NULL);
    ism_blob *stats = hit ? ism_cache_get(&s->cache, sname, NULL) : NULL;
    atomic_fetch_add(hit ? &s->metrics.mesh_hits : &s->metrics.mesh_misses, 1);
    r->cache = hit ? "hit" : "miss";

    ismd_sched_lock(&s->sched);
    ismd_jobs_refusal full;
    ismd_job *job = ismd_jobs_create(s->jobs, r->key, r->fmt, r->who.user, &full);
    if (!job) {
        ismd_sched_unlock(&s->sched);
        ism_blob_unref(hit);
        ism_blob_unref(stats);
        why->submit = full == ISMD_JOBS_USER_FULL ? ISMD_SUBMIT_CLIENT_LIMIT : ISMD_SUBMIT_QUEUE_FULL;
        why->table_full = true;
        return NULL;
    }
    if (hit) {
        ismd_jobs_complete_cached(s->jobs, job, stats);
    } else {
        ismd_user_limits lim = {r->who.max_jobs, r->who.max_running};
        ismd_submit st = ismd_sched_submit(&s->sched, r->key, r->fmt, canonical, r->who.user,
                                           &lim, ismd_job_waiter(job));
        if (st != ISMD_SUBMIT_NEW && st != ISMD_SUBMIT_JOINED) {
            ismd_jobs_discard(s->jobs, job);
            ismd_sched_unlock(&s->sched);
            why->submit = st;
            why->table_full = false;
            return NULL;
        }
        ismd_jobs_submitted(job);
    }
    ism_blob_unref(hit);
    ism_blob_unref(stats);
    ismd_cluster *cluster = ismd_shared_cluster(s->shared);
    if (cluster)
        ismd_cluster_job_created(cluster, ismd_job_id(job), r->who.user, r->key, r->fmt,
                                 (long long)time(NULL));
    return job;
}

enum MHD_Result ismd_respond_job_refused(ismd_req *r, const ismd_job_refusal *why)
{
    if (!why->table_full)
        return ismd_respond_refused(r, why->submit);
    if (why->submit == ISMD_SUBMIT_CLIENT_LIMIT)
        return ismd_respond_error(r, 429, "too_many_jobs",
                                  "every job record you may keep is a live job; wait for "
                                  "one to finish");
    return ismd_respond_error(r, 503, "too_many_jobs", "the job table is full; retry later");
}

enum MHD_Result ismd_route_jobs_post(ismd_req *r)
{
    enum MHD_Result ret;
    ism_blob *canonical = ismd_keyed_request(r, &ret);
    if (!canonical)
        return ret;
    ismd_job_refusal why;
    ismd_job *job = ismd_job_start(r, canonical, &why);
    ism_blob_unref(canonical);
    if (!job)
        return ismd_respond_job_refused(r, &why);
    return accepted_locked(r, job);
}

enum MHD_Result ismd_route_jobs_list(ismd_req *r)
{
    ismd_server *s = r->srv;
    bool all = s->auth->enabled && r->who.admin;
    ismd_sched_lock(&s->sched);
    json_t *o = ismd_jobs_list_json(s->jobs, all ? NULL : r->who.user, JOBS_LIST_MAX);
    ismd_sched_unlock(&s->sched);
    if (o) {
        json_object_set_new(o, "user", json_string(r->who.user));
        json_object_set_new(o, "admin", json_boolean(all));
    }
    enum MHD_Result ret = o ? send_json(r, o) : MHD_NO;
    json_decref(o);
    return ret;
}

/* Under --private a job is seen only by its owner or an admin; canceling needs that always
 * (with tokens on). Answers the 403 itself (lock released) and returns false. */
static bool may_touch(ismd_req *r, ismd_job *job, bool cancel, enum MHD_Result *ret)
{
    ismd_auth *a = r->srv->auth;
    if ((cancel || a->private_mode) && !ismd_auth_owns(a, &r->who, ismd_job_user(job))) {
        ismd_sched_unlock(&r->srv->sched);
        *ret = ismd_respond_error(r, 403, "not_your_job",
                                  "this job belongs to another user (an admin token may touch it)");
        return false;
    }
    return true;
}

/* ---- another daemon's job (--cluster) ----------------------------------------------- */

/* One server-sent event with the job's state now, and a retry delay: the client's
 * EventSource reconnects, through any daemon, until the final event. */
static enum MHD_Result answer_remote_events(ismd_req *r, json_t *o)
{
    const char *state = json_string_value(json_object_get(o, "state"));
    bool final = state && strcmp(state, "queued") != 0 && strcmp(state, "running") != 0;
    char *data = json_dumps(o, JSON_COMPACT);
    size_t cap = (data ? strlen(data) : 0) + 96;
    char *text = data ? malloc(cap) : NULL;
    if (text)
        snprintf(text, cap, "retry: %d\nevent: %s\ndata: %s\n\n", REMOTE_EVENTS_RETRY_MS,
                 final ? state : "progress", data);
    free(data);
    struct MHD_Response *resp = text ? ismd_response_text(text, "text/event-stream") : NULL;
    r->bytes = text ? strlen(text) : 0;
    free(text);
    if (!resp)
        return MHD_NO;
    MHD_add_response_header(resp, MHD_HTTP_HEADER_CACHE_CONTROL, "no-store");
    return ismd_send(r, 200, resp);
}

/* DELETE of another daemon's job: a live one is deleted (its daemon lets go of it, cluster.h)
 * and answered as canceled (a finished one as it is, like a local one). */
static enum MHD_Result cancel_remote(ismd_req *r, json_t *o)
{
    const char *state = json_string_value(json_object_get(o, "state"));
    if (state && (!strcmp(state, "queued") || !strcmp(state, "running"))) {
        ismd_cluster_job_delete(ismd_shared_cluster(r->srv->shared), r->id);
        json_object_set_new(o, "state", json_string("canceled"));
    }
    return send_json(r, o);
}

/* The lookup in Redis answered (r->r_status, r->r_body). */
static enum MHD_Result remote_job_ready(ismd_req *r)
{
    if (r->r_status == 404 || !r->r_body)
        return r->r_status == 503 ? ismd_respond_error(r, 503, "redis_unavailable",
                                                       "the service's Redis did not answer; "
                                                       "retry later")
                                  : job_not_found(r);
    json_t *o = json_loadb((const char *)r->r_body->data, r->r_body->len, 0, NULL);
    const char *user = json_string_value(json_object_get(o, "user"));
    bool cancel = !strcmp(r->method, "DELETE");
    ismd_auth *a = r->srv->auth;
    enum MHD_Result ret;
    if (!o)
        ret = MHD_NO;
    else if ((cancel || a->private_mode) && !(user && ismd_auth_owns(a, &r->who, user)))
        ret = ismd_respond_error(r, 403, "not_your_job",
                                 "this job belongs to another user (an admin token may touch it)");
    else if (r->route == ISMD_R_JOB_EVENTS)
        ret = answer_remote_events(r, o);
    else if (cancel)
        ret = cancel_remote(r, o);
    else {
        struct MHD_Response *resp = ismd_response_blob(r->r_body, "application/json");
        r->bytes = r->r_body->len;
        if (resp)
            MHD_add_response_header(resp, MHD_HTTP_HEADER_CACHE_CONTROL, "no-store");
        ret = resp ? ismd_send(r, 200, resp) : MHD_NO;
    }
    json_decref(o);
    return ret;
}

/* Not a job of this daemon: with --cluster, suspends the request while Redis is asked (lock
 * held on entry, released here). False without a cluster (nothing done, lock still held). */
static bool ask_cluster(ismd_req *r, enum MHD_Result *ret)
{
    ismd_server *s = r->srv;
    ismd_cluster *c = ismd_shared_cluster(s->shared);
    if (!c)
        return false;
    r->on_ready = remote_job_ready;
    r->waiter.done = ismd_req_done;
    r->waiter.progress = NULL;
    if (!ismd_cluster_job_lookup(c, r->id, &r->waiter)) {
        ismd_sched_unlock(&s->sched);
        *ret = ismd_respond_error(r, 503, "shutting_down", "the server is shutting down");
        return true;
    }
    /* the lookup answers under the lock: never before this suspension */
    r->suspended = true;
    atomic_fetch_add(&s->metrics.suspended_connections, 1);
    MHD_suspend_connection(r->conn);
    ismd_sched_unlock(&s->sched);
    *ret = MHD_YES;
    return true;
}

/* The request's job with the scheduler locked: returns it with the lock held, or NULL with
 * the lock released and *ret the answer given (404 unknown, 403 not the caller's; with
 * remote: another daemon's job asked for through Redis). */
static ismd_job *touch_job(ismd_req *r, bool cancel, bool remote, enum MHD_Result *ret)
{
    ismd_sched_lock(&r->srv->sched);
    ismd_job *job = ismd_jobs_find(r->srv->jobs, r->id);
    if (!job) {
        if (remote && ask_cluster(r, ret))
            return NULL;
        ismd_sched_unlock(&r->srv->sched);
        *ret = job_not_found(r);
        return NULL;
    }
    return may_touch(r, job, cancel, ret) ? job : NULL;
}

enum MHD_Result ismd_route_job_get(ismd_req *r)
{
    enum MHD_Result ret;
    ismd_job *job = touch_job(r, false, true, &ret);
    return job ? answer_job_locked(r, 200, job, false) : ret;
}

enum MHD_Result ismd_route_job_delete(ismd_req *r)
{
    enum MHD_Result ret;
    ismd_job *job = touch_job(r, true, true, &ret);
    if (!job)
        return ret;
    ismd_jobs_cancel(r->srv->jobs, &r->srv->sched, job);
    return answer_job_locked(r, 200, job, false);
}

enum MHD_Result ismd_route_job_events(ismd_req *r)
{
    ismd_server *s = r->srv;
    enum MHD_Result ret;
    ismd_job *job = touch_job(r, false, true, &ret);
    if (!job)
        return ret;
    struct MHD_Response *resp = ismd_jobs_stream(s->jobs, &s->sched, job, r->conn, s->loops);
    ismd_sched_unlock(&s->sched);
    if (!resp)
        return MHD_NO;
    return ismd_send(r, 200, resp);
}
