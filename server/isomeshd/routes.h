/* routes.h — the route table (routes.c: each path with its methods, its handler per method and
 * whether it reads a body, in the manner of Redis's command table) and the handlers that
 * answer them (routes_*.c). */
#ifndef ISMD_ROUTES_H
#define ISMD_ROUTES_H

#include "server/isomeshd/http_types.h"
#include "server/isomeshd/respond.h"

/* Finds url's route: sets r->route, r->allow (NULL: 404, answered once the body is read),
 * r->want and the path parameters (r->key, r->fmt, r->id). */
void ismd_route_find(ismd_req *r, const char *url);
/* The handler of r's route for method (HEAD is GET's), NULL when it has none; *body: the
 * request's body is read for it. */
ismd_handler ismd_route_handler(const ismd_req *r, const char *method, bool *body);

/* Why ismd_job_start refused a job. */
typedef struct ismd_job_refusal {
    bool table_full;           /* the jobs table (submit: CLIENT_LIMIT = the user's share) */
    ismd_submit submit;        /* else the scheduler's answer */
} ismd_job_refusal;

/* Starts a job for r->key.r->fmt (canonical: its request): answered from the cache, or its
 * computation joined or queued, and recorded in Redis with --cluster. Returns the job with
 * the scheduler's lock held (the caller answers, then unlocks), or NULL (lock not held) with
 * the reason in why (routes_jobs.c). */
struct ismd_job;
struct ismd_job *ismd_job_start(ismd_req *r, ism_blob *canonical, ismd_job_refusal *why);
/* The 429 or 503 for a refused job. */
enum MHD_Result ismd_respond_job_refused(ismd_req *r, const ismd_job_refusal *why);

/* ---- routes (routes_*.c) ------------------------------------------------------------- */

enum MHD_Result ismd_route_mesh_post(ismd_req *r);       /* POST /v1/mesh */
enum MHD_Result ismd_route_mesh_get(ismd_req *r);        /* GET /v1/meshes/{key}.{fmt} */
/* The headers of a mesh answer to r (its key, fmt, route and cache; Date and Content-Length
 * are the sender's), in the order they are sent. */
void ismd_mesh_headers(ismd_req *r, ismd_add_header add, void *ctx);
enum MHD_Result ismd_route_mesh_json(ismd_req *r);       /* GET /v1/meshes/{key}/stats|features */
enum MHD_Result ismd_route_jobs_post(ismd_req *r);       /* POST /v1/jobs */
enum MHD_Result ismd_route_jobs_list(ismd_req *r);       /* GET /v1/jobs */
enum MHD_Result ismd_route_sweep(ismd_req *r);           /* POST /v1/sweep */
enum MHD_Result ismd_route_job_get(ismd_req *r);         /* GET /v1/jobs/{id} */
enum MHD_Result ismd_route_job_delete(ismd_req *r);      /* DELETE /v1/jobs/{id} */
enum MHD_Result ismd_route_job_events(ismd_req *r);      /* GET /v1/jobs/{id}/events */
enum MHD_Result ismd_route_doc(ismd_req *r);             /* presets, openapi, schema */
enum MHD_Result ismd_route_thumbnail(ismd_req *r);       /* GET /v1/presets/{name}/thumbnail.png */
enum MHD_Result ismd_route_box(ismd_req *r);             /* POST /v1/box */
enum MHD_Result ismd_route_point(ismd_req *r);           /* POST /v1/point?at=X,Y,Z */
enum MHD_Result ismd_route_health(ismd_req *r);          /* /healthz, /readyz */
enum MHD_Result ismd_route_metrics(ismd_req *r);         /* /metrics */
enum MHD_Result ismd_route_static(ismd_req *r);          /* the viewer and /vendor/three */

#endif
