/* routes_misc.c — the small routes: GET /v1/presets, /v1/openapi.yaml, /v1/request.schema.json
 * (documents loaded from --data-dir at start-up), POST /v1/box (the box a surface's zero set
 * needs: a bounded interval pass, proto/box_fit.h, answered on the HTTP thread), POST
 * /v1/point (f and curvature at one point, proto/point_probe.h), /healthz (the process answers), /readyz (a
 * worker is ready and we are not shutting down), /metrics (Prometheus text, with the per-user
 * gauges of user_metrics.h). */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "server/isomeshd/http_types.h"
#include "server/isomeshd/respond.h"
#include "server/isomeshd/routes.h"
#include "server/isomeshd/user_metrics.h"
#include "proto/box_fit.h"
#include "proto/point_probe.h"

enum MHD_Result ismd_route_doc(ismd_req *r)
{
    ismd_server *s = r->srv;
    ism_blob *b;
    const char *type;
    switch (r->route) {
    case ISMD_R_OPENAPI:
        b = s->openapi;
        type = "application/yaml";
        break;
    case ISMD_R_SCHEMA:
        b = s->schema;
        type = "application/schema+json";
        break;
    default:
        b = s->presets;
        type = "application/json";
        break;
    }
    if (!b)
        return ismd_respond_error(r, 404, "not_installed",
                                  "this document was not found in --data-dir at start-up");
    struct MHD_Response *resp = ismd_response_blob(b, type);
    if (!resp)
        return MHD_NO;
    MHD_add_response_header(resp, MHD_HTTP_HEADER_CACHE_CONTROL, "public, max-age=300");
    r->bytes = b->len;
    return ismd_send(r, 200, resp);
}

/* The JSON answer, or the request error err describes. */
static enum MHD_Result answer_or_error(ismd_req *r, char *json, const ism_req_error *err)
{
    if (!json) {
        size_t elen = 0;
        char *e = ism_req_error_json(err, &elen);
        ism_blob *b = e ? ism_blob_copy(e, elen) : NULL;
        free(e);
        enum MHD_Result ret = b ? ismd_respond_error_blob(r, (unsigned)err->status, b)
                                : ismd_respond_error(r, 500, "out_of_memory", "out of memory");
        ism_blob_unref(b);
        return ret;
    }
    enum MHD_Result ret = ismd_respond_json(r, 200, json);
    free(json);
    return ret;
}

enum MHD_Result ismd_route_box(ismd_req *r)
{
    ism_request_limits lim = {.max_depth = r->srv->limits.max_depth};
    ism_req_error err;
    size_t len = 0;
    char *json = ism_box_fit_answer(r->body ? r->body : "", r->body_len, &lim, &len, &err);
    return answer_or_error(r, json, &err);
}

enum MHD_Result ismd_route_point(ismd_req *r)
{
    double at[3];
    const char *q = ismd_query(r, "at");
    if (!q || !ism_point_parse(q, at))
        return ismd_respond_error(r, 400, "bad_request", "?at=X,Y,Z: three finite numbers");
    ism_request_limits lim = {.max_depth = r->srv->limits.max_depth};
    ism_req_error err;
    size_t len = 0;
    char *json = ism_point_probe_answer(r->body ? r->body : "", r->body_len, &lim, at, &len, &err);
    return answer_or_error(r, json, &err);
}

enum MHD_Result ismd_route_health(ismd_req *r)
{
    ismd_server *s = r->srv;
    char body[256];
    if (r->route == ISMD_R_HEALTHZ)
        return ismd_respond_json(r, 200, "{\"status\":\"ok\"}");
    long long ready = atomic_load(&s->metrics.workers_ready);
    long long total = atomic_load(&s->metrics.workers_total);
    bool draining = atomic_load(&s->draining);
    bool ok = ready > 0 && !draining;
    snprintf(body, sizeof body,
             "{\"status\":\"%s\",\"workers_ready\":%lld,\"workers\":%lld,\"draining\":%s}",
             ok ? "ready" : "not_ready", ready, total, draining ? "true" : "false");
    return ismd_respond_json(r, ok ? 200 : 503, body);
}

enum MHD_Result ismd_route_metrics(ismd_req *r)
{
    size_t len, ulen = 0;
    char *text = ismd_metrics_render(&r->srv->metrics, &r->srv->cache, &len);
    char *users = ismd_user_metrics_render(&r->srv->sched, &ulen);
    ism_blob *b = text && users ? ism_blob_new(len + ulen) : NULL;
    if (b) {
        memcpy(b->data, text, len);
        memcpy(b->data + len, users, ulen);
    }
    free(text);
    free(users);
    if (!b)
        return MHD_NO;
    struct MHD_Response *resp = ismd_response_blob(b, "text/plain; version=0.0.4; charset=utf-8");
    r->bytes = b->len;
    ism_blob_unref(b);
    if (!resp)
        return MHD_NO;
    MHD_add_response_header(resp, MHD_HTTP_HEADER_CACHE_CONTROL, "no-store");
    return ismd_send(r, 200, resp);
}
