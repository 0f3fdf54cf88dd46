/* flight_wait.h — a request that needs a computation: the body parsed, checked and keyed,
 * then a wait on the computation's flight (sched.h) with the connection suspended — nothing
 * in libmicrohttpd's threads ever blocks on a worker — until the flight ends and resumes it. */
#ifndef ISMD_FLIGHT_WAIT_H
#define ISMD_FLIGHT_WAIT_H

#include "server/isomeshd/http_types.h"

/* The body of POST /v1/mesh or /v1/jobs parsed, checked and keyed (?format= too): fills
 * r->key and r->fmt and returns the canonical request; NULL when it was refused (answered,
 * *ret what to return) or memory ran out (*ret MHD_NO). */
ism_blob *ismd_keyed_request(ismd_req *r, enum MHD_Result *ret);
/* Joins or starts the flight for key.fmt (request = canonical request JSON) and suspends
 * the connection; on_ready answers once it ends. A memory-cache hit found under the lock
 * answers at once through on_ready as well. Errors (429, 503) are answered here. */
enum MHD_Result ismd_wait_for(ismd_req *r, const char *key, const char *fmt,
                              ism_blob *request, ismd_handler on_ready);

/* The done callback of a request's waiter (r->waiter): keeps the result in r (r_status,
 * r_body, ...) and resumes the suspended connection, whose next call runs r->on_ready.
 * Scheduler lock held. For waits other than a flight's (a lookup in Redis: cluster.h). */
void ismd_req_done(ismd_waiter *w, const ismd_result *res);

#endif
