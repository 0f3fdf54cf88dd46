/* request_log.c — a request's metrics and log line (request_log.h): its count when its
 * answer is queued, its duration, bytes and line in the log when it ends, the same for libmicrohttpd's requests (http.c) and the own
 * sender's (own_sender.c). */
#include "server/isomeshd/request_log.h"

#include <string.h>

#include "core/util/clock.h"
#include "server/common/log.h"
#include "server/isomeshd/metrics.h"

void ismd_request_answered(ismd_req *r, unsigned status)
{
    if (r->status)
        return; /* answered already: the log line and the count keep the first status */
    r->status = status;
    ismd_metrics_count(&r->srv->metrics, r->route, status);
}

void ismd_request_record(ismd_req *r, bool completed, const char *cut)
{
    ismd_server *s = r->srv;
    double secs = (ism_now_ns() - r->t0_ns) / 1e9;
    bool answered = r->status != 0; /* counted then (ismd_request_answered) */
    /* no answer: the body came too slowly, or the client left */
    unsigned status = r->status                          ? r->status
                      : cut && !strcmp(cut, "body_deadline") ? 408
                                                             : 499;
    if (!answered)
        ismd_metrics_count(&s->metrics, r->route, status);
    ismd_metrics_served(&s->metrics, r->route, secs, r->bytes);
    ism_log_field f[] = {
        ISM_LS("method", r->method),
        ISM_LS("path", r->path),
        ISM_LI("status", status),
        ISM_LI("bytes", r->bytes),
        ISM_LN("ms", secs * 1e3),
        ISM_LS("cache", r->cache),
        ISM_LS("key", r->key[0] ? r->key : NULL),
        ISM_LS("client", r->client),
        ISM_LS("user", r->who.state == ISMD_AUTH_OK ? r->who.user : NULL),
        ISM_LS("end", completed ? "ok" : "aborted"),
        ISM_LS("closed", cut ? cut : r->client_left ? "client_left" : NULL),
    };
    ism_log_fields(ISM_LOG_INFO, "request", f, sizeof f / sizeof f[0]);
}
