/* log.c — structured log lines (log.h): a fixed-size line buffer per call, text or JSON
 * escaping, UTC timestamps with milliseconds, one write(2) to stderr. */
#include "server/common/log.h"

#include <errno.h>
#include <math.h>
#include <pthread.h>
#include <stdarg.h>
#include <stdatomic.h>
#include <stdlib.h>
#include <stdio.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

#define LINE_MAX_BYTES 4096

static const char *log_program = "isomesh";
static ism_log_format log_format = ISM_LOG_TEXT;

void ism_log_setup(const char *program, ism_log_format format)
{
    log_program = program;
    log_format = format;
}

bool ism_log_parse_format(const char *s, ism_log_format *out)
{
    if (strcmp(s, "text") == 0)
        *out = ISM_LOG_TEXT;
    else if (strcmp(s, "json") == 0)
        *out = ISM_LOG_JSON;
    else
        return false;
    return true;
}

typedef struct line {
    char buf[LINE_MAX_BYTES];
    size_t len;
} line;

static void add_raw(line *l, const char *s, size_t n)
{
    size_t room = sizeof l->buf - 2 - l->len; /* keep room for '\n' */
    if (n > room)
        n = room;
    memcpy(l->buf + l->len, s, n);
    l->len += n;
}

static void add(line *l, const char *s)
{
    add_raw(l, s, strlen(s));
}

static void addf(line *l, const char *fmt, ...) __attribute__((format(printf, 2, 3)));
static void addf(line *l, const char *fmt, ...)
{
    char tmp[128];
    va_list ap;
    va_start(ap, fmt);
    int n = vsnprintf(tmp, sizeof tmp, fmt, ap);
    va_end(ap);
    if (n > 0)
        add_raw(l, tmp, (size_t)n < sizeof tmp ? (size_t)n : sizeof tmp - 1);
}

/* Decimal digits of v (the hot path: one per request's status and size; vsnprintf's format
 * parsing cost more than the line's copying). */
static void add_int(line *l, long long v)
{
    char tmp[24];
    char *p = tmp + sizeof tmp;
    unsigned long long u = v < 0 ? 0ULL - (unsigned long long)v : (unsigned long long)v;
    do {
        *--p = (char)('0' + u % 10);
        u /= 10;
    } while (u);
    if (v < 0)
        *--p = '-';
    add_raw(l, p, (size_t)(tmp + sizeof tmp - p));
}

/* v as exactly `width` digits, zero-padded (0 <= v < 10^width). */
static void add_padded(line *l, long v, int width)
{
    char tmp[8];
    for (int i = width - 1; i >= 0; i--, v /= 10)
        tmp[i] = (char)('0' + v % 10);
    add_raw(l, tmp, (size_t)width);
}

/* JSON string body (without quotes): escapes quotes, backslashes and control bytes. */
static void add_json_escaped(line *l, const char *s)
{
    for (; *s; s++) {
        unsigned char c = (unsigned char)*s;
        if (c == '"' || c == '\\') {
            char e[2] = {'\\', (char)c};
            add_raw(l, e, 2);
        } else if (c < 0x20 || c == 0x7f) {
            addf(l, "\\u%04x", c);
        } else {
            add_raw(l, (const char *)&c, 1);
        }
    }
}

/* Text value: bare when it is one safe word, quoted and escaped otherwise. */
static void add_text_value(line *l, const char *s)
{
    bool bare = *s != 0;
    for (const char *p = s; *p; p++)
        if ((unsigned char)*p <= ' ' || *p == '"' || *p == '=' || *p == '\\' || (unsigned char)*p == 0x7f)
            bare = false;
    if (bare) {
        add(l, s);
        return;
    }
    add(l, "\"");
    add_json_escaped(l, s);
    add(l, "\"");
}

static const char *level_name(ism_log_level level)
{
    switch (level) {
    case ISM_LOG_DEBUG: return "debug";
    case ISM_LOG_INFO: return "info";
    case ISM_LOG_WARN: return "warn";
    case ISM_LOG_ERROR: return "error";
    }
    return "info";
}

/* As "%.3f" writes it, without vsnprintf (a request's log line and its Server-Timing header:
 * the format parsing and exact decimal conversion were a third of the line's cost). Rounds
 * the value times 1000 to the nearest integer, which can differ from printf's exact rounding
 * only for values within one part in 10^16 of a half thousandth. Non-finite values and
 * magnitudes from 1e9 go to printf. */
size_t ism_log_number(char *out, size_t cap, double d)
{
    /* beyond 1e9 the product's rounding reaches the third decimal: printf's exact way */
    if (!(d > -1e9 && d < 1e9) || cap < 24) {
        int n = snprintf(out, cap, "%.3f", d);
        return n < 0 ? 0 : (size_t)n < cap ? (size_t)n : cap ? cap - 1 : 0;
    }
    long long v = llround(d * 1000.0);
    char digits[24];
    char *p = digits + sizeof digits;
    unsigned long long u = v < 0 ? 0ULL - (unsigned long long)v : (unsigned long long)v;
    for (int i = 0; i < 3; i++, u /= 10)
        *--p = (char)('0' + u % 10);
    *--p = '.';
    do {
        *--p = (char)('0' + u % 10);
        u /= 10;
    } while (u);
    if (v < 0 || signbit(d)) /* printf keeps the sign of a negative value rounding to 0 */
        *--p = '-';
    size_t n = (size_t)(digits + sizeof digits - p);
    memcpy(out, p, n);
    out[n] = 0;
    return n;
}

static void add_fixed3(line *l, double d)
{
    char t[40];
    add_raw(l, t, ism_log_number(t, sizeof t, d));
}

/* The line's UTC timestamp. The date and time of day up to the second are formatted once per
 * second per thread (gmtime_r and the digits were most of it); milliseconds every time. */
static void add_time(line *l)
{
    static _Thread_local time_t shown = -1;
    static _Thread_local char prefix[24];
    static _Thread_local size_t prefix_len;
    struct timespec ts;
    clock_gettime(CLOCK_REALTIME, &ts);
    if (ts.tv_sec != shown) {
        struct tm tm;
        gmtime_r(&ts.tv_sec, &tm);
        /* as "%04d-%02d-%02dT%02d:%02d:%02d." */
        const long parts[] = {tm.tm_year + 1900, tm.tm_mon + 1, tm.tm_mday, tm.tm_hour,
                              tm.tm_min, tm.tm_sec};
        const char seps[] = "--T::.";
        line p;
        p.len = 0;
        for (int i = 0; i < 6; i++) {
            add_padded(&p, parts[i] < 0 ? 0 : parts[i] % (i == 0 ? 10000 : 100), i == 0 ? 4 : 2);
            add_raw(&p, seps + i, 1);
        }
        memcpy(prefix, p.buf, p.len);
        prefix_len = p.len;
        shown = ts.tv_sec;
    }
    add_raw(l, prefix, prefix_len);
    add_padded(l, ts.tv_nsec / 1000000, 3);
    add_raw(l, "Z", 1);
}

static void write_all(const char *p, size_t left)
{
    while (left) {
        ssize_t w = write(STDERR_FILENO, p, left);
        if (w < 0 && errno == EINTR)
            continue;
        if (w <= 0)
            return;
        p += w;
        left -= (size_t)w;
    }
}

/* ---- the background writer ------------------------------------------------------------ */

#define ASYNC_CAPACITY (1u << 20)
/* The writer's gathering time: it wakes at most 1/BATCH_NS times a second under load. At
 * 10 ms its ~100 wake-ups a second were 0.07 context switches per cached-mesh request at
 * 256 connections on a loaded machine (~1000 req/s), a third of the daemon's; lines reach
 * stderr at most this much later (all are written out at a stop). */
#define BATCH_NS 50000000L /* 50 ms */

static struct {
    pthread_mutex_t lock;
    pthread_cond_t wake;
    char *ring;
    size_t head, len;          /* queued bytes start at head (mod capacity) */
    bool running, stopping;
    pthread_t thread;
} async = {.lock = PTHREAD_MUTEX_INITIALIZER, .wake = PTHREAD_COND_INITIALIZER};
static atomic_ullong dropped;

/* Queues one whole line; false when the writer is not running. */
static bool enqueue(const char *p, size_t n)
{
    pthread_mutex_lock(&async.lock);
    if (!async.running) {
        pthread_mutex_unlock(&async.lock);
        return false;
    }
    if (ASYNC_CAPACITY - async.len < n) {
        atomic_fetch_add(&dropped, 1);
    } else {
        bool was_empty = async.len == 0;
        size_t tail = (async.head + async.len) % ASYNC_CAPACITY;
        size_t first = n < ASYNC_CAPACITY - tail ? n : ASYNC_CAPACITY - tail;
        memcpy(async.ring + tail, p, first);
        memcpy(async.ring, p + first, n - first);
        async.len += n;
        if (was_empty) /* the writer sleeps only on an empty queue */
            pthread_cond_signal(&async.wake);
    }
    pthread_mutex_unlock(&async.lock);
    return true;
}

static void *writer_main(void *arg)
{
    (void)arg;
    char chunk[LINE_MAX_BYTES];
    pthread_mutex_lock(&async.lock);
    for (;;) {
        while (!async.len && !async.stopping)
            pthread_cond_wait(&async.wake, &async.lock);
        if (!async.len)
            break;
        if (!async.stopping && async.len < sizeof chunk) {
            /* gather a batch: under load, one wake-up and a few writes per BATCH_NS instead
             * of one per line */
            pthread_mutex_unlock(&async.lock);
            struct timespec ts = {0, BATCH_NS};
            nanosleep(&ts, NULL);
            pthread_mutex_lock(&async.lock);
        }
        /* whole lines only, at most one pipe-atomic write */
        size_t n = async.len < sizeof chunk ? async.len : sizeof chunk;
        size_t first = n < ASYNC_CAPACITY - async.head ? n : ASYNC_CAPACITY - async.head;
        memcpy(chunk, async.ring + async.head, first); /* the ring may wrap once within n */
        memcpy(chunk + first, async.ring, n - first);
        while (n > 0 && chunk[n - 1] != '\n')
            n--;
        if (n == 0) /* cannot happen: lines are shorter than a chunk */
            n = async.len < sizeof chunk ? async.len : sizeof chunk;
        async.head = (async.head + n) % ASYNC_CAPACITY;
        async.len -= n;
        pthread_mutex_unlock(&async.lock);
        write_all(chunk, n);
        pthread_mutex_lock(&async.lock);
    }
    pthread_mutex_unlock(&async.lock);
    return NULL;
}

void ism_log_async(bool on)
{
    pthread_mutex_lock(&async.lock);
    if (on && !async.running) {
        async.ring = malloc(ASYNC_CAPACITY);
        async.head = async.len = 0;
        async.stopping = false;
        async.running = async.ring && pthread_create(&async.thread, NULL, writer_main, NULL) == 0;
        if (!async.running) {
            free(async.ring);
            async.ring = NULL;
        }
        pthread_mutex_unlock(&async.lock);
        return;
    }
    if (!on && async.running) {
        async.stopping = true;
        pthread_cond_signal(&async.wake);
        pthread_mutex_unlock(&async.lock);
        pthread_join(async.thread, NULL);
        pthread_mutex_lock(&async.lock);
        async.running = false;
        free(async.ring);
        async.ring = NULL;
    }
    pthread_mutex_unlock(&async.lock);
}

unsigned long long ism_log_dropped(void)
{
    return atomic_load(&dropped);
}

static void emit(line *l)
{
    l->buf[l->len++] = '\n';
    if (!enqueue(l->buf, l->len))
        write_all(l->buf, l->len);
}

void ism_log_fields(ism_log_level level, const char *event, const ism_log_field *fields,
                    size_t n)
{
    line l; /* not zeroed: 4 KB per line (only buf[0, len) is ever read) */
    l.len = 0;
    if (log_format == ISM_LOG_JSON) {
        add(&l, "{\"ts\":\"");
        add_time(&l);
        add(&l, "\",\"level\":\"");
        add(&l, level_name(level));
        add(&l, "\",\"program\":\"");
        add_json_escaped(&l, log_program);
        add(&l, "\",\"event\":\"");
        add_json_escaped(&l, event);
        add(&l, "\"");
        for (size_t i = 0; i < n; i++) {
            add(&l, ",\"");
            add_json_escaped(&l, fields[i].name);
            add(&l, "\":");
            switch (fields[i].kind) {
            case ISM_LF_STR:
                if (fields[i].s) {
                    add(&l, "\"");
                    add_json_escaped(&l, fields[i].s);
                    add(&l, "\"");
                } else {
                    add(&l, "null");
                }
                break;
            case ISM_LF_INT: add_int(&l, fields[i].i); break;
            case ISM_LF_NUM: add_fixed3(&l, fields[i].d); break;
            }
        }
        if (l.len >= sizeof l.buf - 3)
            l.len = sizeof l.buf - 3; /* truncated: still close the object */
        add_raw(&l, "}", 1);
    } else {
        add_time(&l);
        add(&l, " ");
        add(&l, level_name(level));
        add(&l, " ");
        add(&l, log_program);
        add(&l, ": ");
        add(&l, event);
        for (size_t i = 0; i < n; i++) {
            add(&l, " ");
            add(&l, fields[i].name);
            add(&l, "=");
            switch (fields[i].kind) {
            case ISM_LF_STR: add_text_value(&l, fields[i].s ? fields[i].s : "-"); break;
            case ISM_LF_INT: add_int(&l, fields[i].i); break;
            case ISM_LF_NUM: add_fixed3(&l, fields[i].d); break;
            }
        }
    }
    emit(&l);
}

void ism_logf(ism_log_level level, const char *event, const char *fmt, ...)
{
    char msg[2048];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(msg, sizeof msg, fmt, ap);
    va_end(ap);
    ism_log_field f = ISM_LS("msg", msg);
    ism_log_fields(level, event, &f, 1);
}
