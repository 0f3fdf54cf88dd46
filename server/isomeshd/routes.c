/* routes.c — the route table of routes.h. One line per route, first match wins: its path
 * ({id} a job id, {key} a mesh key, {fmt} a mesh format, {name} a preset's name, a final *
 * anything), its metrics label, its Allow header (NULL: nothing here, 404), and its handler
 * for GET/HEAD, POST and DELETE. A POST handler reads the request body. */
#include "server/isomeshd/routes.h"

#include <stdio.h>
#include <string.h>

#include "proto/presets.h"
#include "proto/request.h"

#define JOB_ID_LEN 32 /* hex digits of a job id (jobs.h) */
#define PRESET_NAME_MAX 64 /* longer than any preset's name (presets.c) */

struct ismd_route_def {
    const char *path;
    ismd_route id;
    const char *allow;
    ismd_handler get, post, del;
    ismd_want want;
};

#define READ "GET, HEAD, OPTIONS"
#define COMPUTE "POST, OPTIONS"

static const ismd_route_def ROUTES[] = {
    /* path                         label                 allow     GET/HEAD, POST, DELETE */
    {"/v1/mesh",                    ISMD_R_MESH,          COMPUTE,  NULL, ismd_route_mesh_post, NULL, 0},
    {"/v1/sweep",                   ISMD_R_SWEEP,         COMPUTE,  NULL, ismd_route_sweep, NULL, 0},
    {"/v1/point",                   ISMD_R_POINT,         COMPUTE,  NULL, ismd_route_point, NULL, 0},
    {"/v1/box",                     ISMD_R_BOX,           COMPUTE,  NULL, ismd_route_box, NULL, 0},
    {"/v1/jobs",                    ISMD_R_JOBS,          "GET, HEAD, POST, OPTIONS",
                                                                    ismd_route_jobs_list, ismd_route_jobs_post, NULL, 0},
    {"/v1/jobs/{id}",               ISMD_R_JOB,           "GET, HEAD, DELETE, OPTIONS",
                                                                    ismd_route_job_get, NULL, ismd_route_job_delete, 0},
    {"/v1/jobs/{id}/events",        ISMD_R_JOB_EVENTS,    "GET, OPTIONS",
                                                                    ismd_route_job_events, NULL, NULL, 0},
    {"/v1/jobs/*",                  ISMD_R_JOB,           NULL,     NULL, NULL, NULL, 0},
    {"/v1/meshes/{key}.{fmt}",      ISMD_R_MESH_FILE,     READ,     ismd_route_mesh_get, NULL, NULL, 0},
    {"/v1/meshes/{key}/stats",      ISMD_R_MESH_STATS,    READ,     ismd_route_mesh_json, NULL, NULL, ISMD_WANT_STATS},
    {"/v1/meshes/{key}/features",   ISMD_R_MESH_FEATURES, READ,     ismd_route_mesh_json, NULL, NULL, ISMD_WANT_FEATURES},
    {"/v1/meshes/*",                ISMD_R_MESH_FILE,     NULL,     NULL, NULL, NULL, 0},
    {"/v1/presets",                 ISMD_R_PRESETS,       READ,     ismd_route_doc, NULL, NULL, 0},
    {"/v1/presets/{name}/thumbnail.png", ISMD_R_THUMBNAIL, READ,   ismd_route_thumbnail, NULL, NULL, 0},
    {"/v1/openapi.yaml",            ISMD_R_OPENAPI,       READ,     ismd_route_doc, NULL, NULL, 0},
    {"/v1/request.schema.json",     ISMD_R_SCHEMA,        READ,     ismd_route_doc, NULL, NULL, 0},
    {"/v1/*",                       ISMD_R_OTHER,         NULL,     NULL, NULL, NULL, 0},
    {"/healthz",                    ISMD_R_HEALTHZ,       READ,     ismd_route_health, NULL, NULL, 0},
    {"/readyz",                     ISMD_R_READYZ,        READ,     ismd_route_health, NULL, NULL, 0},
    {"/metrics",                    ISMD_R_METRICS,       READ,     ismd_route_metrics, NULL, NULL, 0},
    {"/vendor/three/*",             ISMD_R_VENDOR,        READ,     ismd_route_static, NULL, NULL, 0},
    {"/*",                          ISMD_R_STATIC,        READ,     ismd_route_static, NULL, NULL, 0},
};
#define NROUTES (sizeof ROUTES / sizeof ROUTES[0])

/* Nothing here: the same answer for a URL no line matches. */
static const ismd_route_def NOT_FOUND = {"", ISMD_R_OTHER, NULL, NULL, NULL, NULL, 0};

static bool is_hex(const char *s, size_t n)
{
    for (size_t i = 0; i < n; i++)
        if (!((s[i] >= '0' && s[i] <= '9') || (s[i] >= 'a' && s[i] <= 'f')))
            return false;
    return true;
}

/* Takes the parameter named name (n bytes) from the start of *url into r; advances *url. */
static bool take_param(const char *name, size_t n, const char **url, ismd_req *r)
{
    const char *u = *url;
    if (n == 2 && !strncmp(name, "id", 2)) {
        if (strnlen(u, JOB_ID_LEN) < JOB_ID_LEN || !is_hex(u, JOB_ID_LEN))
            return false;
        memcpy(r->id, u, JOB_ID_LEN);
        r->id[JOB_ID_LEN] = 0;
        *url = u + JOB_ID_LEN;
        return true;
    }
    if (n == 3 && !strncmp(name, "key", 3)) {
        if (strnlen(u, ISM_KEY_HEX_LEN) < ISM_KEY_HEX_LEN)
            return false;
        memcpy(r->key, u, ISM_KEY_HEX_LEN);
        r->key[ISM_KEY_HEX_LEN] = 0;
        *url = u + ISM_KEY_HEX_LEN;
        return ism_key_valid(r->key);
    }
    if (n == 4 && !strncmp(name, "name", 4)) { /* a preset's name, up to the next '/' */
        char buf[PRESET_NAME_MAX];
        size_t len = strcspn(u, "/");
        if (len >= sizeof buf)
            return false;
        memcpy(buf, u, len);
        buf[len] = 0;
        const ism_preset *p = ism_preset_find(buf);
        if (!p)
            return false;
        r->preset = p->name;
        *url = u + len;
        return true;
    }
    if (n == 3 && !strncmp(name, "fmt", 3)) { /* the rest of the path */
        size_t len = strlen(u);
        if (len >= sizeof r->fmt || ism_format_lookup(u) < 0)
            return false;
        memcpy(r->fmt, u, len + 1);
        *url = u + len;
        return true;
    }
    return false;
}

static bool match(const char *pat, const char *url, ismd_req *r)
{
    while (*pat) {
        if (*pat == '*')
            return true;
        if (*pat == '{') {
            const char *end = strchr(pat, '}');
            if (!take_param(pat + 1, (size_t)(end - pat - 1), &url, r))
                return false;
            pat = end + 1;
            continue;
        }
        if (*pat++ != *url++)
            return false;
    }
    return *url == 0;
}

void ismd_route_find(ismd_req *r, const char *url)
{
    const ismd_route_def *d = &NOT_FOUND;
    for (size_t i = 0; i < NROUTES; i++)
        if (match(ROUTES[i].path, url, r)) {
            d = &ROUTES[i];
            break;
        }
    r->def = d;
    r->route = d->id;
    r->allow = d->allow;
    r->want = d->want;
    if (!d->allow) { /* what a well-formed URL of that kind looks like */
        r->early_status = 404;
        r->early_code = "not_found";
        if (d->id == ISMD_R_JOB)
            snprintf(r->early_msg, sizeof r->early_msg, "no such job: a job is /v1/jobs/ID "
                     "(and /events), ID the %d hex digits POST /v1/jobs answers", JOB_ID_LEN);
        else if (d->id == ISMD_R_MESH_FILE)
            snprintf(r->early_msg, sizeof r->early_msg, "no such mesh: a mesh is "
                     "/v1/meshes/KEY.FORMAT, /v1/meshes/KEY/stats or /features, KEY the %d hex "
                     "digits of a job's key, FORMAT drc, glb, ply, obj, stl or png",
                     ISM_KEY_HEX_LEN);
        else
            snprintf(r->early_msg, sizeof r->early_msg, "nothing here: the API is described "
                     "at GET /v1/openapi.yaml");
    }
}

ismd_handler ismd_route_handler(const ismd_req *r, const char *method, bool *body)
{
    const ismd_route_def *d = r->def;
    *body = false;
    if (!d)
        return NULL;
    if (!strcmp(method, "POST")) {
        *body = d->post != NULL;
        return d->post;
    }
    return !strcmp(method, "DELETE") ? d->del : d->get;
}
