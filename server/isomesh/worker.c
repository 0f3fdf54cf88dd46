/* worker.c — the `isomesh --worker` loop: one job at a time from the daemon's REQUEST frames
 * to RESULT frames, with rate-limited PROGRESS frames in between. Any framing problem ends
 * the process: the daemon sees the pipe close, fails the job and starts a fresh worker.
 * Before its HELLO the worker enters the seccomp sandbox (sandbox.h); it never runs without. */
#include "server/isomesh/worker.h"
#include "core/util/clock.h"
#include "core/util/le_bytes.h"

#include <errno.h>
#include <fcntl.h>
#include <pthread.h>
#include <signal.h>
#include <stdio.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

#include "core/version.h"
#include "proto/frame.h"
#include "proto/request.h"
#include "core/util/parallel.h"
#include "server/common/pipeline.h"
#include "server/isomesh/sandbox.h"

/* A request frame holds one JSON request (the daemon caps bodies far below 1 MB) and maybe
 * a stored computed surface, as large as the daemon's triangle limit makes it: the frame
 * ceiling. */
#define WORKER_MAX_REQUEST ISM_FRAME_MAX_PAYLOAD
/* Progress frames at most this often (plus the first one). */
#define PROGRESS_INTERVAL_NS 50000000LL
/* Share of the daemon's job timeout after which the singular stages stop (the locus then
 * reported incomplete): the rest is left to what follows them — the curves, the analysis,
 * encoding and sending — so the job answers with a partial locus instead of the daemon's
 * 504 (the polygoniser runs between the stages and is not cut). */
#define SINGULAR_DEADLINE_SHARE 0.7

/* Polygoniser threads for a job that names none: counted before the sandbox, because counting
 * cores reads /sys. */
static int default_threads = 1;

typedef struct progress_state {
    int fd;
    uint64_t job;
    long long last_ns;
    uint32_t last_millionths;
    bool failed;
    pthread_mutex_t lock;
} progress_state;

static void on_progress(void *ctx, double fraction)
{
    progress_state *ps = ctx;
    if (!(fraction >= 0))
        fraction = 0;
    if (fraction > 1)
        fraction = 1;
    uint32_t m = (uint32_t)(fraction * 1e6);
    pthread_mutex_lock(&ps->lock);
    long long t = ism_now_ns();
    if (!ps->failed && m != ps->last_millionths &&
        (ps->last_ns == 0 || t - ps->last_ns >= PROGRESS_INTERVAL_NS)) {
        unsigned char p[4];
        ism_put_le32(p, m);
        ism_frame_part part = {p, 4};
        if (ism_frame_write_fd(ps->fd, ISM_FRAME_PROGRESS, ps->job, &part, 1) != ISM_FRAME_OK)
            ps->failed = true;
        ps->last_ns = t;
        ps->last_millionths = m;
    }
    pthread_mutex_unlock(&ps->lock);
}

/* Sends an ERROR frame: status and an error JSON of the house format. */
static bool send_error(int fd, uint64_t job, unsigned status, const char *code, const char *msg)
{
    char json[512];
    snprintf(json, sizeof json, "{\"error\": {\"code\": \"%s\", \"message\": \"%s\"}}", code, msg);
    ism_frame_builder b = {0};
    ism_frame_put_u32(&b, status);
    ism_frame_put_str(&b, json);
    bool ok = !b.failed;
    if (ok) {
        ism_frame_part part = {b.data, b.len};
        ok = ism_frame_write_fd(fd, ISM_FRAME_ERROR, job, &part, 1) == ISM_FRAME_OK;
    }
    ism_frame_builder_free(&b);
    return ok;
}

static bool send_hello(int fd)
{
    ism_frame_builder b = {0};
    ism_frame_put_u32(&b, (uint32_t)getpid());
    ism_frame_put_str(&b, ISM_VERSION " " ISM_MESHER_VERSION);
    bool ok = !b.failed;
    if (ok) {
        ism_frame_part part = {b.data, b.len};
        ok = ism_frame_write_fd(fd, ISM_FRAME_HELLO, 0, &part, 1) == ISM_FRAME_OK;
    }
    ism_frame_builder_free(&b);
    return ok;
}

static bool send_result(int fd, uint64_t job, const ism_pipeline_result *pr, long long start_ns)
{
    ism_frame_result r = {0};
    r.status = (uint32_t)pr->status;
    long long us = (ism_now_ns() - start_ns) / 1000;
    r.worker_us = us > (long long)UINT32_MAX ? UINT32_MAX : (uint32_t)us;
    snprintf(r.key, sizeof r.key, "%s", pr->key);
    snprintf(r.surface_key, sizeof r.surface_key, "%s", pr->surface_key);
    r.polygonised = pr->polygonised;
    /* a surface over the frame ceiling (1 GB) is not stored */
    bool surface = pr->status == 200 && pr->computed.len &&
                   pr->computed.len <= ISM_FRAME_MAX_PAYLOAD;
    r.surface_len = surface ? (uint32_t)pr->computed.len : 0;
    snprintf(r.format, sizeof r.format, "%s", pr->format);
    snprintf(r.content_type, sizeof r.content_type, "%s",
             pr->content_type ? pr->content_type : "application/octet-stream");
    r.body = pr->body.data;
    r.body_len = pr->body.len;
    r.stats = pr->stats.data;
    r.stats_len = pr->stats.len;
    r.features = pr->features.data;
    r.features_len = pr->features.len;
    r.canonical = pr->canonical.data;
    r.canonical_len = pr->canonical.len;
    ism_frame_builder head = {0};
    unsigned char tail[4];
    bool ok = ism_frame_result_encode(&r, &head, tail);
    if (ok) {
        ism_frame_part parts[3] = {{head.data, head.len}, {r.body, r.body_len}, {tail, 4}};
        ok = ism_frame_write_fd(fd, ISM_FRAME_RESULT, job, parts, 3) == ISM_FRAME_OK;
        /* the surface after the answer: the daemon has the mesh on its way to the client
         * while this crosses the pipe (frame.h surface_len) */
        ism_frame_part surf = {pr->computed.data, pr->computed.len};
        if (ok && surface)
            ok = ism_frame_write_fd(fd, ISM_FRAME_SURFACE, job, &surf, 1) == ISM_FRAME_OK;
    } else {
        ok = send_error(fd, job, 500, "result_too_large", "the result does not fit in a frame");
    }
    ism_frame_builder_free(&head);
    return ok;
}

static bool run_job(int out_fd, const ism_frame *f)
{
    ism_frame_job job;
    if (!ism_frame_job_decode(f, &job)) {
        fprintf(stderr, "isomesh worker: malformed request frame for job %llu\n",
                (unsigned long long)f->job);
        send_error(out_fd, f->job, 500, "bad_frame", "the worker received a malformed request");
        return false;
    }
    ism_pipeline_limits lim;
    ism_pipeline_limits_default(&lim);
    if (job.max_depth)
        lim.max_depth = (int)job.max_depth;
    if (job.max_triangles)
        lim.max_triangles = (size_t)job.max_triangles;
    if (job.max_memory)
        lim.max_memory = (size_t)job.max_memory;
    lim.threads = job.threads ? (int)job.threads : default_threads;

    progress_state ps = {.fd = out_fd, .job = f->job};
    pthread_mutex_init(&ps.lock, NULL);
    ism_pipeline_hooks hooks = {.progress = on_progress, .ctx = &ps, .cancel = NULL,
                                .keep_computed = true};
    ism_pipeline_result pr;
    memset(&pr, 0, sizeof pr);
    long long start = ism_now_ns();
    if (job.timeout_ms)
        hooks.deadline_ms = (double)start / 1e6 + SINGULAR_DEADLINE_SHARE * job.timeout_ms;
    const char *json = (const char *)job.json, *format = job.format[0] ? job.format : NULL;
    /* From the stored surface when there is one that fits; computed otherwise. */
    if (!job.computed_len ||
        (!ism_pipeline_encode_stored(json, job.json_len, format, &lim, job.computed,
                                     job.computed_len, &pr) && pr.status == 0)) {
        ism_pipeline_result_free(&pr);
        ism_pipeline_run(json, job.json_len, format, &lim, &hooks, &pr);
    }
    bool ok = !ps.failed && send_result(out_fd, f->job, &pr, start);
    ism_pipeline_result_free(&pr);
    pthread_mutex_destroy(&ps.lock);
    return ok;
}

/* Runs a tiny surface through the pipeline in every format before the sandbox closes, so that
 * whatever the libraries set up on first use (random seeds, tables, a sanitizer's runtime) is
 * set up while files can still be read. The first run uses the job threads (what threads set
 * up on first use), the other formats one thread: a threaded run hands work between threads
 * hundreds of times, and on a loaded machine each hand-off waits for a CPU, so a replacement
 * worker (after a preemption, a deadline, a crash) took seconds to say hello for 0.06 s of
 * CPU. */
static void warm_up(void)
{
    static const char req[] = "{\"expr\": \"x^2 + y^2 + z^2 - 0.5\", \"depth\": {\"min\": 2, \"max\": 3}}";
    ism_pipeline_limits lim;
    ism_pipeline_limits_default(&lim);
    for (int i = 0; i < ISM_FORMAT_COUNT; i++) {
        lim.threads = i == 0 ? default_threads : 1;
        ism_pipeline_result pr;
        memset(&pr, 0, sizeof pr);
        ism_pipeline_run(req, sizeof req - 1, ism_format_name((enum ism_format)i), &lim, NULL,
                         &pr);
        ism_pipeline_result_free(&pr);
    }
}

/* A sandboxed worker ends with _exit: exit handlers of libraries (a sanitizer's leak check
 * among them) may need system calls the sandbox refuses. */
static int worker_exit(int status)
{
    fflush(NULL);
    if (ism_sandbox_active())
        _exit(status);
    return status;
}

int ism_worker_main(int in_fd, int out_fd)
{
    signal(SIGPIPE, SIG_IGN);
    if (out_fd == STDOUT_FILENO) {
        int chan = fcntl(out_fd, F_DUPFD_CLOEXEC, 3);
        if (chan < 0 || dup2(STDERR_FILENO, STDOUT_FILENO) < 0) {
            perror("isomesh worker: moving the channel off stdout");
            return 1;
        }
        out_fd = chan;
    }
    default_threads = ism_threads_resolve(0);
    warm_up();
    char why[256];
    if (!ism_sandbox_enter(in_fd, out_fd, why, sizeof why)) {
        fprintf(stderr, "isomesh worker: cannot enter the sandbox: %s\n", why);
        return 1;
    }
    if (!send_hello(out_fd)) {
        perror("isomesh worker: writing hello");
        return worker_exit(1);
    }
    ism_frame_reader rd;
    ism_frame_reader_init(&rd, WORKER_MAX_REQUEST);
    for (;;) {
        ism_frame f = {0};
        ism_frame_status st = ism_frame_read_fd(&rd, in_fd, &f);
        if (st == ISM_FRAME_EOF) {
            ism_frame_reader_free(&rd);
            return worker_exit(0);
        }
        if (st != ISM_FRAME_OK) {
            fprintf(stderr, "isomesh worker: reading a request: %s%s%s\n",
                    ism_frame_status_name(st), st == ISM_FRAME_IO_ERROR ? ": " : "",
                    st == ISM_FRAME_IO_ERROR ? strerror(errno) : "");
            ism_frame_reader_free(&rd);
            return worker_exit(1);
        }
        bool ok = f.type == ISM_FRAME_REQUEST && run_job(out_fd, &f);
        if (f.type != ISM_FRAME_REQUEST)
            fprintf(stderr, "isomesh worker: unexpected frame type %d\n", (int)f.type);
        ism_frame_free(&f);
        if (!ok) {
            ism_frame_reader_free(&rd);
            return worker_exit(1);
        }
    }
}
