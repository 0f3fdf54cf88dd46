/* jobs.h — asynchronous jobs (POST /v1/jobs): a job is a waiter on a flight (sched.h) with an
 * id, a state (queued, running, done, failed, canceled), a progress fraction and, at the end,
 * the mesh's stats or the error. Server-sent event streams (GET /v1/jobs/{id}/events) follow
 * a job: each change resumes the suspended stream, which sends the latest state (progress
 * events coalesce when a client reads slowly) and ends after the final state.
 *
 * Finished jobs are kept for a while (JOB_TTL in jobs.c) and the table is bounded, per user
 * and in all (USER_JOBS_KEPT, MAX_JOBS): one user's flood of posts evicts that user's own
 * oldest finished records, never another user's, and never a live one. All calls
 * below need the scheduler's lock (ismd_sched_lock) unless they say otherwise. */
#ifndef ISMD_JOBS_H
#define ISMD_JOBS_H

#include <jansson.h>
#include <microhttpd.h>
#include <stdbool.h>
#include <time.h>

#include "server/common/blob.h"
#include "server/common/http_loops.h"
#include "server/isomeshd/metrics.h"
#include "server/isomeshd/sched.h"

typedef struct ismd_jobs ismd_jobs;
typedef struct ismd_job ismd_job;

typedef enum ismd_job_state {
    ISMD_JOB_QUEUED, ISMD_JOB_RUNNING, ISMD_JOB_DONE, ISMD_JOB_FAILED, ISMD_JOB_CANCELED
} ismd_job_state;

/* Lock not needed. */
ismd_jobs *ismd_jobs_new(ismd_metrics *metrics);
void ismd_jobs_free(ismd_jobs *j);

typedef enum ismd_jobs_refusal {
    ISMD_JOBS_OK,
    ISMD_JOBS_USER_FULL,   /* every record the user may keep is a live job (429) */
    ISMD_JOBS_TABLE_FULL,  /* the table is full of live jobs, or out of memory (503) */
} ismd_jobs_refusal;

/* A new queued job of user for key.fmt, or NULL with *why. Its waiter is
 * ismd_job_waiter(job); submit it to the scheduler, then call ismd_jobs_submitted. */
ismd_job *ismd_jobs_create(ismd_jobs *j, const char *key, const char *fmt, const char *user,
                           ismd_jobs_refusal *why);
ismd_waiter *ismd_job_waiter(ismd_job *job);
/* After a successful submission: takes the flight's current state (a joined flight may
 * already be running). */
void ismd_jobs_submitted(ismd_job *job);
/* Drops a job whose submission failed. */
void ismd_jobs_discard(ismd_jobs *j, ismd_job *job);
/* Marks a job done at once (its mesh was cached); stats may be NULL. */
void ismd_jobs_complete_cached(ismd_jobs *j, ismd_job *job, ism_blob *stats);

ismd_job *ismd_jobs_find(ismd_jobs *j, const char *id);
const char *ismd_job_id(const ismd_job *job);
/* Who created the job (a token's user or a client address). */
const char *ismd_job_user(const ismd_job *job);
/* The job as JSON (caller owns the reference). */
json_t *ismd_job_json(const ismd_job *job);

/* What the JSON of a job says, wherever it comes from (this daemon's table, or a job of
 * another daemon read from Redis: cluster.h). Lock not needed. */
typedef struct ismd_job_view {
    const char *id, *key, *fmt, *user;
    ismd_job_state state;
    double progress;
    time_t created_unix;
    long long started_unix_ms;  /* 0: not started (or unknown) */
    double queue_ms;            /* from creation to start, when started */
    unsigned status;            /* failed: the HTTP status */
    const ism_blob *stats;      /* done: may be NULL */
    const ism_blob *error;      /* failed: the error JSON, may be NULL */
} ismd_job_view;
json_t *ismd_job_view_json(const ismd_job_view *v);
/* The state named s ("queued", "running", ...); false when none is. */
bool ismd_job_state_parse(const char *s, ismd_job_state *out);
/* {"jobs": [...]}: the jobs of user (NULL: everyone's), newest first, at most max, without
 * their stats; "truncated": true when more were left out. */
json_t *ismd_jobs_list_json(const ismd_jobs *j, const char *user, size_t max);
/* Whether the job ended canceled (a DELETE, or ismd_jobs_revoke). */
bool ismd_job_canceled(const ismd_job *job);
/* Cancels a live job (no effect on a finished one). True when it was live. */
bool ismd_jobs_cancel(ismd_jobs *j, ismd_sched *s, ismd_job *job);
/* A finished job whose DELETE was made while this daemon looked dead to the cluster (cut off
 * from Redis past a lock lifetime, cluster.h): that DELETE was the cancel (its client was
 * told canceled, its computation stopped as abandoned), so the job reads canceled here too,
 * even when a computation started over for other requests finished it since. */
void ismd_jobs_revoke(ismd_jobs *j, ismd_job *job);

/* An event-stream response following job (NULL when out of memory). conn is the connection
 * the response will be queued on, served by one of loops' threads (each event resumes it
 * there); sched is the lock's owner. */
struct MHD_Response *ismd_jobs_stream(ismd_jobs *j, ismd_sched *s, ismd_job *job,
                                      struct MHD_Connection *conn, ism_http_loops *loops);
/* Shutdown: every stream sends its last event and ends; new streams end at once. */
void ismd_jobs_close_streams(ismd_jobs *j);

#endif
