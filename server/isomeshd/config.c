/* config.c — isomeshd's flag table (config.h): names, defaults, value parsers (counts, byte
 * sizes with K/M/G suffixes, durations with ms/s/m/h), the `--config FILE` reader and --help.
 * One table drives all three, so a flag cannot exist in one and be missing in another. */
#include "server/isomeshd/config.h"

#include <arpa/inet.h>
#include <ctype.h>
#include <errno.h>
#include <limits.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "core/version.h"
#include "server/common/cache_redis.h"

typedef enum kind {
    K_LISTEN, K_INT, K_SIZE, K_DURATION, K_PATH, K_STRING, K_LOGFMT, K_BOOL, K_ORDER, K_REDIS
} kind;

typedef struct flag {
    const char *name;
    kind kind;
    long long min, max;     /* K_INT, K_SIZE bounds */
    const char *arg;        /* placeholder in --help */
    const char *help;
    const char *def;        /* the default, as a value of this flag: set_defaults applies it
                               and --help shows it; NULL = computed in set_defaults (or none) */
    const char *shown;      /* --help's words for the default when def is not them */
} flag;

static const flag FLAGS[] = {
    {"listen", K_LISTEN, 0, 0, "HOST:PORT",
     "address to serve HTTP on; port 0 picks a free port (logged)",
     "127.0.0.1:8080", NULL},
    {"workers", K_INT, 1, 256, "N", "worker processes computing meshes",
     NULL, "one per online core"},
    {"queue", K_INT, 0, 100000, "N",
     "computations waiting for a worker before new ones get 503",
     "64", NULL},
    {"user-jobs", K_INT, 1, 100000, "N",
     "computations one user (token user, else client address) may have queued or running "
     "before 429",
     "32", NULL},
    {"client-jobs", K_INT, 1, 100000, "N", "old name of --user-jobs",
     NULL, NULL},
    {"user-running", K_INT, 0, 256, "N",
     "computations of one user on workers at once, the rest wait; 0 = every worker while no "
     "other user waits, half of them (rounded up) while others do: a user above that gives "
     "one back (preempted, requeued) to a user below it",
     "0", NULL},
    {"queue-order", K_ORDER, 0, 0, "fair|fifo",
     "fair: waiting computations are served round robin across users; fifo: oldest first",
     "fair", NULL},
    {"tokens", K_PATH, 0, 0, "FILE",
     "bearer tokens file (`isomeshd token add NAME`): computing needs a token; re-read on "
     "SIGHUP",
     NULL, "none: open to all"},
    {"private", K_BOOL, 0, 0, "",
     "with --tokens, reading (meshes, jobs, presets, documents, /metrics) needs a token too; "
     "the viewer's files, /healthz and /readyz stay open",
     "off", NULL},
    {"cache-dir", K_PATH, 0, 0, "DIR",
     "disk cache directory",
     NULL, "$XDG_CACHE_HOME/isomesh, else $HOME/.cache/isomesh"},
    {"cache-mem", K_SIZE, 0, (long long)1 << 40, "BYTES",
     "in-memory cache size, e.g. 512M; 0 disables it",
     "256M", NULL},
    {"cache-disk-max", K_SIZE, 0, (long long)1 << 50, "BYTES",
     "disk cache size; past it the least recently used entries are removed; 0 = no bound",
     "4G", NULL},
    {"redis", K_REDIS, 0, 0, "HOST:PORT",
     "shared cache in this Redis server: daemons using the same one serve each other's "
     "meshes and compute identical requests once (deploy/README.md)",
     NULL, "none"},
    {"redis-namespace", K_STRING, 0, 0, "NAME",
     "first part of every Redis key (NAME:v1:...): services with different names share one "
     "Redis without seeing each other's meshes, locks or queue; 1-48 of A-Z a-z 0-9 . _ -",
     ISM_REDIS_DEFAULT_NAMESPACE, NULL},
    {"redis-password-file", K_PATH, 0, 0, "FILE",
     "AUTH to Redis with the first line of FILE, PASSWORD or USER PASSWORD (a Redis ACL "
     "user); FILE must not be readable by others",
     NULL, "none"},
    {"cluster", K_BOOL, 0, 0, "",
     "with --redis, one queue for every daemon sharing that Redis: computations wait in "
     "per-user Redis streams and run on whichever daemon has an idle worker (users served in "
     "turn, --user-jobs and --user-running, and its default half share, held over every "
     "daemon's workers); a daemon that dies has its "
     "computations re-run elsewhere after --redis-lock-ttl (deploy/README.md)",
     "off", NULL},
    {"redis-lock-ttl", K_DURATION, 0, 0, "TIME",
     "lifetime of a computation's lock in Redis, extended while it runs: the longest wait "
     "for a daemon that died mid-computation; at least 500ms",
     "10s", NULL},
    {"job-timeout", K_DURATION, 0, 0, "TIME",
     "deadline of one computation from its start on a worker, e.g. 90s, 500ms",
     "60s", NULL},
    {"queue-timeout", K_DURATION, 0, 0, "TIME",
     "longest wait of a computation for a free worker; past it the request gets 503 "
     "queue_timeout (a synchronous request waits at most queue-timeout + job-timeout)",
     "60s", NULL},
    {"job-memory", K_SIZE, 0, (long long)1 << 42, "BYTES",
     "address-space limit of each worker process; 0 = none",
     "4G", NULL},
    {"max-body", K_SIZE, 1024, (long long)64 << 20, "BYTES", "largest request body",
     "256K", NULL},
    {"upload-memory", K_SIZE, 1024, (long long)1 << 40, "BYTES",
     "memory all request bodies being received may hold at once; beyond it a request gets "
     "503",
     "64M", NULL}, /* 256 bodies of the largest --max-body */
    {"conn-timeout", K_DURATION, 0, 0, "TIME",
     "close a connection idle this long (one waiting for its computation never is); at "
     "least 1s",
     "30s", NULL},
    {"client-conns", K_INT, 0, 100000, "N",
     "connections one address may hold open at once; behind a proxy keep it above the "
     "proxy's connections; 0 = no limit",
     "512", NULL},
    {"max-connections", K_INT, 16, 20000, "N",
     "connections the daemon holds at once; at the limit an address holding fewer than the "
     "largest holder still gets in (that holder's longest-idle connection is closed, else "
     "its newest), others are refused at once",
     "4000", NULL},
    {"header-timeout", K_DURATION, 0, 0, "TIME",
     "a request's headers must arrive within this time of the connection being ready for "
     "them (accepted, or its previous answer done), however they trickle; also bounds an "
     "idle kept-alive connection; at least 1s",
     "30s", NULL},
    {"body-timeout", K_DURATION, 0, 0, "TIME",
     "a request's body must arrive within this time of its headers, however it trickles; "
     "at least 1s",
     "60s", NULL},
    {"http-threads", K_INT, 1, 256, "N",
     "threads serving HTTP connections (at least; one per core is started with the own "
     "sender, two per core with --own-sender=off)",
     "1", NULL}, /* at least: http.c starts as many as the connection limit needs */
    {"tcp-congestion", K_STRING, 0, 0, "NAME",
     "TCP congestion control of the daemon's connections (one of "
     "net.ipv4.tcp_allowed_congestion_control, e.g. reno, cubic); behind nginx on the same "
     "host, where the system's is bbr without the fq qdisc, a non-pacing one costs less CPU",
     NULL, "the system's"},
    {"own-sender", K_BOOL, 0, 0, "",
     "cached meshes are sent by the daemon's own sender (header block held back, then "
     "sendfile, as nginx sends a file) where libmicrohttpd would push the header block "
     "alone (respond.c); other requests, and idle connections, stay libmicrohttpd's; "
     "its connections count against the same limits; not started behind --trusted-proxy "
     "or with --private (it would take no request there); --own-sender=off leaves every "
     "connection to libmicrohttpd",
     "on", NULL},
    {"max-depth", K_INT, 1, 16, "N", "deepest octree a request may ask for",
     "10", NULL},
    {"max-triangles", K_INT, 1, 1000000000LL, "N",
     "most triangles a request may produce",
     "4000000", NULL},
    {"web-root", K_PATH, 0, 0, "DIR",
     "the viewer's directory, served at /; \"\" serves no files",
     NULL, "web/ of the source tree"},
    {"data-dir", K_PATH, 0, 0, "DIR",
     "directory with openapi.yaml and request.schema.json",
     NULL, "proto/ of the source tree"},
    {"cors-origin", K_STRING, 0, 0, "ORIGIN",
     "value of Access-Control-Allow-Origin, e.g. * or https://example.org",
     NULL, "none"},
    {"trusted-proxy", K_STRING, 0, 0, "ADDR[,ADDR]",
     "reverse proxies (e.g. nginx at 127.0.0.1) whose X-Real-IP header names the client for "
     "per-user limits and fair scheduling without tokens",
     NULL, "none"},
    {"log-format", K_LOGFMT, 0, 0, "text|json", "log line format on stderr",
     "text", NULL},
};
#define NFLAGS (sizeof FLAGS / sizeof FLAGS[0])

/* ---- value parsers ------------------------------------------------------------------- */

/* A kernel congestion control's name: lower-case letters, digits, '_' (at most 15: the
 * kernel's TCP_CA_NAME_MAX with its terminator). Whether the kernel has it is known only
 * when the listening socket takes it (http.c). */
static bool valid_congestion_name(const char *v)
{
    size_t n = strlen(v);
    if (n == 0 || n > 15)
        return false;
    for (const char *p = v; *p; p++)
        if (!((*p >= 'a' && *p <= 'z') || (*p >= '0' && *p <= '9') || *p == '_'))
            return false;
    return true;
}

/* "ADDR[,ADDR...]": IPv4 or IPv6 literals. */
static bool valid_address_list(const char *v)
{
    char buf[512];
    if (!*v || strlen(v) >= sizeof buf)
        return false;
    snprintf(buf, sizeof buf, "%s", v);
    char *save = NULL;
    for (char *a = strtok_r(buf, ",", &save); a; a = strtok_r(NULL, ",", &save)) {
        unsigned char bin[16];
        if (inet_pton(AF_INET, a, bin) != 1 && inet_pton(AF_INET6, a, bin) != 1)
            return false;
    }
    return true;
}

/* A Redis key namespace: 1-48 of A-Z a-z 0-9 . _ - (no ':' : it separates the key's parts). */
static bool valid_namespace(const char *v)
{
    size_t n = strlen(v);
    if (n == 0 || n > 48)
        return false;
    for (const char *p = v; *p; p++)
        if (!isalnum((unsigned char)*p) && *p != '.' && *p != '_' && *p != '-')
            return false;
    return true;
}

static bool parse_ll(const char *s, long long *out)
{
    if (!*s || isspace((unsigned char)*s))
        return false;
    char *end;
    errno = 0;
    long long v = strtoll(s, &end, 10);
    if (errno || *end)
        return false;
    *out = v;
    return true;
}

/* "512", "64K", "256M", "4G", "1T", also with "B" or "iB" after the letter. */
static bool parse_size(const char *s, long long *out)
{
    if (!isdigit((unsigned char)*s))
        return false;
    char *end;
    errno = 0;
    unsigned long long v = strtoull(s, &end, 10);
    if (errno)
        return false;
    unsigned shift = 0;
    switch (toupper((unsigned char)*end)) {
    case 'K': shift = 10, end++; break;
    case 'M': shift = 20, end++; break;
    case 'G': shift = 30, end++; break;
    case 'T': shift = 40, end++; break;
    default: break;
    }
    if (shift && (*end == 'i' || *end == 'I'))
        end++;
    if (*end == 'B' || *end == 'b')
        end++;
    if (*end || (shift && v > (ULLONG_MAX >> shift)) || (v << shift) > (unsigned long long)LLONG_MAX)
        return false;
    *out = (long long)(v << shift);
    return true;
}

/* "60", "60s", "500ms", "2m", "1h" -> seconds. */
static bool parse_duration(const char *s, double *out)
{
    if (!isdigit((unsigned char)*s) && *s != '.')
        return false;
    char *end;
    errno = 0;
    double v = strtod(s, &end);
    if (errno || !isfinite(v) || v < 0)
        return false;
    double scale;
    if (!*end || strcmp(end, "s") == 0)
        scale = 1;
    else if (strcmp(end, "ms") == 0)
        scale = 1e-3;
    else if (strcmp(end, "m") == 0 || strcmp(end, "min") == 0)
        scale = 60;
    else if (strcmp(end, "h") == 0)
        scale = 3600;
    else
        return false;
    *out = v * scale;
    return *out >= 0.001 && *out <= 7 * 86400.0;
}

/* "HOST:PORT", "[V6]:PORT", ":PORT" (all interfaces), "PORT" (loopback). */
static bool parse_listen(const char *s, ismd_config *cfg)
{
    const char *colon = strrchr(s, ':');
    const char *port = colon ? colon + 1 : s;
    char host[256] = "127.0.0.1";
    if (colon) {
        size_t n = (size_t)(colon - s);
        if (n >= sizeof host)
            return false;
        memcpy(host, s, n);
        host[n] = 0;
        if (n >= 2 && host[0] == '[' && host[n - 1] == ']') {
            memmove(host, host + 1, n - 2);
            host[n - 2] = 0;
        } else if (strchr(host, ':') || strchr(host, '[') || strchr(host, ']')) {
            return false; /* an IPv6 address needs brackets */
        }
        if (n == 0)
            strcpy(host, "0.0.0.0");
    }
    long long p;
    if (!parse_ll(port, &p) || p < 0 || p > 65535)
        return false;
    snprintf(cfg->listen_host, sizeof cfg->listen_host, "%s", host);
    cfg->listen_port = (unsigned short)p;
    return true;
}

static const char *describe(const flag *f)
{
    static char buf[160];
    switch (f->kind) {
    case K_LISTEN: return "expected HOST:PORT, [IPV6]:PORT, :PORT or PORT";
    case K_INT:
        snprintf(buf, sizeof buf, "expected a whole number from %lld to %lld", f->min, f->max);
        return buf;
    case K_SIZE:
        snprintf(buf, sizeof buf, "expected a size like 65536, 64K, 256M or 4G, at least %lld bytes", f->min);
        return buf;
    case K_DURATION: return "expected a duration like 60, 90s, 500ms, 2m (1 ms to 7 days)";
    case K_PATH: return "expected a path shorter than 4096 bytes";
    case K_STRING:
        return !strcmp(f->name, "tcp-congestion")
                   ? "expected a congestion control's name (a-z, 0-9, _; at most 15)"
                   : "expected a short string without control characters";
    case K_LOGFMT: return "expected text or json";
    case K_BOOL: return "expected true or false";
    case K_ORDER: return "expected fair or fifo";
    case K_REDIS: return "expected HOST:PORT, [IPV6]:PORT or HOST (port 6379), or \"\" for none";
    }
    return "bad value";
}

static bool set_path(char *dst, size_t cap, const char *v)
{
    return snprintf(dst, cap, "%s", v) < (int)cap;
}

/* Applies one name=value; false when the value is bad. */
static bool apply(ismd_config *cfg, const flag *f, const char *v)
{
    long long n;
    double d;
    const char *name = f->name;
    switch (f->kind) {
    case K_LISTEN: return parse_listen(v, cfg);
    case K_INT:
        if (!parse_ll(v, &n) || n < f->min || n > f->max)
            return false;
        if (!strcmp(name, "workers")) cfg->workers = (int)n;
        else if (!strcmp(name, "queue")) cfg->queue = (int)n;
        else if (!strcmp(name, "user-jobs") || !strcmp(name, "client-jobs")) cfg->user_jobs = (int)n;
        else if (!strcmp(name, "user-running")) cfg->user_running = (int)n;
        else if (!strcmp(name, "max-depth")) cfg->max_depth = (int)n;
        else if (!strcmp(name, "max-triangles")) cfg->max_triangles = (size_t)n;
        else if (!strcmp(name, "client-conns")) cfg->client_conns = (int)n;
        else if (!strcmp(name, "http-threads")) cfg->http_threads = (int)n;
        else if (!strcmp(name, "max-connections")) cfg->max_conns = (unsigned)n;
        return true;
    case K_SIZE:
        if (!parse_size(v, &n) || n < f->min || n > f->max)
            return false;
        if (!strcmp(name, "cache-mem")) cfg->cache_mem = (size_t)n;
        else if (!strcmp(name, "job-memory")) cfg->job_memory = (size_t)n;
        else if (!strcmp(name, "max-body")) cfg->max_body = (size_t)n;
        else if (!strcmp(name, "upload-memory")) cfg->upload_memory = (size_t)n;
        else if (!strcmp(name, "cache-disk-max")) cfg->cache_disk_max = (unsigned long long)n;
        return true;
    case K_DURATION:
        if (!parse_duration(v, &d))
            return false;
        if (!strcmp(name, "redis-lock-ttl")) {
            if (d < 0.5)
                return false;
            cfg->redis_lock_ttl_s = d;
        } else if (!strcmp(name, "conn-timeout")) {
            if (d < 1)
                return false;
            cfg->conn_timeout_s = (unsigned)(d + 0.5);
        } else if (!strcmp(name, "header-timeout") || !strcmp(name, "body-timeout")) {
            if (d < 1)
                return false;
            *(name[0] == 'h' ? &cfg->header_timeout_s : &cfg->body_timeout_s) = d;
        } else if (!strcmp(name, "queue-timeout")) {
            cfg->queue_timeout_s = d;
        } else {
            cfg->job_timeout_s = d;
        }
        return true;
    case K_PATH:
        if (!strcmp(name, "cache-dir"))
            return *v && set_path(cfg->cache_dir, sizeof cfg->cache_dir, v);
        if (!strcmp(name, "web-root"))
            return set_path(cfg->web_root, sizeof cfg->web_root, v);
        if (!strcmp(name, "data-dir"))
            return set_path(cfg->data_dir, sizeof cfg->data_dir, v);
        if (!strcmp(name, "tokens"))
            return set_path(cfg->tokens, sizeof cfg->tokens, v);
        if (!strcmp(name, "redis-password-file"))
            return set_path(cfg->redis_password_file, sizeof cfg->redis_password_file, v);
        return false;
    case K_STRING:
        for (const char *p = v; *p; p++)
            if ((unsigned char)*p < 0x20 || *p == 0x7f)
                return false;
        if (!strcmp(name, "redis-namespace"))
            return valid_namespace(v) && set_path(cfg->redis_namespace, sizeof cfg->redis_namespace, v);
        if (!strcmp(name, "trusted-proxy"))
            return valid_address_list(v) &&
                   set_path(cfg->trusted_proxy, sizeof cfg->trusted_proxy, v);
        if (!strcmp(name, "tcp-congestion"))
            return valid_congestion_name(v) &&
                   set_path(cfg->tcp_congestion, sizeof cfg->tcp_congestion, v);
        return set_path(cfg->cors_origin, sizeof cfg->cors_origin, v);
    case K_LOGFMT: return ism_log_parse_format(v, &cfg->log_format);
    case K_BOOL: {
        bool *b = !strcmp(name, "cluster")      ? &cfg->cluster
                  : !strcmp(name, "own-sender") ? &cfg->own_sender
                                                : &cfg->private_mode;
        if (!strcmp(v, "true") || !strcmp(v, "yes") || !strcmp(v, "1") || !strcmp(v, "on"))
            *b = true;
        else if (!strcmp(v, "false") || !strcmp(v, "no") || !strcmp(v, "0") || !strcmp(v, "off"))
            *b = false;
        else
            return false;
        return true;
    }
    case K_ORDER:
        if (strcmp(v, "fair") != 0 && strcmp(v, "fifo") != 0)
            return false;
        cfg->queue_fifo = !strcmp(v, "fifo");
        return true;
    case K_REDIS: {
        char host[256];
        unsigned short port;
        if (*v && !ism_redis_parse_address(v, host, &port))
            return false;
        return set_path(cfg->redis, sizeof cfg->redis, v);
    }
    }
    return false;
}

static const flag *find_flag(const char *name, size_t len)
{
    for (size_t i = 0; i < NFLAGS; i++)
        if (strlen(FLAGS[i].name) == len && strncmp(FLAGS[i].name, name, len) == 0)
            return &FLAGS[i];
    return NULL;
}

/* ---- defaults ------------------------------------------------------------------------ */

static bool is_dir(const char *p)
{
    struct stat st;
    return stat(p, &st) == 0 && S_ISDIR(st.st_mode);
}

/* The directory holding this executable ("" when unknown). */
static void exe_dir(char *out, size_t cap)
{
    char buf[4096];
    ssize_t n = readlink("/proc/self/exe", buf, sizeof buf - 1);
    out[0] = 0;
    if (n <= 0)
        return;
    buf[n] = 0;
    char *slash = strrchr(buf, '/');
    if (!slash)
        return;
    *slash = 0;
    snprintf(out, cap, "%s", buf);
}

/* First existing directory among <exe>/../../<name> (the source tree, build/<kind>/isomeshd)
 * and ./<name>; "" when none. */
static void source_tree_dir(char *out, size_t cap, const char *exe, const char *name)
{
    char cand[8192];
    out[0] = 0;
    if (*exe) {
        snprintf(cand, sizeof cand, "%s/../../%s", exe, name);
        if (is_dir(cand) && realpath(cand, out) && strlen(out) < cap)
            return;
        out[0] = 0;
    }
    if (is_dir(name))
        snprintf(out, cap, "%s", name);
}

static void set_defaults(ismd_config *cfg)
{
    memset(cfg, 0, sizeof *cfg);
    for (size_t i = 0; i < NFLAGS; i++)
        if (FLAGS[i].def && !apply(cfg, &FLAGS[i], FLAGS[i].def))
            abort(); /* a default that its own parser refuses: a bug in FLAGS */
    long cores = sysconf(_SC_NPROCESSORS_ONLN);
    cfg->workers = cores < 1 ? 1 : cores > 256 ? 256 : (int)cores;
    const char *xdg = getenv("XDG_CACHE_HOME");
    const char *home = getenv("HOME");
    if (xdg && *xdg == '/')
        snprintf(cfg->cache_dir, sizeof cfg->cache_dir, "%s/isomesh", xdg);
    else if (home && *home == '/')
        snprintf(cfg->cache_dir, sizeof cfg->cache_dir, "%s/.cache/isomesh", home);
    else
        snprintf(cfg->cache_dir, sizeof cfg->cache_dir, "/tmp/isomesh-cache-%ld", (long)getuid());
    char exe[4096];
    exe_dir(exe, sizeof exe);
    source_tree_dir(cfg->web_root, sizeof cfg->web_root, exe, "web");
    source_tree_dir(cfg->data_dir, sizeof cfg->data_dir, exe, "proto");
    if (snprintf(cfg->worker_path, sizeof cfg->worker_path, "%s/isomesh", *exe ? exe : ".") >=
        (int)sizeof cfg->worker_path)
        strcpy(cfg->worker_path, "./isomesh");
}

/* ---- help, config file, argv --------------------------------------------------------- */

static void print_help(void)
{
    printf("usage: isomeshd [--config FILE] [--FLAG VALUE | --FLAG=VALUE]...\n"
           "       isomeshd token add|remove|list ... (bearer tokens; see the end)\n\n"
           "isomeshd serves meshes of implicit surfaces f(x,y,z) = 0 over HTTP, computed by a\n"
           "pool of `isomesh --worker` processes (the isomesh program next to isomeshd) and\n"
           "cached in memory and on disk. Every flag has a default; --config FILE reads lines\n"
           "`name = value` with the flag names below (# starts a comment); flags given on the\n"
           "command line override the file.\n\nflags:\n");
    for (size_t i = 0; i < NFLAGS; i++) {
        char left[64];
        snprintf(left, sizeof left, "--%s %s", FLAGS[i].name, FLAGS[i].arg);
        const char *d = FLAGS[i].shown ? FLAGS[i].shown : FLAGS[i].def;
        if (d)
            printf("  %-28s %s [%s]\n", left, FLAGS[i].help, d);
        else
            printf("  %-28s %s\n", left, FLAGS[i].help);
    }
    printf("  %-28s %s\n", "--config FILE", "read settings from FILE first");
    printf("  %-28s %s\n", "--help, --version", "print this or the version and exit");
    printf("\nroutes: POST /v1/mesh, POST|GET /v1/jobs, GET|DELETE /v1/jobs/{id},\n"
           "GET /v1/jobs/{id}/events, GET /v1/meshes/{key}.{drc,glb,ply,obj,stl},\n"
           "GET /v1/meshes/{key}/stats, GET /v1/meshes/{key}/features, GET /v1/presets,\n"
           "GET /v1/openapi.yaml, GET /v1/request.schema.json, GET /healthz, GET /readyz,\n"
           "GET /metrics, the viewer at / and three.js under /vendor/three/.\n"
           "SIGTERM or SIGINT: stop accepting, finish or cancel running jobs, exit.\n"
           "SIGHUP: re-read the --tokens file (a file that does not parse keeps the old one).\n"
           "\nisomeshd token add NAME [--file FILE] [--jobs N] [--running N] [--admin] prints a\n"
           "new token once and appends its hash to FILE; `token remove NAME`, `token list`.\n");
}

static char *trim(char *s)
{
    while (isspace((unsigned char)*s))
        s++;
    char *e = s + strlen(s);
    while (e > s && isspace((unsigned char)e[-1]))
        *--e = 0;
    return s;
}

static int load_file(ismd_config *cfg, const char *path)
{
    FILE *fp = fopen(path, "r");
    if (!fp) {
        fprintf(stderr, "isomeshd: --config %s: %s\n", path, strerror(errno));
        return 2;
    }
    char line[8192];
    int lineno = 0;
    while (fgets(line, sizeof line, fp)) {
        lineno++;
        if (!strchr(line, '\n') && !feof(fp)) {
            fprintf(stderr, "isomeshd: %s:%d: line too long\n", path, lineno);
            fclose(fp);
            return 2;
        }
        char *hash = strchr(line, '#');
        if (hash)
            *hash = 0;
        char *s = trim(line);
        if (!*s)
            continue;
        char *eq = strchr(s, '=');
        if (!eq) {
            fprintf(stderr, "isomeshd: %s:%d: expected `name = value`\n", path, lineno);
            fclose(fp);
            return 2;
        }
        *eq = 0;
        char *name = trim(s), *value = trim(eq + 1);
        size_t vl = strlen(value);
        if (vl >= 2 && value[0] == '"' && value[vl - 1] == '"') {
            value[vl - 1] = 0;
            value++;
        }
        const flag *f = find_flag(name, strlen(name));
        if (!f) {
            fprintf(stderr, "isomeshd: %s:%d: unknown setting '%s' (see --help)\n", path, lineno, name);
            fclose(fp);
            return 2;
        }
        if (!apply(cfg, f, value)) {
            fprintf(stderr, "isomeshd: %s:%d: %s: bad value '%s': %s\n", path, lineno, name,
                    value, describe(f));
            fclose(fp);
            return 2;
        }
    }
    fclose(fp);
    return 0;
}

/* Splits argv[i] into a flag name and value ("--name=value" or "--name value"). */
static int next_flag(int argc, char **argv, int *i, const char **name, size_t *nlen,
                     const char **value)
{
    const char *a = argv[*i];
    if (strncmp(a, "--", 2) != 0) {
        fprintf(stderr, "isomeshd: unexpected argument '%s' (see --help)\n", a);
        return 2;
    }
    *name = a + 2;
    const char *eq = strchr(*name, '=');
    if (eq) {
        *nlen = (size_t)(eq - *name);
        *value = eq + 1;
        return 0;
    }
    *nlen = strlen(*name);
    const flag *f = find_flag(*name, *nlen);
    if (f && f->kind == K_BOOL) { /* --private alone means true */
        *value = "true";
        return 0;
    }
    if (*i + 1 >= argc) {
        fprintf(stderr, "isomeshd: %s needs a value (see --help)\n", a);
        return 2;
    }
    const char *next = argv[*i + 1];
    if (!strncmp(next, "--", 2) && find_flag(next + 2, strcspn(next + 2, "="))) {
        /* `--listen --cache-dir DIR`: the value was forgotten, not "--cache-dir" */
        fprintf(stderr, "isomeshd: %s needs a value (the next word, '%s', is a flag)\n", a,
                next);
        return 2;
    }
    *value = argv[++*i];
    return 0;
}

int ismd_config_load(ismd_config *cfg, int argc, char **argv)
{
    set_defaults(cfg);
    for (int i = 1; i < argc; i++) {
        if (!strcmp(argv[i], "--help") || !strcmp(argv[i], "-h")) {
            print_help();
            return 1;
        }
        if (!strcmp(argv[i], "--version")) {
            printf("isomeshd %s (%s)\n", ISM_VERSION, ISM_MESHER_VERSION);
            return 1;
        }
    }
    /* The config file first, wherever --config appears. */
    for (int i = 1; i < argc; i++) {
        const char *name, *value;
        size_t nlen;
        int rc = next_flag(argc, argv, &i, &name, &nlen, &value);
        if (rc)
            return rc;
        if (nlen == 6 && !strncmp(name, "config", 6) && (rc = load_file(cfg, value)))
            return rc;
    }
    for (int i = 1; i < argc; i++) {
        const char *name, *value;
        size_t nlen;
        next_flag(argc, argv, &i, &name, &nlen, &value);
        if (nlen == 6 && !strncmp(name, "config", 6))
            continue;
        const flag *f = find_flag(name, nlen);
        if (!f) {
            fprintf(stderr, "isomeshd: unknown flag --%.*s (see --help)\n", (int)nlen, name);
            return 2;
        }
        if (!apply(cfg, f, value)) {
            fprintf(stderr, "isomeshd: --%s: bad value '%s': %s\n", f->name, value, describe(f));
            return 2;
        }
    }
    if (cfg->private_mode && !cfg->tokens[0]) {
        fprintf(stderr, "isomeshd: --private needs --tokens FILE\n");
        return 2;
    }
    if (cfg->cluster && !cfg->redis[0]) {
        fprintf(stderr, "isomeshd: --cluster needs --redis HOST:PORT\n");
        return 2;
    }
    return 0;
}
