/* routes_thumbnail.c — GET /v1/presets/{name}/thumbnail.png: the gallery's picture of a
 * preset, rendered by the daemon itself. It is the PNG format (proto/thumbnail.h) of the
 * preset's mesh at a coarse depth, so it is keyed, computed by a worker (bounded, deadlined,
 * sandboxed, single flight) and cached like any encoding; the first request for a preset
 * computes it, every later one is a cache hit. */
#include <stdio.h>
#include <string.h>

#include "proto/presets.h"
#include "proto/request.h"
#include "server/isomeshd/flight_wait.h"
#include "server/isomeshd/http_types.h"
#include "server/isomeshd/respond.h"
#include "server/isomeshd/routes.h"

/* Depth of a thumbnail's mesh: 32 cells a side are plenty for 160 x 120 pixels and keep the
 * first request of a gallery page cheap (the deepest preset costs well under a second). The
 * request asks for the depth path ("max_error": null): a picture this small needs no error
 * bound, and the default one would refine to depth 5 everywhere near a singular locus. */
#define THUMB_DEPTH 5
/* A preset's picture changes only with a new mesher version: browsers may keep it a day. */
#define THUMB_CACHE_CONTROL "public, max-age=86400"

static enum MHD_Result answer_thumbnail(ismd_req *r)
{
    if (r->r_status != 200 || !r->r_body) {
        if (r->r_body)
            return ismd_respond_error_blob(r, r->r_status ? r->r_status : 500, r->r_body);
        return ismd_respond_error(r, 500, "internal", "the computation gave no answer");
    }
    struct MHD_Response *resp = ismd_response_blob(r->r_body, ism_format_mime_of("png"));
    if (!resp)
        return MHD_NO;
    char etag[80];
    snprintf(etag, sizeof etag, "\"%s\"", r->key);
    MHD_add_response_header(resp, MHD_HTTP_HEADER_ETAG, etag);
    MHD_add_response_header(resp, MHD_HTTP_HEADER_CACHE_CONTROL, THUMB_CACHE_CONTROL);
    MHD_add_response_header(resp, "X-Cache", r->cache ? r->cache : "miss");
    r->bytes = r->r_body->len;
    return ismd_send(r, 200, resp);
}

enum MHD_Result ismd_route_thumbnail(ismd_req *r)
{
    const ism_preset *p = ism_preset_find(r->preset ? r->preset : "");
    if (!p)
        return ismd_respond_error(r, 404, "not_found", "no such preset");
    char body[192];
    int min_depth = p->min_depth < THUMB_DEPTH ? p->min_depth : THUMB_DEPTH;
    snprintf(body, sizeof body, "{\"preset\": \"%s\", \"depth\": {\"min\": %d, \"max\": %d}, "
             "\"max_error\": null}", p->name, min_depth, THUMB_DEPTH);
    ism_pipeline_result pr;
    memset(&pr, 0, sizeof pr);
    if (!ism_pipeline_key(body, strlen(body), "png", &r->srv->limits, &pr)) {
        ism_pipeline_result_free(&pr);
        return ismd_respond_error(r, 500, "internal", "the preset's thumbnail request failed");
    }
    snprintf(r->key, sizeof r->key, "%s", pr.key);
    snprintf(r->fmt, sizeof r->fmt, "png");
    ism_blob *canonical = ism_blob_copy(pr.canonical.data, pr.canonical.len);
    ism_pipeline_result_free(&pr);
    if (!canonical)
        return ismd_respond_error(r, 500, "out_of_memory", "the server ran out of memory");
    char name[ISM_CACHE_NAME_MAX];
    ism_blob *hit = ism_cache_name(name, r->key, "png") ? ism_cache_get(&r->srv->cache, name, NULL)
                                                         : NULL;
    enum MHD_Result ret;
    if (hit) {
        r->r_status = 200;
        r->r_body = hit;
        r->cache = "hit";
        ret = answer_thumbnail(r);
    } else {
        ret = ismd_wait_for(r, r->key, "png", canonical, answer_thumbnail);
    }
    ism_blob_unref(canonical);
    return ret;
}
