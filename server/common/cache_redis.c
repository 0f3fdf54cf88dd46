/* cache_redis.c — the shared Redis tier (cache_redis.h): the stored form of values, the one
 * connection and its failure handling (timeouts, outage logging, back-off), the write queue,
 * the task list, and the calls tasks make (fetch, locks). Only the tier's thread touches the
 * hiredis context. */
#include "server/common/cache_redis.h"
#include "server/common/fd_io.h"
#include "core/util/le_bytes.h"

#include <errno.h>
#include <fcntl.h>
#include <hiredis/hiredis.h>
#include <pthread.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <sys/time.h>
#include <unistd.h>
#include <time.h>

#include "proto/frame.h"
#include "server/common/log.h"

#define VALUE_VERSION 1
#define KEY_MAX (ISM_CACHE_NAME_MAX + 32)
#define BACKOFF_MIN_NS 100000000LL       /* first reconnect 100 ms after a failure */
#define BACKOFF_MAX_NS 2000000000LL      /* then doubling up to 2 s */
#define HEALTH_INTERVAL_NS 1000000000LL  /* an idle connection is pinged once a second */
#define CLOSE_FLUSH_NS 2000000000LL      /* at close, queued writes get this long */
#define CORRUPT_LOG_INTERVAL_S 10
#define PASSWORD_FILE_MAX 512

/* Compare-and-act scripts: only the holder's token may extend or release a lock. */
static const char RENEW_LUA[] =
    "if redis.call('get', KEYS[1]) == ARGV[1] then "
    "return redis.call('pexpire', KEYS[1], ARGV[2]) else return 0 end";
/* A lock without expiry, or with more of it left than any daemon ever gives (left by a bug,
 * an older version or an operator), would stop every daemon from computing that entry
 * forever: it is removed, and the caller told (2). Else 1 held, 0 free. */
static const char LOCKED_LUA[] =
    "local t = redis.call('pttl', KEYS[1]) "
    "if t == -2 then return 0 end "
    "if t == -1 or t > tonumber(ARGV[1]) then redis.call('del', KEYS[1]) return 2 end "
    "return 1";
/* A lock no daemon would have set (LOCKED_LUA) is taken over. */
static const char LOCK_KIN_LUA[] =
    "local t = redis.call('pttl', KEYS[1]) "
    "if t == -1 or t > tonumber(ARGV[2]) then redis.call('del', KEYS[1]) end "
    "if redis.call('set', KEYS[1], ARGV[1], 'NX', 'PX', ARGV[2]) then return 1 end "
    "local v = redis.call('get', KEYS[1]) "
    "if v and string.sub(v, 1, #ARGV[3]) == ARGV[3] then return 2 end "
    "return 0";
static const char UNLOCK_LUA[] =
    "if redis.call('get', KEYS[1]) == ARGV[1] then "
    "return redis.call('del', KEYS[1]) else return 0 end";

typedef struct put {
    struct put *next;
    ism_blob *blob;
    char name[ISM_CACHE_NAME_MAX];
} put;

typedef struct redis_tier {
    ism_cache_tier base;
    ism_redis_settings cfg;
    ism_redis_counters counters;
    char addr[280];                 /* host:port for log lines */
    char prefix[ISM_REDIS_PREFIX_MAX];       /* "<namespace>:v1:" */
    char lock_prefix[ISM_REDIS_PREFIX_MAX + 8];
    redisContext *ctx;              /* the tier's thread only */
    long long retry_at_ns, backoff_ns, down_since_ns, last_used_ns;
    bool outage_logged;
    time_t last_corrupt_log;
    pthread_t thread;
    bool thread_started;
    pthread_mutex_t lock;           /* guards everything below */
    pthread_cond_t wake;
    put *puts_head, *puts_tail;
    size_t pending_bytes;
    ism_redis_task *tasks;          /* unordered; scanned for due ones */
    bool stopping, closed;
} redis_tier;

/* ---- the stored form ----------------------------------------------------------------- */

static uint32_t value_crc(const char *name, const unsigned char *hdr, const void *data, size_t len)
{
    uint32_t c = ism_crc32c(0, name, strlen(name));
    c = ism_crc32c(c, hdr, 16);
    return ism_crc32c(c, data, len);
}

unsigned char *ism_redis_value_encode(const char *name, const ism_blob *b, size_t *len)
{
    if (b->len > SIZE_MAX - ISM_REDIS_HEADER_SIZE)
        return NULL;
    unsigned char *v = malloc(ISM_REDIS_HEADER_SIZE + b->len);
    if (!v)
        return NULL;
    memcpy(v, "ISMR", 4);
    ism_put_le32(v + 4, VALUE_VERSION);
    ism_put_le32(v + 8, (uint32_t)b->len);
    ism_put_le32(v + 12, (uint32_t)((uint64_t)b->len >> 32));
    ism_put_le32(v + 16, value_crc(name, v, b->data, b->len));
    ism_put_le32(v + 20, 0);
    memcpy(v + ISM_REDIS_HEADER_SIZE, b->data, b->len);
    *len = ISM_REDIS_HEADER_SIZE + b->len;
    return v;
}

ism_blob *ism_redis_value_decode(const char *name, const void *data, size_t len,
                                 const char **why)
{
    const unsigned char *v = data;
    *why = NULL;
    if (len < ISM_REDIS_HEADER_SIZE) {
        *why = "shorter than its header";
        return NULL;
    }
    if (memcmp(v, "ISMR", 4) != 0 || ism_get_le32(v + 4) != VALUE_VERSION || ism_get_le32(v + 20) != 0) {
        *why = "bad header";
        return NULL;
    }
    uint64_t n = (uint64_t)ism_get_le32(v + 8) | (uint64_t)ism_get_le32(v + 12) << 32;
    if (n != len - ISM_REDIS_HEADER_SIZE) {
        *why = "length does not match the value";
        return NULL;
    }
    if (value_crc(name, v, v + ISM_REDIS_HEADER_SIZE, (size_t)n) != ism_get_le32(v + 16)) {
        *why = "checksum mismatch";
        return NULL;
    }
    return ism_blob_copy(v + ISM_REDIS_HEADER_SIZE, (size_t)n);
}

bool ism_redis_parse_address(const char *s, char host[256], unsigned short *port)
{
    const char *colon = strrchr(s, ':');
    const char *h = s;
    size_t hl;
    long p = 6379;
    if (s[0] == '[') { /* [v6]:port */
        const char *close = strchr(s, ']');
        if (!close || close[1] != ':')
            return false;
        h = s + 1;
        hl = (size_t)(close - h);
        colon = close + 1;
    } else if (colon && strchr(s, ':') != colon) {
        return false; /* a bare IPv6 address needs brackets */
    } else {
        hl = colon ? (size_t)(colon - s) : strlen(s);
    }
    if (colon) {
        char *end;
        errno = 0;
        p = strtol(colon + 1, &end, 10);
        if (errno || end == colon + 1 || *end || p < 1 || p > 65535)
            return false;
    }
    if (hl == 0 || hl >= 256)
        return false;
    for (size_t i = 0; i < hl; i++) {
        char c = h[i];
        if (!((c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') ||
              c == '.' || c == '-' || c == '_' || c == ':'))
            return false;
    }
    memcpy(host, h, hl);
    host[hl] = 0;
    *port = (unsigned short)p;
    return true;
}

/* ---- the connection ------------------------------------------------------------------ */

static struct timeval ms_tv(int ms)
{
    return (struct timeval){.tv_sec = ms / 1000, .tv_usec = (ms % 1000) * 1000};
}

static void log_outage(redis_tier *rt, const char *what, const char *err)
{
    ism_log_field f[] = {ISM_LS("redis", rt->addr), ISM_LS("what", what), ISM_LS("error", err)};
    ism_log_fields(ISM_LOG_WARN, "redis_unavailable", f, sizeof f / sizeof f[0]);
}

/* A call failed: drop the connection, count, log the outage once, schedule a reconnect. */
static void conn_failed(redis_tier *rt, const char *what)
{
    char err[160] = "unreachable";
    if (rt->ctx) {
        if (rt->ctx->err)
            snprintf(err, sizeof err, "%s", rt->ctx->errstr);
        redisFree(rt->ctx);
        rt->ctx = NULL;
    }
    atomic_fetch_add(&rt->counters.errors, 1);
    long long now = ism_now_ns();
    if (!rt->outage_logged) {
        rt->outage_logged = true;
        rt->down_since_ns = now;
        atomic_fetch_add(&rt->counters.outages, 1);
        log_outage(rt, what, err);
    }
    atomic_store(&rt->counters.up, 0);
    rt->retry_at_ns = now + rt->backoff_ns;
    rt->backoff_ns = rt->backoff_ns * 2 > BACKOFF_MAX_NS ? BACKOFF_MAX_NS : rt->backoff_ns * 2;
}

/* AUTH [user] password on a new connection (never logged). */
static bool authenticate(redis_tier *rt)
{
    const char *argv[3] = {"AUTH"};
    size_t lens[3] = {4};
    int argc = 1;
    if (rt->cfg.username[0]) {
        argv[argc] = rt->cfg.username;
        lens[argc++] = strlen(rt->cfg.username);
    }
    argv[argc] = rt->cfg.password;
    lens[argc++] = strlen(rt->cfg.password);
    redisReply *r = redisCommandArgv(rt->ctx, argc, argv, lens);
    bool ok = r && r->type == REDIS_REPLY_STATUS && !strcmp(r->str, "OK");
    if (r)
        freeReplyObject(r);
    return ok;
}

static void connect_now(redis_tier *rt)
{
    redisContext *c = redisConnectWithTimeout(rt->cfg.host, rt->cfg.port,
                                              ms_tv(ISM_REDIS_CONNECT_TIMEOUT_MS));
    if (!c) {
        conn_failed(rt, "connect");
        return;
    }
    rt->ctx = c;
    if (c->err) {
        conn_failed(rt, "connect");
        return;
    }
    redisSetTimeout(c, ms_tv(ISM_REDIS_COMMAND_TIMEOUT_MS));
    redisEnableKeepAlive(c);
    if (rt->cfg.password[0] && !authenticate(rt)) {
        conn_failed(rt, "auth");
        return;
    }
    redisReply *r = redisCommand(c, "PING");
    bool ok = r && r->type == REDIS_REPLY_STATUS && !strcmp(r->str, "PONG");
    if (r)
        freeReplyObject(r);
    if (!ok) {
        conn_failed(rt, "ping");
        return;
    }
    long long now = ism_now_ns();
    rt->last_used_ns = now;
    rt->backoff_ns = BACKOFF_MIN_NS;
    atomic_store(&rt->counters.up, 1);
    atomic_fetch_add(&rt->counters.connects, 1);
    if (rt->outage_logged) {
        ism_log_field f[] = {ISM_LS("redis", rt->addr),
                             ISM_LN("down_s", (now - rt->down_since_ns) / 1e9)};
        ism_log_fields(ISM_LOG_INFO, "redis_recovered", f, 2);
    } else {
        ism_log_field f = ISM_LS("redis", rt->addr);
        ism_log_fields(ISM_LOG_INFO, "redis_connected", &f, 1);
    }
    rt->outage_logged = false;
}

/* Runs one command (argv form); NULL (connection dropped) on I/O failure or an error reply. */
static redisReply *command(redis_tier *rt, const char *what, int argc, const char **argv,
                           const size_t *lens)
{
    if (!rt->ctx)
        return NULL;
    redisReply *r = redisCommandArgv(rt->ctx, argc, argv, lens);
    if (!r || rt->ctx->err) {
        if (r)
            freeReplyObject(r);
        conn_failed(rt, what);
        return NULL;
    }
    rt->last_used_ns = ism_now_ns();
    if (r->type == REDIS_REPLY_ERROR) {
        /* Redis answered but refused (OOM, scripting disabled, ...): count and log, keep
         * the connection; the caller treats it as unavailable for this call. */
        atomic_fetch_add(&rt->counters.errors, 1);
        ism_log_field f[] = {ISM_LS("redis", rt->addr), ISM_LS("what", what),
                             ISM_LS("error", r->str)};
        ism_log_fields(ISM_LOG_WARN, "redis_error_reply", f, 3);
        freeReplyObject(r);
        return NULL;
    }
    return r;
}

const char *ism_cache_redis_prefix(const ism_cache_tier *t)
{
    return ((const redis_tier *)t)->prefix;
}

bool ism_redis_load_password(const char *path, ism_redis_settings *s, char *err, size_t cap)
{
    char *text;
    size_t n;
    unsigned mode = 0;
    int rc = ism_read_file(path, PASSWORD_FILE_MAX, &text, &n, &mode, err, cap);
    if (rc == 0)
        snprintf(err, cap, "%s: %s", path, strerror(ENOENT));
    if (rc <= 0)
        return false;
    if (mode & (S_IROTH | S_IWOTH)) {
        explicit_bzero(text, n);
        free(text);
        snprintf(err, cap, "%s: readable or writable by others (chmod o-rw it)", path);
        return false;
    }
    text[strcspn(text, "\r\n")] = 0; /* the first line: "PASSWORD" or "USER PASSWORD" */
    char *space = strchr(text, ' ');
    const char *user = space ? text : "", *pass = space ? space + 1 : text;
    if (space)
        *space = 0;
    bool ok = *pass && strlen(pass) < sizeof s->password && strlen(user) < sizeof s->username;
    if (ok) {
        memcpy(s->username, user, strlen(user) + 1); /* lengths checked above */
        memcpy(s->password, pass, strlen(pass) + 1);
    } else {
        snprintf(err, cap, "%s: expected one line, PASSWORD or USER PASSWORD", path);
    }
    explicit_bzero(text, n);
    free(text);
    return ok;
}

struct redisReply *ism_cache_redis_call(ism_cache_tier *t, const char *what, int argc,
                                       const char **argv, const size_t *lens)
{
    return command((redis_tier *)t, what, argc, argv, lens);
}

static bool entry_key(char out[KEY_MAX], const char *prefix, const char *name)
{
    return ism_cache_name_valid(name) && snprintf(out, KEY_MAX, "%s%s", prefix, name) < KEY_MAX;
}

/* ---- writes -------------------------------------------------------------------------- */

static void store_one(redis_tier *rt, const put *p)
{
    char key[KEY_MAX];
    size_t vlen = 0;
    unsigned char *v = entry_key(key, rt->prefix, p->name)
                           ? ism_redis_value_encode(p->name, p->blob, &vlen) : NULL;
    if (!v || !rt->ctx) {
        free(v);
        atomic_fetch_add(&rt->base.counters.store_failures, 1);
        return;
    }
    const char *argv[] = {"SET", key, (const char *)v};
    size_t lens[] = {3, strlen(key), vlen};
    redisReply *r = command(rt, "set", 3, argv, lens);
    free(v);
    if (r && r->type == REDIS_REPLY_STATUS)
        atomic_fetch_add(&rt->base.counters.stores, 1);
    else
        atomic_fetch_add(&rt->base.counters.store_failures, 1);
    if (r)
        freeReplyObject(r);
}

/* Writes queued puts until the queue is empty (or until deadline_ns, when not 0). */
static void write_puts(redis_tier *rt, long long deadline_ns)
{
    for (;;) {
        pthread_mutex_lock(&rt->lock);
        put *p = rt->puts_head;
        if (p) {
            rt->puts_head = p->next;
            if (!rt->puts_head)
                rt->puts_tail = NULL;
        }
        pthread_mutex_unlock(&rt->lock);
        if (!p)
            return;
        if (deadline_ns && ism_now_ns() > deadline_ns)
            atomic_fetch_add(&rt->base.counters.store_failures, 1);
        else
            store_one(rt, p);
        pthread_mutex_lock(&rt->lock);
        rt->pending_bytes -= p->blob->len;
        pthread_mutex_unlock(&rt->lock);
        ism_blob_unref(p->blob);
        free(p);
    }
}

void ism_cache_redis_flush(ism_cache_tier *t)
{
    write_puts((redis_tier *)t, 0);
}

static void redis_put(ism_cache_tier *t, const char *name, ism_blob *b)
{
    redis_tier *rt = (redis_tier *)t;
    if (!atomic_load(&rt->counters.up) || b->len > rt->cfg.max_entry ||
        strlen(name) >= ISM_CACHE_NAME_MAX) {
        atomic_fetch_add(&t->counters.store_failures, 1);
        return;
    }
    put *p = calloc(1, sizeof *p);
    if (!p) {
        atomic_fetch_add(&t->counters.store_failures, 1);
        return;
    }
    strcpy(p->name, name);
    pthread_mutex_lock(&rt->lock);
    /* as the disk tier: skipped only while the queue holds max_pending */
    if (rt->stopping || rt->pending_bytes >= rt->cfg.max_pending) {
        pthread_mutex_unlock(&rt->lock);
        free(p);
        atomic_fetch_add(&t->counters.store_failures, 1);
        return;
    }
    p->blob = ism_blob_ref(b);
    rt->pending_bytes += b->len;
    if (rt->puts_tail)
        rt->puts_tail->next = p;
    else
        rt->puts_head = p;
    rt->puts_tail = p;
    pthread_cond_signal(&rt->wake);
    pthread_mutex_unlock(&rt->lock);
}

/* ---- reads and locks (tasks only) ---------------------------------------------------- */

bool ism_cache_redis_up(ism_cache_tier *t)
{
    return ((redis_tier *)t)->ctx != NULL;
}

static void drop_corrupt(redis_tier *rt, const char *key, const char *name, const char *why)
{
    atomic_fetch_add(&rt->base.counters.corrupt, 1);
    const char *argv[] = {"DEL", key};
    size_t lens[] = {3, strlen(key)};
    redisReply *r = command(rt, "del", 2, argv, lens);
    if (r)
        freeReplyObject(r);
    time_t now = time(NULL);
    if (rt->last_corrupt_log && now - rt->last_corrupt_log < CORRUPT_LOG_INTERVAL_S)
        return;
    rt->last_corrupt_log = now;
    ism_log_field f[] = {ISM_LS("name", name), ISM_LS("why", why), ISM_LS("redis", rt->addr)};
    ism_log_fields(ISM_LOG_WARN, "redis_corrupt_entry_dropped", f, 3);
}

#define FETCH_MAX 8

int ism_cache_redis_fetch(ism_cache_tier *t, const char *const *names, size_t n, ism_blob **out)
{
    redis_tier *rt = (redis_tier *)t;
    char keys[FETCH_MAX][KEY_MAX];
    const char *argv[FETCH_MAX + 1] = {"MGET"};
    size_t lens[FETCH_MAX + 1] = {4};
    for (size_t i = 0; i < n; i++)
        out[i] = NULL;
    if (n == 0 || n > FETCH_MAX || !rt->ctx)
        return -1;
    for (size_t i = 0; i < n; i++) {
        if (!entry_key(keys[i], rt->prefix, names[i]))
            return -1;
        argv[i + 1] = keys[i];
        lens[i + 1] = strlen(keys[i]);
    }
    redisReply *r = command(rt, "mget", (int)n + 1, argv, lens);
    if (!r)
        return -1;
    if (r->type != REDIS_REPLY_ARRAY || r->elements != n) {
        freeReplyObject(r);
        conn_failed(rt, "mget reply");
        return -1;
    }
    for (size_t i = 0; i < n; i++) {
        redisReply *e = r->element[i];
        if (e->type != REDIS_REPLY_STRING)
            continue; /* nil: not there */
        const char *why;
        out[i] = ism_redis_value_decode(names[i], e->str, e->len, &why);
        if (!out[i] && why)
            drop_corrupt(rt, keys[i], names[i], why);
    }
    freeReplyObject(r);
    return 0;
}

/* An integer reply of a one-key command; -1 when unavailable. */
static long long int_command(redis_tier *rt, const char *what, int argc, const char **argv,
                             const size_t *lens)
{
    redisReply *r = command(rt, what, argc, argv, lens);
    if (!r)
        return -1;
    long long v = r->type == REDIS_REPLY_INTEGER ? r->integer : -1;
    freeReplyObject(r);
    return v;
}

/* EXISTS over names[0..n) with prefix: how many exist, or -1. */
static int exists(redis_tier *rt, const char *prefix, const char *const *names, size_t n)
{
    char keys[FETCH_MAX][KEY_MAX];
    const char *argv[FETCH_MAX + 1] = {"EXISTS"};
    size_t lens[FETCH_MAX + 1] = {6};
    if (!rt->ctx || n == 0 || n > FETCH_MAX)
        return -1;
    for (size_t i = 0; i < n; i++) {
        if (!entry_key(keys[i], prefix, names[i]))
            return -1;
        argv[i + 1] = keys[i];
        lens[i + 1] = strlen(keys[i]);
    }
    long long v = int_command(rt, "exists", (int)n + 1, argv, lens);
    return v < 0 || v > (long long)n ? -1 : (int)v;
}

int ism_cache_redis_count(ism_cache_tier *t, const char *const *names, size_t n)
{
    return exists((redis_tier *)t, ((redis_tier *)t)->prefix, names, n);
}


int ism_cache_redis_lock(ism_cache_tier *t, const char *name, const char *token, long ttl_ms)
{
    redis_tier *rt = (redis_tier *)t;
    char key[KEY_MAX], ttl[24];
    if (!rt->ctx || !entry_key(key, rt->lock_prefix, name))
        return -1;
    snprintf(ttl, sizeof ttl, "%ld", ttl_ms);
    const char *argv[] = {"SET", key, token, "NX", "PX", ttl};
    size_t lens[] = {3, strlen(key), strlen(token), 2, 2, strlen(ttl)};
    redisReply *r = command(rt, "lock", 6, argv, lens);
    if (!r)
        return -1;
    int got = r->type == REDIS_REPLY_STATUS ? 1 : r->type == REDIS_REPLY_NIL ? 0 : -1;
    freeReplyObject(r);
    return got;
}

int ism_cache_redis_lock_kin(ism_cache_tier *t, const char *name, const char *token,
                             long ttl_ms, const char *kin)
{
    redis_tier *rt = (redis_tier *)t;
    char key[KEY_MAX], ttl[24];
    if (!rt->ctx || !entry_key(key, rt->lock_prefix, name))
        return -1;
    snprintf(ttl, sizeof ttl, "%ld", ttl_ms);
    const char *argv[] = {"EVAL", LOCK_KIN_LUA, "1", key, token, ttl, kin};
    size_t lens[] = {4, strlen(LOCK_KIN_LUA), 1, strlen(key), strlen(token), strlen(ttl),
                     strlen(kin)};
    long long v = int_command(rt, "lock_kin", 7, argv, lens);
    return v < 0 || v > 2 ? -1 : (int)v;
}

static int script(redis_tier *rt, const char *what, const char *lua, const char *name,
                  const char *token, const char *extra)
{
    char key[KEY_MAX];
    if (!rt->ctx || !entry_key(key, rt->lock_prefix, name))
        return -1;
    const char *argv[] = {"EVAL", lua, "1", key, token, extra};
    size_t lens[] = {4, strlen(lua), 1, strlen(key), strlen(token), extra ? strlen(extra) : 0};
    long long v = int_command(rt, what, extra ? 6 : 5, argv, lens);
    return v < 0 ? -1 : v > 0;
}

int ism_cache_redis_locked(ism_cache_tier *t, const char *name, long max_ttl_ms)
{
    redis_tier *rt = (redis_tier *)t;
    char key[KEY_MAX], ttl[24];
    if (!rt->ctx || !entry_key(key, rt->lock_prefix, name))
        return -1;
    snprintf(ttl, sizeof ttl, "%ld", max_ttl_ms);
    const char *argv[] = {"EVAL", LOCKED_LUA, "1", key, ttl};
    size_t lens[] = {4, strlen(LOCKED_LUA), 1, strlen(key), strlen(ttl)};
    long long v = int_command(rt, "locked", 5, argv, lens);
    return v < 0 ? -1 : (int)v;
}

int ism_cache_redis_renew(ism_cache_tier *t, const char *name, const char *token, long ttl_ms)
{
    char ttl[24];
    snprintf(ttl, sizeof ttl, "%ld", ttl_ms);
    return script((redis_tier *)t, "renew", RENEW_LUA, name, token, ttl);
}

int ism_cache_redis_unlock(ism_cache_tier *t, const char *name, const char *token)
{
    return script((redis_tier *)t, "unlock", UNLOCK_LUA, name, token, NULL);
}

/* ---- tasks --------------------------------------------------------------------------- */

void ism_cache_redis_schedule(ism_cache_tier *t, ism_redis_task *task, long long due_ns)
{
    redis_tier *rt = (redis_tier *)t;
    pthread_mutex_lock(&rt->lock);
    if (rt->closed) { /* too late for the thread: let the task clean up here */
        pthread_mutex_unlock(&rt->lock);
        task->run(task, t, true);
        return;
    }
    task->due_ns = due_ns;
    task->next = rt->tasks;
    rt->tasks = task;
    pthread_cond_signal(&rt->wake);
    pthread_mutex_unlock(&rt->lock);
}

/* Takes the due tasks (all of them when every is set) off the list; lock held. */
static ism_redis_task *take_due(redis_tier *rt, long long now, bool every)
{
    ism_redis_task *due = NULL, **p = &rt->tasks;
    while (*p) {
        ism_redis_task *k = *p;
        if (every || k->due_ns <= now) {
            *p = k->next;
            k->next = due;
            due = k;
        } else {
            p = &k->next;
        }
    }
    return due;
}

static void run_tasks(redis_tier *rt, ism_redis_task *list, bool stopping)
{
    while (list) {
        ism_redis_task *k = list;
        list = k->next;
        k->next = NULL;
        long long again = k->run(k, &rt->base, stopping);
        if (again && !stopping) {
            pthread_mutex_lock(&rt->lock);
            k->due_ns = again;
            k->next = rt->tasks;
            rt->tasks = k;
            pthread_mutex_unlock(&rt->lock);
        }
    }
}

/* ---- the thread ---------------------------------------------------------------------- */

static long long next_wake(redis_tier *rt, long long now)
{
    long long next = now + HEALTH_INTERVAL_NS;
    if (!rt->ctx && rt->retry_at_ns < next)
        next = rt->retry_at_ns;
    if (rt->ctx && rt->last_used_ns + HEALTH_INTERVAL_NS < next)
        next = rt->last_used_ns + HEALTH_INTERVAL_NS;
    for (ism_redis_task *k = rt->tasks; k; k = k->next)
        if (k->due_ns < next)
            next = k->due_ns;
    return next;
}

static void health_check(redis_tier *rt, long long now)
{
    if (!rt->ctx || now - rt->last_used_ns < HEALTH_INTERVAL_NS)
        return;
    const char *argv[] = {"PING"};
    size_t lens[] = {4};
    redisReply *r = command(rt, "ping", 1, argv, lens);
    if (r)
        freeReplyObject(r);
}

static void *redis_main(void *arg)
{
    redis_tier *rt = arg;
    pthread_mutex_lock(&rt->lock);
    while (!rt->stopping) {
        long long now = ism_now_ns();
        long long wake_at = next_wake(rt, now);
        if (!rt->puts_head && wake_at > now) {
            struct timespec ts = {.tv_sec = wake_at / 1000000000LL, .tv_nsec = wake_at % 1000000000LL};
            pthread_cond_timedwait(&rt->wake, &rt->lock, &ts);
            continue;
        }
        ism_redis_task *due = take_due(rt, now, false);
        pthread_mutex_unlock(&rt->lock);
        if (!rt->ctx && now >= rt->retry_at_ns)
            connect_now(rt);
        write_puts(rt, 0);
        run_tasks(rt, due, false);
        health_check(rt, ism_now_ns());
        pthread_mutex_lock(&rt->lock);
    }
    pthread_mutex_unlock(&rt->lock);
    /* Closing: queued writes get a bounded time, then every task cleans up (locks go). */
    write_puts(rt, ism_now_ns() + CLOSE_FLUSH_NS);
    pthread_mutex_lock(&rt->lock);
    ism_redis_task *all = take_due(rt, 0, true);
    rt->closed = true;
    pthread_mutex_unlock(&rt->lock);
    run_tasks(rt, all, true);
    if (rt->ctx) {
        redisFree(rt->ctx);
        rt->ctx = NULL;
    }
    atomic_store(&rt->counters.up, 0);
    return NULL;
}

/* ---- the tier interface -------------------------------------------------------------- */

/* Reads never come through the cache stack (the tier is remote): see cache_redis.h. */
static ism_blob *redis_get(ism_cache_tier *t, const char *name)
{
    (void)t;
    (void)name;
    return NULL;
}

static bool redis_has(ism_cache_tier *t, const char *name)
{
    (void)t;
    (void)name;
    return false;
}

static void redis_close(ism_cache_tier *t)
{
    redis_tier *rt = (redis_tier *)t;
    pthread_mutex_lock(&rt->lock);
    rt->stopping = true;
    pthread_cond_signal(&rt->wake);
    pthread_mutex_unlock(&rt->lock);
    if (rt->thread_started)
        pthread_join(rt->thread, NULL);
    write_puts(rt, 1); /* only when the thread never ran: drops (and counts) what is queued */
    pthread_mutex_destroy(&rt->lock);
    pthread_cond_destroy(&rt->wake);
    free(rt);
}

ism_redis_counters *ism_cache_redis_counters(ism_cache_tier *t)
{
    return &((redis_tier *)t)->counters;
}

ism_cache_tier *ism_cache_redis_new(const ism_redis_settings *settings)
{
    redis_tier *rt = calloc(1, sizeof *rt);
    if (!rt)
        return NULL;
    rt->cfg = *settings;
    snprintf(rt->prefix, sizeof rt->prefix, "%s:v1:",
             settings->namespace_[0] ? settings->namespace_ : ISM_REDIS_DEFAULT_NAMESPACE);
    snprintf(rt->lock_prefix, sizeof rt->lock_prefix, "%slock:", rt->prefix);
    snprintf(rt->addr, sizeof rt->addr, strchr(rt->cfg.host, ':') ? "[%s]:%u" : "%s:%u",
             rt->cfg.host, rt->cfg.port);
    rt->backoff_ns = BACKOFF_MIN_NS;
    pthread_mutex_init(&rt->lock, NULL);
    pthread_condattr_t ca;
    pthread_condattr_init(&ca);
    pthread_condattr_setclock(&ca, CLOCK_MONOTONIC);
    pthread_cond_init(&rt->wake, &ca);
    pthread_condattr_destroy(&ca);
    rt->base.name = "redis";
    rt->base.remote = true;
    rt->base.get = redis_get;
    rt->base.has = redis_has;
    rt->base.put = redis_put;
    rt->base.close = redis_close;
    if (pthread_create(&rt->thread, NULL, redis_main, rt) != 0) {
        pthread_mutex_destroy(&rt->lock);
        pthread_cond_destroy(&rt->wake);
        free(rt);
        return NULL;
    }
    rt->thread_started = true;
    return &rt->base;
}
