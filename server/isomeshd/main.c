/* main.c — isomeshd's start-up and shutdown: settings, logging, cache tiers, scheduler, jobs,
 * documents and static roots, the listening socket, the worker pool and the HTTP front; then
 * it waits for signals (SIGHUP re-reads the tokens file) and on SIGTERM/SIGINT stops in
 * order: refuse new connections, finish or cancel computations within a bound, end event
 * streams, let answers drain, stop HTTP, flush and close the cache. */
#include <errno.h>
#include <fcntl.h>
#include <netdb.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>
#include <sys/socket.h>
#include <sys/stat.h>
#include <unistd.h>

#include "core/util/parallel.h"
#include "core/version.h"
#include "proto/presets.h"
#include "server/common/cache_disk.h"
#include "server/common/cache_mem.h"
#include "server/common/cache_redis.h"
#include "server/common/fd_io.h"
#include "server/common/log.h"
#include "server/isomeshd/config.h"
#include "server/isomeshd/http.h"
#include "server/isomeshd/jobs.h"
#include "server/isomeshd/shared_cache.h"
#include "server/isomeshd/token_cmd.h"
#include "server/isomeshd/worker_pool.h"

#define DOC_MAX (8u << 20)
/* Bytes of new entries waiting for the disk (or Redis) writer: a quarter of --cache-mem, at
 * least DISK_WRITE_QUEUE_MIN. A writer that falls behind (a loaded machine, 128 connections
 * posting new surfaces) grew a fixed 256 MiB queue by ~30 MiB in 10 s with --cache-mem 4M
 * (tests/reliability/test_load.py); a longer queue only delays the writes, so while it holds
 * this much a put is skipped (isomesh_cache_store_failures_total; the entry stays in the memory
 * tier). The minimum keeps one computation's entries (mesh, body, stats) of a few MiB whole. */
#define DISK_WRITE_QUEUE_MIN ((size_t)8 << 20)
#define DISK_WRITE_QUEUE_SHARE 4 /* of --cache-mem */
#define REDIS_MAX_ENTRY ((size_t)128 << 20) /* larger meshes stay on the daemon that made them */
#define MAX_STOP_GRACE_S 10.0

/* Reads a whole small file into a blob (NULL when missing or too big). */
static ism_blob *load_doc(const char *dir, const char *name)
{
    if (!*dir)
        return NULL;
    char path[8192], err[256];
    snprintf(path, sizeof path, "%s/%s", dir, name);
    char *text;
    size_t len;
    if (ism_read_file(path, DOC_MAX, &text, &len, NULL, err, sizeof err) != 1)
        return NULL;
    ism_blob *b = ism_blob_copy(text, len);
    free(text);
    return b;
}

static void load_docs(ismd_server *s, const ismd_config *cfg)
{
    s->openapi = load_doc(cfg->data_dir, "openapi.yaml");
    s->schema = load_doc(cfg->data_dir, "request.schema.json");
    size_t plen = 0;
    char *presets = ism_presets_json(&plen);
    s->presets = presets ? ism_blob_copy(presets, plen) : NULL;
    free(presets);
    const char *missing[2];
    int n = 0;
    if (!s->openapi)
        missing[n++] = "openapi.yaml";
    if (!s->schema)
        missing[n++] = "request.schema.json";
    for (int i = 0; i < n; i++)
        ism_logf(ISM_LOG_WARN, "document_missing", "%s not found in --data-dir '%s'", missing[i],
                 cfg->data_dir);
}

static void open_static(ismd_server *s, const ismd_config *cfg)
{
    s->web.root_fd = s->vendor.root_fd = -1;
    if (!cfg->web_root[0])
        return;
    if (!ismd_static_open(&s->web, cfg->web_root)) {
        ism_logf(ISM_LOG_WARN, "web_root_unusable", "--web-root '%s': %s; serving no viewer",
                 cfg->web_root, strerror(errno));
        return;
    }
    char three[8192];
    snprintf(three, sizeof three, "%s/node_modules/three", s->web.root);
    if (!ismd_static_open(&s->vendor, three))
        ism_logf(ISM_LOG_WARN, "vendor_missing", "%s not found (run `make web-deps`)", three);
}

/* A listening TCP socket for host:port; -1 with a logged reason. */
static int listen_on(const char *host, unsigned short port, unsigned short *bound)
{
    struct addrinfo hints = {.ai_family = AF_UNSPEC, .ai_socktype = SOCK_STREAM,
                             .ai_flags = AI_PASSIVE | AI_NUMERICSERV};
    struct addrinfo *res = NULL;
    char portstr[8];
    snprintf(portstr, sizeof portstr, "%u", port);
    int rc = getaddrinfo(host, portstr, &hints, &res);
    if (rc != 0) {
        ism_logf(ISM_LOG_ERROR, "listen_failed", "--listen %s:%u: %s", host, port, gai_strerror(rc));
        return -1;
    }
    int fd = -1, err = 0;
    for (struct addrinfo *ai = res; ai; ai = ai->ai_next) {
        fd = socket(ai->ai_family, ai->ai_socktype | SOCK_CLOEXEC, ai->ai_protocol);
        if (fd < 0) {
            err = errno;
            continue;
        }
        int one = 1;
        setsockopt(fd, SOL_SOCKET, SO_REUSEADDR, &one, sizeof one);
        if (bind(fd, ai->ai_addr, ai->ai_addrlen) == 0 && listen(fd, 1024) == 0)
            break;
        err = errno;
        close(fd);
        fd = -1;
    }
    freeaddrinfo(res);
    if (fd < 0) {
        ism_logf(ISM_LOG_ERROR, "listen_failed", "--listen %s:%u: %s", host, port, strerror(err));
        return -1;
    }
    struct sockaddr_storage ss;
    socklen_t len = sizeof ss;
    *bound = port;
    if (getsockname(fd, (struct sockaddr *)&ss, &len) == 0) {
        if (ss.ss_family == AF_INET)
            *bound = ntohs(((struct sockaddr_in *)&ss)->sin_port);
        else if (ss.ss_family == AF_INET6)
            *bound = ntohs(((struct sockaddr_in6 *)&ss)->sin6_port);
    }
    return fd;
}

static void raise_fd_limit(void)
{
    struct rlimit rl;
    if (getrlimit(RLIMIT_NOFILE, &rl) == 0 && rl.rlim_cur < rl.rlim_max) {
        rl.rlim_cur = rl.rlim_max;
        setrlimit(RLIMIT_NOFILE, &rl);
    }
}

static bool setup_cache(ismd_server *s, const ismd_config *cfg)
{
    if (cfg->cache_mem) {
        ism_cache_tier *mem = ism_cache_mem_new(cfg->cache_mem);
        if (!mem || !ism_cache_add_tier(&s->cache, mem))
            return false;
    }
    size_t queue = cfg->cache_mem / DISK_WRITE_QUEUE_SHARE;
    if (queue < DISK_WRITE_QUEUE_MIN)
        queue = DISK_WRITE_QUEUE_MIN;
    s->disk = ism_cache_disk_new(cfg->cache_dir, queue);
    if (s->disk)
        ism_cache_disk_set_max(s->disk, cfg->cache_disk_max);
    if (!s->disk || !ism_cache_add_tier(&s->cache, s->disk))
        return false;
    if (!cfg->redis[0])
        return true;
    ism_redis_settings rs = {.max_pending = queue, .max_entry = REDIS_MAX_ENTRY};
    if (!ism_redis_parse_address(cfg->redis, rs.host, &rs.port)) /* checked by config.c */
        return false;
    snprintf(rs.namespace_, sizeof rs.namespace_, "%s", cfg->redis_namespace);
    char err[600];
    if (cfg->redis_password_file[0] &&
        !ism_redis_load_password(cfg->redis_password_file, &rs, err, sizeof err)) {
        ism_log_field f = ISM_LS("error", err);
        ism_log_fields(ISM_LOG_ERROR, "redis_password_unusable", &f, 1);
        return false;
    }
    s->redis = ism_cache_redis_new(&rs);
    explicit_bzero(rs.password, sizeof rs.password);
    if (!s->redis || !ism_cache_add_tier(&s->cache, s->redis))
        return false;
    s->metrics.redis = ism_cache_redis_counters(s->redis);
    return true;
}

int main(int argc, char **argv)
{
    if (argc >= 2 && !strcmp(argv[1], "token"))
        return ismd_token_command(argc - 1, argv + 1);
    static ismd_config cfg;
    int rc = ismd_config_load(&cfg, argc, argv);
    if (rc)
        return rc == 1 ? 0 : 2;
    ism_log_setup("isomeshd", cfg.log_format);
    signal(SIGPIPE, SIG_IGN);
    sigset_t stop_signals;
    sigemptyset(&stop_signals);
    sigaddset(&stop_signals, SIGTERM);
    sigaddset(&stop_signals, SIGINT);
    sigaddset(&stop_signals, SIGHUP); /* taken by sigwait below: reload, not stop */
    pthread_sigmask(SIG_BLOCK, &stop_signals, NULL); /* every thread inherits this */
    /* after the mask: a thread started earlier would take SIGTERM/SIGHUP's default action */
    ism_log_async(true); /* the HTTP thread never blocks on a slow log reader */
    raise_fd_limit();

    static ismd_server s;
    static ismd_auth auth;
    s.cfg = &cfg;
    s.listen_fd = -1;
    s.auth = &auth;
    char auth_err[600];
    if (!ismd_auth_init(&auth, cfg.tokens, cfg.private_mode, auth_err, sizeof auth_err)) {
        ism_log_field f = ISM_LS("error", auth_err);
        ism_log_fields(ISM_LOG_ERROR, "tokens_unusable", &f, 1);
        ism_log_async(false);
        return 1;
    }
    ismd_metrics_init(&s.metrics);
    ism_pipeline_limits_default(&s.limits);
    s.limits.max_depth = cfg.max_depth;
    s.limits.max_triangles = cfg.max_triangles;
    if (!setup_cache(&s, &cfg) ||
        !ismd_sched_init(&s.sched,
                         ismd_queue_new((size_t)cfg.queue, cfg.queue_fifo ? ISMD_ORDER_FIFO : ISMD_ORDER_FAIR,
                                        cfg.user_jobs, cfg.user_running, cfg.workers),
                         cfg.job_timeout_s, cfg.queue_timeout_s, &s.metrics) ||
        !(s.jobs = ismd_jobs_new(&s.metrics))) {
        ism_logf(ISM_LOG_ERROR, "startup_failed", "out of memory");
        ism_log_async(false);
        return 1;
    }
    ismd_cluster_settings cluster = {cfg.user_jobs, cfg.user_running, s.jobs};
    if (s.redis && !(s.shared = ismd_shared_start(&s.sched, &s.cache, s.redis, &s.limits,
                                                  cfg.redis_lock_ttl_s,
                                                  cfg.cluster ? &cluster : NULL))) {
        ism_logf(ISM_LOG_ERROR, "startup_failed", "out of memory");
        ism_log_async(false);
        return 1;
    }
    load_docs(&s, &cfg);
    open_static(&s, &cfg);

    unsigned short port = 0;
    int lfd = listen_on(cfg.listen_host, cfg.listen_port, &port);
    if (lfd < 0) {
        ism_log_async(false);
        return 1;
    }
    /* each worker an even share of the cores, at least 1 and at most what one computation
     * runs (a share above ISM_MAX_THREADS would make every request's mesher refuse it) */
    int threads = ism_threads_given(ism_cpu_count() / cfg.workers, 1);
    ismd_pool_config pc = {
        .workers = cfg.workers,
        .worker_path = cfg.worker_path,
        .job_memory = cfg.job_memory,
        .max_depth = cfg.max_depth,
        .max_triangles = cfg.max_triangles,
        .threads = threads,
    };
    s.pool = ismd_pool_start(&pc, &s.sched, &s.cache, &s.metrics);
    if (!s.pool || !ismd_http_start(&s, lfd)) {
        ism_log_async(false);
        return 1;
    }
    ism_log_field f[] = {
        ISM_LS("host", cfg.listen_host), ISM_LI("port", port), ISM_LI("workers", cfg.workers),
        ISM_LS("cache_dir", cfg.cache_dir), ISM_LS("web_root", s.web.root_fd >= 0 ? s.web.root : NULL),
        ISM_LS("data_dir", cfg.data_dir), ISM_LS("version", ISM_VERSION " " ISM_MESHER_VERSION),
        ISM_LS("redis", cfg.redis[0] ? cfg.redis : NULL),
    };
    ism_log_fields(ISM_LOG_INFO, "listening", f, sizeof f / sizeof f[0]);

    if (auth.enabled) {
        ism_log_field af[] = {ISM_LS("file", auth.path), ISM_LI("tokens", auth.table.n),
                              ISM_LS("private", cfg.private_mode ? "yes" : "no")};
        ism_log_fields(ISM_LOG_INFO, "access_control", af, 3);
    }
    int sig = 0;
    for (;;) {
        if (sigwait(&stop_signals, &sig) != 0)
            continue;
        if (sig != SIGHUP)
            break;
        ismd_auth_reload(&auth); /* connections and computations carry on */
    }
    ism_logf(ISM_LOG_INFO, "stopping", "signal %d: finishing in-flight work", sig);
    atomic_store(&s.draining, true);
    ismd_http_quiesce(&s);
    double grace = cfg.job_timeout_s < MAX_STOP_GRACE_S ? cfg.job_timeout_s : MAX_STOP_GRACE_S;
    ismd_pool_stop(s.pool, grace);
    if (s.shared)
        ismd_shared_stop(s.shared); /* releases the Redis locks this daemon holds */
    ismd_sched_lock(&s.sched);
    ismd_jobs_close_streams(s.jobs);
    ismd_sched_unlock(&s.sched);
    ismd_http_stop(&s, 3.0);
    ismd_jobs_free(s.jobs);
    ismd_sched_destroy(&s.sched);
    ism_cache_close(&s.cache);
    ism_blob_unref(s.openapi);
    ism_blob_unref(s.schema);
    ism_blob_unref(s.presets);
    ismd_static_close(&s.web);
    ismd_static_close(&s.vendor);
    ismd_auth_destroy(&auth);
    ism_logf(ISM_LOG_INFO, "stopped", "clean shutdown");
    ism_log_async(false);
    return 0;
}
