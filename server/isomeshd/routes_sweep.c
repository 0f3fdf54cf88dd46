/* routes_sweep.c — POST /v1/sweep: one base request and a grid of parameter values, answered
 * with one job per point of the grid (202; the jobs are those of POST /v1/jobs, each with its
 * "params"). Body: {"request": {...}, "grid": {"NAME": [v0, v1, ...], ...}}; ?format= applies
 * to every point. Every point is decoded and keyed before any job starts, so a bad point
 * refuses the whole sweep (400/422 naming the point); a refusal by the job table or the queue
 * cancels the jobs already started (all or nothing). At most SWEEP_MAX_POINTS points. */
#include <jansson.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "server/isomeshd/http_types.h"
#include "server/isomeshd/respond.h"
#include "server/isomeshd/routes.h"
#include "server/isomeshd/jobs.h"

/* Points per sweep: each one is a job record and (unless cached) a computation, and a user's
 * share of those is bounded anyway (--user-jobs); 64 covers an 8 x 8 grid. */
#define SWEEP_MAX_POINTS 64
/* Parameters varied at once (a grid over more is a mistake, not a study). */
#define SWEEP_MAX_AXES 4

typedef struct point {
    char key[65], fmt[8];
    ism_blob *canonical;
    json_t *params;            /* this point's values */
} point;

static enum MHD_Result bad(ismd_req *r, unsigned status, const char *msg)
{
    return ismd_respond_error(r, status, status == 422 ? "over_limit" : "bad_request", msg);
}

/* The grid's axes, checked: names and arrays of finite numbers. Number of points, 0 when
 * refused (answered). */
static size_t check_grid(ismd_req *r, json_t *grid, enum MHD_Result *ret)
{
    if (!json_is_object(grid) || json_object_size(grid) == 0) {
        *ret = bad(r, 400, "$.grid: expected an object of parameter names to arrays of numbers");
        return 0;
    }
    if (json_object_size(grid) > SWEEP_MAX_AXES) {
        *ret = bad(r, 422, "$.grid: at most 4 parameters vary in one sweep");
        return 0;
    }
    size_t points = 1;
    const char *name;
    json_t *values;
    json_object_foreach(grid, name, values) {
        size_t n = json_is_array(values) ? json_array_size(values) : 0;
        char msg[200];
        for (size_t i = 0; i < n; i++)
            if (!json_is_number(json_array_get(values, i)))
                n = 0;
        if (n == 0) {
            snprintf(msg, sizeof msg, "$.grid.%.60s: expected a non-empty array of numbers", name);
            *ret = bad(r, 400, msg);
            return 0;
        }
        points *= n;
        if (points > SWEEP_MAX_POINTS) {
            snprintf(msg, sizeof msg, "$.grid: more than %d points", SWEEP_MAX_POINTS);
            *ret = bad(r, 422, msg);
            return 0;
        }
    }
    return points;
}

/* Point k of the grid (mixed radix, the first axis slowest): the base request with its
 * params set. Keyed into p; false when refused (answered, naming the point). */
static bool make_point(ismd_req *r, json_t *base, json_t *grid, size_t k, point *p,
                       enum MHD_Result *ret)
{
    json_t *req = json_deep_copy(base);
    json_t *params = json_object_get(req, "params");
    if (!params) {
        params = json_object();
        json_object_set_new(req, "params", params);
    }
    p->params = json_object();
    size_t stride = SIZE_MAX, rest = k; /* k's digits, the first axis the most significant */
    size_t total = 1;
    const char *name;
    json_t *values;
    json_object_foreach(grid, name, values) total *= json_array_size(values);
    stride = total;
    json_object_foreach(grid, name, values) {
        stride /= json_array_size(values);
        json_t *v = json_array_get(values, rest / stride);
        rest %= stride;
        json_object_set(params, name, v);
        json_object_set(p->params, name, v);
    }
    char *text = json_dumps(req, JSON_COMPACT);
    json_decref(req);
    ism_pipeline_result pr;
    memset(&pr, 0, sizeof pr);
    const char *fmt = ismd_query(r, "format");
    bool ok = text && ism_pipeline_key(text, strlen(text), fmt, &r->srv->limits, &pr);
    free(text);
    if (!ok) {
        char msg[600];
        ism_blob *b = pr.body.len ? ism_blob_copy(pr.body.data, pr.body.len) : NULL;
        json_t *e = b ? json_loadb((const char *)b->data, b->len, 0, NULL) : NULL;
        const char *m = json_string_value(json_object_get(json_object_get(e, "error"), "message"));
        snprintf(msg, sizeof msg, "grid point %zu: %s", k, m ? m : "not accepted");
        unsigned status = pr.status == 422 ? 422 : 400;
        *ret = bad(r, status, msg);
        json_decref(e);
        ism_blob_unref(b);
        ism_pipeline_result_free(&pr);
        return false;
    }
    snprintf(p->key, sizeof p->key, "%s", pr.key);
    snprintf(p->fmt, sizeof p->fmt, "%s", pr.format);
    p->canonical = ism_blob_copy(pr.canonical.data, pr.canonical.len);
    ism_pipeline_result_free(&pr);
    return p->canonical != NULL;
}

static void free_points(point *pts, size_t n)
{
    for (size_t i = 0; i < n; i++) {
        ism_blob_unref(pts[i].canonical);
        json_decref(pts[i].params);
    }
    free(pts);
}

/* Starts every point's job; their JSON into jobs. All or nothing: a refusal cancels the jobs
 * started before it and is answered. */
static bool start_all(ismd_req *r, point *pts, size_t n, json_t *jobs, enum MHD_Result *ret)
{
    ismd_job **started = calloc(n, sizeof *started);
    if (!started) {
        *ret = MHD_NO;
        return false;
    }
    for (size_t i = 0; i < n; i++) {
        snprintf(r->key, sizeof r->key, "%s", pts[i].key);
        snprintf(r->fmt, sizeof r->fmt, "%s", pts[i].fmt);
        ismd_job_refusal why;
        started[i] = ismd_job_start(r, pts[i].canonical, &why);
        if (!started[i]) {
            ismd_sched_lock(&r->srv->sched);
            for (size_t j = 0; j < i; j++)
                ismd_jobs_cancel(r->srv->jobs, &r->srv->sched, started[j]);
            ismd_sched_unlock(&r->srv->sched);
            free(started);
            *ret = ismd_respond_job_refused(r, &why);
            return false;
        }
        json_t *o = ismd_job_json(started[i]);
        ismd_sched_unlock(&r->srv->sched);
        if (o) {
            json_object_set(o, "params", pts[i].params);
            json_array_append_new(jobs, o);
        }
    }
    free(started);
    return true;
}

enum MHD_Result ismd_route_sweep(ismd_req *r)
{
    json_error_t jerr;
    json_t *body = json_loadb(r->body ? r->body : "", r->body_len, JSON_REJECT_DUPLICATES, &jerr);
    json_t *base = json_object_get(body, "request"), *grid = json_object_get(body, "grid");
    enum MHD_Result ret = MHD_NO;
    if (!json_is_object(body) || !json_is_object(base) || json_object_size(body) != 2) {
        json_decref(body);
        return bad(r, 400, "expected {\"request\": {...}, \"grid\": {\"NAME\": [numbers]}}");
    }
    size_t n = check_grid(r, grid, &ret);
    point *pts = n ? calloc(n, sizeof *pts) : NULL;
    bool ok = pts != NULL;
    for (size_t k = 0; ok && k < n; k++)
        ok = make_point(r, base, grid, k, &pts[k], &ret);
    json_t *jobs = json_array();
    if (ok)
        ok = start_all(r, pts, n, jobs, &ret);
    if (ok) {
        json_t *o = json_pack("{s:I, s:O}", "count", (json_int_t)n, "jobs", jobs);
        char *text = o ? json_dumps(o, JSON_COMPACT) : NULL;
        ret = text ? ismd_respond_json(r, 202, text) : MHD_NO;
        free(text);
        json_decref(o);
    }
    json_decref(jobs);
    json_decref(body);
    if (pts)
        free_points(pts, n);
    return ret;
}
