/* flight_wait.c — a request that needs a computation (flight_wait.h): its body turned into
 * the canonical, keyed request, the flight joined or started and the connection suspended,
 * and the result kept and the connection resumed when the flight ends. */
#include "server/isomeshd/flight_wait.h"

#include <jansson.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "server/common/http_loops.h"
#include "server/isomeshd/respond.h"

void ismd_req_done(ismd_waiter *w, const ismd_result *res)
{
    ismd_req *r = (ismd_req *)((char *)w - offsetof(ismd_req, waiter));
    r->r_status = res->status;
    ism_blob_set(&r->r_body, res->body);
    ism_blob_set(&r->r_stats, res->stats);
    ism_blob_set(&r->r_features, res->features);
    r->r_ctype = res->content_type;
    r->queue_ms = res->queue_ms;
    r->worker_ms = res->worker_ms;
    snprintf(r->timing, sizeof r->timing, "%s", res->timing);
    if (res->cache)
        r->cache = res->cache; /* "shared": another daemon computed it */
    r->ready = true;
    if (r->suspended) {
        r->suspended = false;
        atomic_fetch_sub(&r->srv->metrics.suspended_connections, 1);
        ism_http_resume(r->srv->loops, r->conn);
    }
}

enum MHD_Result ismd_wait_for(ismd_req *r, const char *key, const char *fmt,
                              ism_blob *request, ismd_handler on_ready)
{
    ismd_server *s = r->srv;
    char wanted[ISM_CACHE_NAME_MAX];
    const char *ext = r->want == ISMD_WANT_STATS      ? "stats.json"
                      : r->want == ISMD_WANT_FEATURES ? "features.json"
                                                      : fmt;
    if (!ism_cache_name(wanted, key, ext))
        return ismd_respond_error(r, 500, "internal", "bad cache name");
    bool may_compute = !ismd_auth_lacking(s->auth, &r->who);
    r->on_ready = on_ready;
    r->waiter.done = ismd_req_done;
    r->waiter.progress = NULL;
    ismd_sched_lock(&s->sched);
    /* The flight may have ended between the caller's cache lookup and this lock. */
    ism_blob *hit = ism_cache_get_fast(&s->cache, wanted);
    if (hit) {
        ismd_sched_unlock(&s->sched);
        r->r_status = 200;
        ism_blob **slot = r->want == ISMD_WANT_STATS      ? &r->r_stats
                          : r->want == ISMD_WANT_FEATURES ? &r->r_features
                                                          : &r->r_body;
        ism_blob_set(slot, hit);
        ism_blob_unref(hit);
        r->r_ctype = r->want == ISMD_WANT_MESH ? NULL : "application/json";
        r->cache = "hit";
        return on_ready(r);
    }
    if (!may_compute) { /* not cached: computing it needs a token */
        ismd_sched_unlock(&s->sched);
        return ismd_respond_unauthorized(r);
    }
    ismd_user_limits lim = {r->who.max_jobs, r->who.max_running};
    ismd_submit st = ismd_sched_submit(&s->sched, key, fmt, request, r->who.user, &lim, &r->waiter);
    if (st == ISMD_SUBMIT_NEW || st == ISMD_SUBMIT_JOINED) {
        r->suspended = true;
        r->cache = "miss";
        atomic_fetch_add(&s->metrics.suspended_connections, 1);
        MHD_suspend_connection(r->conn);
        ismd_sched_unlock(&s->sched);
        return MHD_YES;
    }
    ismd_sched_unlock(&s->sched);
    return ismd_respond_refused(r, st);
}

/* ?draco=0: the body with "output": {"draco": false} (a plain glb). NULL (and *bad set when
 * the value is neither 0 nor 1, or the body is not a JSON object) when nothing changes. */
static char *without_draco(ismd_req *r, bool *bad)
{
    const char *q = ismd_query(r, "draco");
    *bad = q && strcmp(q, "0") != 0 && strcmp(q, "1") != 0;
    if (!q || strcmp(q, "0") != 0)
        return NULL;
    json_t *root = json_loadb(r->body ? r->body : "", r->body_len, JSON_REJECT_DUPLICATES, NULL);
    json_t *out = json_object_get(root, "output");
    if (json_is_object(root) && !out)
        json_object_set_new(root, "output", out = json_object());
    char *text = NULL;
    if (json_is_object(out) && json_object_set_new(out, "draco", json_false()) == 0)
        text = json_dumps(root, JSON_COMPACT);
    json_decref(root);
    return text; /* NULL: the body as it is, whose decoding then names what is wrong */
}

ism_blob *ismd_keyed_request(ismd_req *r, enum MHD_Result *ret)
{
    long long t0 = ism_now_ns();
    ism_pipeline_result pr;
    memset(&pr, 0, sizeof pr);
    const char *fmt = ismd_query(r, "format");
    if (fmt && !strcmp(fmt, "json"))
        fmt = NULL; /* links to every format (routes_mesh.c); the mesh is the request's own */
    bool bad_draco;
    char *plain = without_draco(r, &bad_draco);
    if (bad_draco) {
        *ret = ismd_respond_error(r, 400, "bad_request", "draco: expected 0 or 1");
        return NULL;
    }
    bool ok = plain ? ism_pipeline_key(plain, strlen(plain), fmt, &r->srv->limits, &pr)
                    : ism_pipeline_key(r->body ? r->body : "", r->body_len, fmt,
                                       &r->srv->limits, &pr);
    free(plain);
    r->parse_ms = (ism_now_ns() - t0) / 1e6;
    if (!ok) {
        unsigned status = pr.status >= 400 && pr.status <= 599 ? (unsigned)pr.status : 400;
        ism_blob *b = pr.body.len ? ism_blob_copy(pr.body.data, pr.body.len) : NULL;
        *ret = b ? ismd_respond_error_blob(r, status, b)
                 : ismd_respond_error(r, status, "bad_request", "the request was not accepted");
        ism_blob_unref(b);
        ism_pipeline_result_free(&pr);
        return NULL;
    }
    snprintf(r->key, sizeof r->key, "%s", pr.key);
    snprintf(r->fmt, sizeof r->fmt, "%s", pr.format);
    ism_blob *canonical = ism_blob_copy(pr.canonical.data, pr.canonical.len);
    ism_pipeline_result_free(&pr);
    *ret = MHD_NO;
    return canonical;
}

