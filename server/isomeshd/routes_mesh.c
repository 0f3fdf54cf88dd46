/* routes_mesh.c — the mesh routes: POST /v1/mesh (decode, key, cache or compute, answer with
 * the mesh, or with ?format=json / Accept: application/json its key, the URLs of every
 * format, stats and features, and the stats), GET /v1/meshes/{key}.{fmt} (immutable, 304 on If-None-Match, another format of a
 * known key computed from its stored canonical request), GET /v1/meshes/{key}/stats and
 * /features. Requests are decoded and keyed here, in the HTTP thread, without geometry, so
 * cache hits never wait for a worker. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "proto/json_writer.h"
#include "proto/request.h"
#include "server/common/gzip_body.h"
#include "server/common/log.h"
#include "server/isomeshd/errors.h"
#include "server/isomeshd/flight_wait.h"
#include "server/isomeshd/http_types.h"
#include "server/isomeshd/respond.h"
#include "server/isomeshd/routes.h"
#include "server/isomeshd/worker_pool.h"

#define IMMUTABLE "public, max-age=31536000, immutable"
/* The gzip variant's entity tag is the plain one's key with this tail (RFC 9110 8.8.3: each
 * content coding its own strong tag). */
#define GZIP_TAG "-gzip"

/* The Server-Timing value of r's answer. */
static void timing_of(ismd_req *r, char t[512])
{
    double total = (ism_now_ns() - r->t0_ns) / 1e6;
    if (r->cache && !strcmp(r->cache, "hit")) { /* every cached answer: no snprintf */
        char parse[40], all[40];
        ism_log_number(parse, sizeof parse, r->parse_ms);
        ism_log_number(all, sizeof all, total);
        size_t n = 0;
        const char *parts[] = {"parse;dur=", parse, ", cache;desc=\"hit\", total;dur=", all};
        for (size_t i = 0; i < sizeof parts / sizeof parts[0]; i++) {
            size_t len = strlen(parts[i]);
            memcpy(t + n, parts[i], len); /* at most 10 + 39 + 29 + 39 bytes */
            n += len;
        }
        t[n] = 0;
    } else
        snprintf(t, 512, "parse;dur=%.3f, queue;dur=%.3f, worker;dur=%.3f%s%s, total;dur=%.3f",
                 r->parse_ms, r->queue_ms, r->worker_ms, r->timing[0] ? ", " : "", r->timing,
                 total);
}

void ismd_mesh_headers(ismd_req *r, ismd_add_header add, void *ctx)
{
    char etag[80], loc[128], timing[512];
    snprintf(etag, sizeof etag, "\"%s\"", r->key);
    add(ctx, MHD_HTTP_HEADER_CONTENT_TYPE, ism_format_mime_of(r->fmt));
    add(ctx, MHD_HTTP_HEADER_ETAG, etag);
    add(ctx, "X-Cache", r->cache ? r->cache : "miss");
    if (r->route == ISMD_R_MESH) {
        snprintf(loc, sizeof loc, "/v1/meshes/%s.%s", r->key, r->fmt);
        add(ctx, MHD_HTTP_HEADER_LOCATION, loc);
        add(ctx, MHD_HTTP_HEADER_CACHE_CONTROL, "no-store");
    } else {
        add(ctx, MHD_HTTP_HEADER_CACHE_CONTROL, IMMUTABLE);
    }
    timing_of(r, timing);
    add(ctx, "Server-Timing", timing);
}

static enum MHD_Result answer_failure(ismd_req *r)
{
    if (r->r_status == 200 || !r->r_body)
        return ismd_respond_error(r, 500, "internal", "the computation gave no answer");
    return ismd_respond_error_blob(r, r->r_status, r->r_body);
}

/* Looks name up in every cache tier; counts the hit or miss. */
static ism_blob *lookup(ismd_req *r, const char *ext);

/* Writes "/v1/meshes/<key><tail>" as the value of k. */
static void url_member(ism_jw *w, const char *k, const char *key, const char *tail)
{
    char url[160];
    snprintf(url, sizeof url, "/v1/meshes/%s%s", key, tail);
    ism_jw_key(w, k);
    ism_jw_string(w, url);
}

/* The JSON answer for scripts (?format=json, Accept: application/json): the key, the URL of
 * every format, of the stats and the features, and the stats themselves. */
static enum MHD_Result answer_links(ismd_req *r)
{
    ism_blob *stats = r->r_stats ? ism_blob_ref(r->r_stats) : lookup(r, "stats.json");
    ism_jw w;
    ism_jw_init(&w);
    ism_jw_object(&w);
    ism_jw_key(&w, "key");
    ism_jw_string(&w, r->key);
    ism_jw_key(&w, "format");
    ism_jw_string(&w, r->fmt);
    char tail[16];
    snprintf(tail, sizeof tail, ".%s", r->fmt);
    url_member(&w, "url", r->key, tail);
    ism_jw_key(&w, "urls");
    ism_jw_object(&w);
    for (int i = 0; i < ISM_FORMAT_COUNT; i++) {
        const char *name = ism_format_name((enum ism_format)i);
        snprintf(tail, sizeof tail, ".%s", name);
        url_member(&w, name, r->key, tail);
    }
    url_member(&w, "stats", r->key, "/stats");
    url_member(&w, "features", r->key, "/features");
    ism_jw_object_end(&w);
    ism_jw_key(&w, "stats");
    if (stats)
        ism_jw_raw(&w, (const char *)stats->data, stats->len);
    else
        ism_jw_null(&w);
    ism_jw_object_end(&w);
    ism_blob_unref(stats);
    char *json = ism_jw_take(&w, NULL);
    if (!json)
        return ismd_respond_error(r, 500, "out_of_memory", "the server ran out of memory");
    enum MHD_Result ret = ismd_respond_json(r, 200, json);
    free(json);
    return ret;
}

/* Answers with the mesh in r->r_body (hit or fresh). */
static enum MHD_Result answer_mesh(ismd_req *r)
{
    if (r->r_status != 200 || !r->r_body)
        return answer_failure(r);
    if (r->links)
        return answer_links(r);
    char name[ISM_CACHE_NAME_MAX];
    struct MHD_Response *resp = ism_cache_name(name, r->key, r->fmt)
                                    ? ismd_response_cached(r->srv, name, r->r_body, NULL)
                                    : ismd_response_blob(r->r_body, NULL);
    if (!resp)
        return MHD_NO;
    ismd_mesh_headers(r, ismd_add_to_response, resp);
    r->bytes = r->r_body->len;
    return ismd_send(r, 200, resp);
}

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
    const char *q = ismd_query(r, "format"), *accept = ismd_header(r, MHD_HTTP_HEADER_ACCEPT);
    r->links = (q && !strcmp(q, "json")) || (accept && strstr(accept, "application/json"));
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

/* If-None-Match (a list of entity tags, or *) names tag ("\"...\"") or is *. A weak
 * W/ tag compares weakly, as RFC 9110 13.1.2 asks of If-None-Match. */
static bool tag_listed(const char *inm, const char *tag)
{
    size_t n = strlen(tag);
    for (const char *p = inm; p && *p;) {
        while (*p == ' ' || *p == ',')
            p++;
        if (!strncmp(p, "W/", 2))
            p += 2;
        size_t len = strcspn(p, ",");
        while (len && p[len - 1] == ' ')
            len--;
        if ((len == 1 && *p == '*') || (len == n && !strncmp(p, tag, n)))
            return true;
        p += strcspn(p, ",");
    }
    return false;
}

/* If-None-Match holds the plain tag of key (or *). */
static bool etag_matches(const char *inm, const char *key)
{
    char tag[ISM_KEY_HEX_LEN + 3];
    snprintf(tag, sizeof tag, "\"%s\"", key);
    return tag_listed(inm, tag);
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
    if (!ism_cache_name(name, r->key, r->fmt))
        return ismd_respond_error(r, 404, "not_found", "no such mesh");
    if (etag_matches(ismd_header(r, MHD_HTTP_HEADER_IF_NONE_MATCH), r->key) &&
        (ism_cache_has(&s->cache, name) ||
         (ism_cache_name(reqname, r->key, "request.json") && ism_cache_has(&s->cache, reqname)))) {
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

/* The gzip bytes of r's features document b: the stored "<key>.features.json.gz" (the
 * worker pool makes it when it stores a fresh result, worker_pool.c), else compressed here
 * once and kept beside the plain entry in the local tiers (a document stored before, or one
 * fetched from a peer). NULL when out of memory. */
static ism_blob *features_gzip(ismd_req *r, const ism_blob *b)
{
    char name[ISM_CACHE_NAME_MAX];
    ism_blob *gz = ism_cache_name(name, r->key, ISM_GZIP_FEATURES_EXT)
                       ? ism_cache_get(&r->srv->cache, name, NULL)
                       : NULL;
    if (gz)
        return gz;
    atomic_fetch_add(&r->srv->metrics.gzip_on_request, 1);
    return ism_cache_put_features_gzip(&r->srv->cache, r->key, b);
}

static enum MHD_Result answer_json(ismd_req *r)
{
    if (r->r_status != 200)
        return answer_failure(r);
    ism_blob *b = r->want == ISMD_WANT_STATS ? r->r_stats : r->r_features;
    if (!b)
        return ismd_respond_error(r, 404, "not_found", "the pipeline produced no such document");
    /* The features JSON goes gzipped to a client that takes it (browsers' fetch always do):
     * it is the side data beside the mesh, mostly digits (gzip_body.h). Its gzip bytes are an
     * entry of their own beside the plain one, made once (features_gzip): a client that
     * fetches it again costs this thread a lookup, not a compression. */
    bool features = r->want != ISMD_WANT_STATS;
    /* The tag depends on whether gzip is wanted, not on its bytes: a revalidation that ends
     * in 304 never fetches (or makes) them. */
    bool want_gz = features && b->len >= ISM_GZIP_MIN_BODY &&
                   ism_accepts_gzip(ismd_header(r, MHD_HTTP_HEADER_ACCEPT_ENCODING));
    char etag[80]; /* each encoding its own strong tag (RFC 9110 8.8.3) */
    snprintf(etag, sizeof etag, "\"%s%s\"", r->key, want_gz ? GZIP_TAG : "");
    ism_blob *gz = NULL;
    struct MHD_Response *resp;
    int status = 200;
    if (features && tag_listed(ismd_header(r, MHD_HTTP_HEADER_IF_NONE_MATCH), etag)) {
        resp = MHD_create_response_from_buffer(0, "", MHD_RESPMEM_PERSISTENT);
        status = 304;
    } else {
        gz = want_gz ? features_gzip(r, b) : NULL;
        if (want_gz && !gz) /* out of memory: the plain body goes, under its own tag */
            snprintf(etag, sizeof etag, "\"%s\"", r->key);
        resp = ismd_response_blob(gz ? gz : b, "application/json");
    }
    size_t sent = status == 304 ? 0 : gz ? gz->len : b->len;
    ism_blob_unref(gz); /* the response holds its own reference */
    if (!resp)
        return MHD_NO;
    MHD_add_response_header(resp, MHD_HTTP_HEADER_ETAG, etag);
    if (features)
        MHD_add_response_header(resp, MHD_HTTP_HEADER_VARY, MHD_HTTP_HEADER_ACCEPT_ENCODING);
    if (gz && status == 200)
        MHD_add_response_header(resp, MHD_HTTP_HEADER_CONTENT_ENCODING, "gzip");
    MHD_add_response_header(resp, MHD_HTTP_HEADER_CACHE_CONTROL, "public, max-age=3600");
    MHD_add_response_header(resp, "X-Cache", r->cache ? r->cache : "miss");
    r->bytes = sent;
    return ismd_send(r, status, resp);
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
