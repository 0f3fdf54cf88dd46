/* routes_mesh.c — the mesh routes: POST /v1/mesh (decode, key, cache or compute, answer with
 * the mesh), GET /v1/meshes/{key}.{fmt} (immutable, 304 on If-None-Match, another format of a
 * known key computed from its stored canonical request), GET /v1/meshes/{key}/stats and
 * /features. Requests are decoded and keyed here, in the HTTP thread, without geometry, so
 * cache hits never wait for a worker. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "proto/request.h"
#include "server/common/log.h"
#include "server/isomeshd/errors.h"
#include "server/isomeshd/http.h"
#include "server/isomeshd/worker_pool.h"

#define IMMUTABLE "public, max-age=31536000, immutable"

static void add_timing(ismd_req *r, struct MHD_Response *resp)
{
    char t[512];
    double total = (ism_now_ns() - r->t0_ns) / 1e6;
    if (r->cache && !strcmp(r->cache, "hit"))
        snprintf(t, sizeof t, "parse;dur=%.3f, cache;desc=\"hit\", total;dur=%.3f", r->parse_ms,
                 total);
    else
        snprintf(t, sizeof t, "parse;dur=%.3f, queue;dur=%.3f, worker;dur=%.3f%s%s, total;dur=%.3f",
                 r->parse_ms, r->queue_ms, r->worker_ms, r->timing[0] ? ", " : "", r->timing,
                 total);
    MHD_add_response_header(resp, "Server-Timing", t);
}

static enum MHD_Result answer_failure(ismd_req *r)
{
    if (r->r_status == 200 || !r->r_body)
        return ismd_respond_error(r, 500, "internal", "the computation gave no answer");
    return ismd_respond_error_blob(r, r->r_status, r->r_body);
}

/* Answers with the mesh in r->r_body (hit or fresh). */
static enum MHD_Result answer_mesh(ismd_req *r)
{
    if (r->r_status != 200 || !r->r_body)
        return answer_failure(r);
    struct MHD_Response *resp = ismd_response_blob(r->r_body, ism_format_mime_of(r->fmt));
    if (!resp)
        return MHD_NO;
    char etag[80], loc[128];
    snprintf(etag, sizeof etag, "\"%s\"", r->key);
    snprintf(loc, sizeof loc, "/v1/meshes/%s.%s", r->key, r->fmt);
    MHD_add_response_header(resp, MHD_HTTP_HEADER_ETAG, etag);
    MHD_add_response_header(resp, "X-Cache", r->cache ? r->cache : "miss");
    if (r->route == ISMD_R_MESH) {
        MHD_add_response_header(resp, MHD_HTTP_HEADER_LOCATION, loc);
        MHD_add_response_header(resp, MHD_HTTP_HEADER_CACHE_CONTROL, "no-store");
    } else {
        MHD_add_response_header(resp, MHD_HTTP_HEADER_CACHE_CONTROL, IMMUTABLE);
    }
    add_timing(r, resp);
    r->bytes = r->r_body->len;
    return ismd_send(r, 200, resp);
}

/* Looks name up in every cache tier; counts the hit or miss. */
static ism_blob *lookup(ismd_req *r, const char *ext)
{
    char name[ISM_CACHE_NAME_MAX];
    if (!ism_cache_name(name, r->key, ext))
        return NULL;
    ism_blob *b = ism_cache_get(&r->srv->cache, name, NULL);
    atomic_fetch_add(b ? &r->srv->metrics.mesh_hits : &r->srv->metrics.mesh_misses, 1);
    if (b)
        r->cache = "hit";
    return b;
}

enum MHD_Result ismd_route_mesh_post(ismd_req *r)
{
    enum MHD_Result ret;
    ism_blob *canonical = ismd_keyed_request(r, &ret);
    if (!canonical)
        return ret;
    ism_blob *hit = lookup(r, r->fmt);
    if (hit) {
        r->r_status = 200;
        r->r_body = hit;
        ret = answer_mesh(r);
    } else {
        ret = ismd_wait_for(r, r->key, r->fmt, canonical, answer_mesh);
    }
    ism_blob_unref(canonical);
    return ret;
}

/* If-None-Match holds our tag (or *). */
static bool etag_matches(const char *inm, const char *key)
{
    if (!inm)
        return false;
    for (const char *p = inm; *p;) {
        while (*p == ' ' || *p == ',')
            p++;
        if (!strncmp(p, "W/", 2))
            p += 2;
        size_t n = strcspn(p, ",");
        while (n && p[n - 1] == ' ')
            n--;
        if ((n == 1 && *p == '*') || (n == 66 && p[0] == '"' && !strncmp(p + 1, key, 64) && p[65] == '"'))
            return true;
        p += strcspn(p, ",");
    }
    return false;
}

/* The stored canonical request of r->key, checked to still produce that key (a new mesher
 * version gives new keys: old keys are then gone). NULL when unknown. */
static ism_blob *stored_request(ismd_req *r, const char *fmt)
{
    char name[ISM_CACHE_NAME_MAX];
    if (!ism_cache_name(name, r->key, "request.json"))
        return NULL;
    ism_blob *req = ism_cache_get(&r->srv->cache, name, NULL);
    if (!req)
        return NULL;
    ism_pipeline_result pr;
    memset(&pr, 0, sizeof pr);
    bool same = ism_pipeline_key((const char *)req->data, req->len, fmt, &r->srv->limits, &pr) &&
                !strcmp(pr.key, r->key);
    ism_pipeline_result_free(&pr);
    if (!same) {
        ism_logf(ISM_LOG_WARN, "stored_request_stale", "%s no longer gives its key", name);
        ism_blob_unref(req);
        return NULL;
    }
    return req;
}

enum MHD_Result ismd_route_mesh_get(ismd_req *r)
{
    ismd_server *s = r->srv;
    char name[ISM_CACHE_NAME_MAX], reqname[ISM_CACHE_NAME_MAX];
    if (!ism_cache_name(name, r->key, r->fmt) || !ism_cache_name(reqname, r->key, "request.json"))
        return ismd_respond_error(r, 404, "not_found", "no such mesh");
    if (etag_matches(ismd_header(r, MHD_HTTP_HEADER_IF_NONE_MATCH), r->key) &&
        (ism_cache_has(&s->cache, name) || ism_cache_has(&s->cache, reqname))) {
        struct MHD_Response *resp = MHD_create_response_from_buffer(0, "", MHD_RESPMEM_PERSISTENT);
        char etag[80];
        snprintf(etag, sizeof etag, "\"%s\"", r->key);
        MHD_add_response_header(resp, MHD_HTTP_HEADER_ETAG, etag);
        MHD_add_response_header(resp, MHD_HTTP_HEADER_CACHE_CONTROL, IMMUTABLE);
        r->cache = "hit";
        return ismd_send(r, 304, resp);
    }
    ism_blob *hit = lookup(r, r->fmt);
    if (hit) {
        r->r_status = 200;
        r->r_body = hit;
        return answer_mesh(r);
    }
    ism_blob *req = stored_request(r, r->fmt);
    if (!req && s->shared) /* maybe known to the service: the shared cache fetches it */
        return ismd_wait_for(r, r->key, r->fmt, NULL, answer_mesh);
    if (!req)
        return ismd_respond_error(r, 404, "unknown_mesh",
                                  "no mesh with this key is known here; POST its request to /v1/mesh");
    enum MHD_Result ret = ismd_wait_for(r, r->key, r->fmt, req, answer_mesh);
    ism_blob_unref(req);
    return ret;
}

static enum MHD_Result answer_json(ismd_req *r)
{
    if (r->r_status != 200)
        return answer_failure(r);
    ism_blob *b = r->want == ISMD_WANT_STATS ? r->r_stats : r->r_features;
    if (!b)
        return ismd_respond_error(r, 404, "not_found", "the pipeline produced no such document");
    struct MHD_Response *resp = ismd_response_blob(b, "application/json");
    if (!resp)
        return MHD_NO;
    char etag[80];
    snprintf(etag, sizeof etag, "\"%s\"", r->key);
    MHD_add_response_header(resp, MHD_HTTP_HEADER_ETAG, etag);
    MHD_add_response_header(resp, MHD_HTTP_HEADER_CACHE_CONTROL, "public, max-age=3600");
    MHD_add_response_header(resp, "X-Cache", r->cache ? r->cache : "miss");
    r->bytes = b->len;
    return ismd_send(r, 200, resp);
}

enum MHD_Result ismd_route_mesh_json(ismd_req *r)
{
    const char *ext = r->want == ISMD_WANT_STATS ? "stats.json" : "features.json";
    ism_blob *hit = lookup(r, ext);
    if (hit) {
        r->r_status = 200;
        ism_blob **slot = r->want == ISMD_WANT_STATS ? &r->r_stats : &r->r_features;
        *slot = hit;
        return answer_json(r);
    }
    ism_blob *req = stored_request(r, "drc");
    if (!req && r->srv->shared) { /* maybe known to the service: the shared cache fetches it */
        snprintf(r->fmt, sizeof r->fmt, "drc");
        return ismd_wait_for(r, r->key, "drc", NULL, answer_json);
    }
    if (!req)
        return ismd_respond_error(r, 404, "unknown_mesh",
                                  "no mesh with this key is known here; POST its request to /v1/mesh");
    snprintf(r->fmt, sizeof r->fmt, "drc");
    enum MHD_Result ret = ismd_wait_for(r, r->key, "drc", req, answer_json);
    ism_blob_unref(req);
    return ret;
}
