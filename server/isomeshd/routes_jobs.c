/* routes_jobs.c — the job routes: POST /v1/jobs (202 with the job), GET /v1/jobs (the
 * caller's jobs; every job for an admin token), GET /v1/jobs/{id}, DELETE /v1/jobs/{id}
 * (cancel: its owner or an admin when tokens are on), GET /v1/jobs/{id}/events (server-sent
 * events). */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "server/isomeshd/http.h"
#include "server/isomeshd/jobs.h"

#define JOBS_LIST_MAX 500 /* newest jobs shown by GET /v1/jobs */

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

static enum MHD_Result job_not_found(ismd_req *r)
{
    return ismd_respond_error(r, 404, "unknown_job", "no job with this id (finished jobs are "
                                                     "kept for 30 minutes)");
}

enum MHD_Result ismd_route_jobs_post(ismd_req *r)
{
    ismd_server *s = r->srv;
    enum MHD_Result ret;
    ism_blob *canonical = ismd_keyed_request(r, &ret);
    if (!canonical)
        return ret;

    char name[ISM_CACHE_NAME_MAX], sname[ISM_CACHE_NAME_MAX];
    ism_cache_name(name, r->key, r->fmt);
    ism_cache_name(sname, r->key, "stats.json");
    ism_blob *hit = ism_cache_get(&s->cache, name, NULL);
    ism_blob *stats = hit ? ism_cache_get(&s->cache, sname, NULL) : NULL;
    atomic_fetch_add(hit ? &s->metrics.mesh_hits : &s->metrics.mesh_misses, 1);
    r->cache = hit ? "hit" : "miss";

    ismd_sched_lock(&s->sched);
    ismd_jobs_refusal why;
    ismd_job *job = ismd_jobs_create(s->jobs, r->key, r->fmt, r->who.user, &why);
    if (!job) {
        ismd_sched_unlock(&s->sched);
        ism_blob_unref(hit);
        ism_blob_unref(stats);
        ism_blob_unref(canonical);
        if (why == ISMD_JOBS_USER_FULL)
            return ismd_respond_error(r, 429, "too_many_jobs",
                                      "every job record you may keep is a live job; wait for "
                                      "one to finish");
        return ismd_respond_error(r, 503, "too_many_jobs", "the job table is full; retry later");
    }
    if (hit) {
        ismd_jobs_complete_cached(s->jobs, job, stats);
        ism_blob_unref(hit);
        ism_blob_unref(stats);
        ism_blob_unref(canonical);
        return answer_job_locked(r, 202, job, true);
    }
    ismd_user_limits lim = {r->who.max_jobs, r->who.max_running};
    ismd_submit st = ismd_sched_submit(&s->sched, r->key, r->fmt, canonical, r->who.user, &lim,
                                       ismd_job_waiter(job));
    ism_blob_unref(canonical);
    if (st == ISMD_SUBMIT_NEW || st == ISMD_SUBMIT_JOINED) {
        ismd_jobs_submitted(job);
        return answer_job_locked(r, 202, job, true);
    }
    ismd_jobs_discard(s->jobs, job);
    ismd_sched_unlock(&s->sched);
    return ismd_respond_refused(r, st);
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
    char *text = o ? json_dumps(o, JSON_COMPACT) : NULL;
    json_decref(o);
    if (!text)
        return MHD_NO;
    ism_blob *b = ism_blob_from_str(text);
    free(text);
    struct MHD_Response *resp = b ? ismd_response_blob(b, "application/json") : NULL;
    r->bytes = b ? b->len : 0;
    ism_blob_unref(b);
    if (!resp)
        return MHD_NO;
    MHD_add_response_header(resp, MHD_HTTP_HEADER_CACHE_CONTROL, "no-store");
    return ismd_send(r, 200, resp);
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

/* The request's job with the scheduler locked: returns it with the lock held, or NULL with
 * the lock released and *ret the answer given (404 unknown, 403 not the caller's). */
static ismd_job *touch_job(ismd_req *r, bool cancel, enum MHD_Result *ret)
{
    ismd_sched_lock(&r->srv->sched);
    ismd_job *job = ismd_jobs_find(r->srv->jobs, r->id);
    if (!job) {
        ismd_sched_unlock(&r->srv->sched);
        *ret = job_not_found(r);
        return NULL;
    }
    return may_touch(r, job, cancel, ret) ? job : NULL;
}

enum MHD_Result ismd_route_job_get(ismd_req *r)
{
    enum MHD_Result ret;
    ismd_job *job = touch_job(r, false, &ret);
    return job ? answer_job_locked(r, 200, job, false) : ret;
}

enum MHD_Result ismd_route_job_delete(ismd_req *r)
{
    enum MHD_Result ret;
    ismd_job *job = touch_job(r, true, &ret);
    if (!job)
        return ret;
    ismd_jobs_cancel(r->srv->jobs, &r->srv->sched, job);
    return answer_job_locked(r, 200, job, false);
}

enum MHD_Result ismd_route_job_events(ismd_req *r)
{
    ismd_server *s = r->srv;
    enum MHD_Result ret;
    ismd_job *job = touch_job(r, false, &ret);
    if (!job)
        return ret;
    struct MHD_Response *resp = ismd_jobs_stream(s->jobs, &s->sched, job, r->conn);
    ismd_sched_unlock(&s->sched);
    if (!resp)
        return MHD_NO;
    return ismd_send(r, 200, resp);
}
