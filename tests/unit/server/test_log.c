/* test_log.c — structured log lines (server/common/log.h): JSON lines parse and keep every
 * field, awkward values are escaped, background writing keeps every line whole and in order,
 * and a log reader that stops reading never blocks the caller (lines are dropped and
 * counted instead). */
#include <criterion/criterion.h>
#include <ctype.h>
#include <limits.h>
#include <math.h>
#include <jansson.h>
#include <pthread.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

#include "server/common/log.h"

typedef struct capture {
    int read_fd, saved_stderr;
    char *text;
    size_t len, cap;
    pthread_t thread;
} capture;

static void *drain(void *arg)
{
    capture *c = arg;
    char buf[8192];
    ssize_t n;
    while ((n = read(c->read_fd, buf, sizeof buf)) > 0) {
        if (c->len + (size_t)n + 1 > c->cap) {
            c->cap = (c->len + (size_t)n + 1) * 2;
            c->text = realloc(c->text, c->cap);
        }
        memcpy(c->text + c->len, buf, (size_t)n);
        c->len += (size_t)n;
        c->text[c->len] = 0;
    }
    return NULL;
}

/* Points stderr at a pipe read by a thread. */
static void capture_start(capture *c)
{
    memset(c, 0, sizeof *c);
    int p[2];
    cr_assert_eq(pipe(p), 0);
    c->read_fd = p[0];
    c->saved_stderr = dup(STDERR_FILENO);
    dup2(p[1], STDERR_FILENO);
    close(p[1]);
    pthread_create(&c->thread, NULL, drain, c);
}

static void capture_stop(capture *c)
{
    dup2(c->saved_stderr, STDERR_FILENO);
    close(c->saved_stderr);
    pthread_join(c->thread, NULL);
    close(c->read_fd);
    if (!c->text)
        c->text = calloc(1, 1);
}

Test(log, json_lines_parse_and_escape)
{
    ism_log_setup("test", ISM_LOG_JSON);
    capture c;
    capture_start(&c);
    ism_log_field f[] = {ISM_LS("path", "/a \"quoted\"\\path\n\x01"), ISM_LI("status", 404),
                         ISM_LN("ms", 1.25), ISM_LS("key", NULL)};
    ism_log_fields(ISM_LOG_WARN, "request", f, 4);
    capture_stop(&c);
    cr_assert_eq(strchr(c.text, '\n'), c.text + c.len - 1, "not exactly one line: %s", c.text);
    json_error_t err;
    json_t *o = json_loads(c.text, 0, &err);
    cr_assert_not_null(o, "%s: %s", err.text, c.text);
    cr_assert_str_eq(json_string_value(json_object_get(o, "path")), "/a \"quoted\"\\path\n\x01");
    cr_assert_eq(json_integer_value(json_object_get(o, "status")), 404);
    cr_assert_float_eq(json_number_value(json_object_get(o, "ms")), 1.25, 1e-9);
    cr_assert(json_is_null(json_object_get(o, "key")));
    cr_assert_str_eq(json_string_value(json_object_get(o, "level")), "warn");
    cr_assert_str_eq(json_string_value(json_object_get(o, "event")), "request");
    json_decref(o);
    free(c.text);
}

/* Integers and the timestamp are written without printf: compared with printf's own "%lld"
 * and with the UTC time read around the call (strftime). */
Test(log, integers_and_timestamp_match_printf)
{
    ism_log_setup("test", ISM_LOG_TEXT);
    const long long vals[] = {0, 7, -1, 404, 1234567890123LL, LLONG_MAX, LLONG_MIN};
    enum { NV = sizeof vals / sizeof vals[0] };
    capture c;
    capture_start(&c);
    /* the log reads CLOCK_REALTIME; time() reads the coarse clock, which can still show the
     * last second just after the fine clock turned over (07:21:44.000 vs 43: seen in CI) */
    struct timespec t0, t1;
    clock_gettime(CLOCK_REALTIME, &t0);
    time_t before = t0.tv_sec;
    for (int i = 0; i < NV; i++) {
        ism_log_field f = ISM_LI("v", vals[i]);
        ism_log_fields(ISM_LOG_INFO, "n", &f, 1);
    }
    clock_gettime(CLOCK_REALTIME, &t1);
    time_t after = t1.tv_sec;
    capture_stop(&c);
    char *line = c.text;
    for (int i = 0; i < NV; i++) {
        char want[48], ts0[32], ts1[32];
        snprintf(want, sizeof want, " info test: n v=%lld\n", vals[i]);
        cr_assert(!strncmp(line + 24, want, strlen(want)), "%.80s vs %s", line, want);
        strftime(ts0, sizeof ts0, "%Y-%m-%dT%H:%M:%S", gmtime(&before));
        strftime(ts1, sizeof ts1, "%Y-%m-%dT%H:%M:%S", gmtime(&after));
        cr_assert(strncmp(line, ts0, 19) >= 0 && strncmp(line, ts1, 19) <= 0, "%.24s", line);
        cr_assert(line[19] == '.' && isdigit((unsigned char)line[20]) &&
                  isdigit((unsigned char)line[21]) && isdigit((unsigned char)line[22]) &&
                  line[23] == 'Z', "%.24s", line);
        line = strchr(line, '\n') + 1;
    }
    free(c.text);
}

/* Numbers (ISM_LF_NUM, Server-Timing) are written without printf: compared with printf's own
 * "%.3f" on values of every magnitude, both signs, exact thousandths and values just beside
 * them, and the non-finite ones printf writes itself. */
Test(log, numbers_match_printf)
{
    const double fixed[] = {0.0, -0.0, 0.0004, -0.0004, 0.0006, 1.25, 0.001, 0.999, 0.9996,
                            12.5, 999.9999, 1e-9, 123456789.123, -42.042, 1e14 + 0.25, 1e15,
                            -1e16, 3.0e300, INFINITY, -INFINITY, NAN};
    char got[64], want[400];
    for (size_t i = 0; i < sizeof fixed / sizeof fixed[0]; i++) {
        size_t n = ism_log_number(got, sizeof got, fixed[i]);
        snprintf(want, sizeof want, "%.3f", fixed[i]);
        cr_assert_str_eq(got, strlen(want) < sizeof got ? want : got, "%.17g", fixed[i]);
        cr_assert_eq(n, strlen(got));
    }
    /* milliseconds as a request's timings give them: microsecond steps, away from halves */
    unsigned seed = 12345;
    for (int i = 0; i < 20000; i++) {
        seed = seed * 1103515245u + 12345u;
        double v = (double)(seed % 100000000u) / 1e6 + 1e-7; /* [0, 100) ms */
        if (i & 1)
            v = -v;
        ism_log_number(got, sizeof got, v);
        snprintf(want, sizeof want, "%.3f", v);
        cr_assert_str_eq(got, want, "%.17g", v);
    }
    cr_assert_eq(ism_log_number(got, 4, 1234.5), 3); /* a short buffer: printf's truncation */
    cr_assert_str_eq(got, "123");
}

Test(log, text_values_with_spaces_are_quoted)
{
    ism_log_setup("test", ISM_LOG_TEXT);
    capture c;
    capture_start(&c);
    ism_log_field f[] = {ISM_LS("a", "plain"), ISM_LS("b", "two words"), ISM_LS("c", "")};
    ism_log_fields(ISM_LOG_INFO, "thing", f, 3);
    capture_stop(&c);
    cr_assert(strstr(c.text, " a=plain "), "%s", c.text);
    cr_assert(strstr(c.text, " b=\"two words\" "), "%s", c.text);
    cr_assert(strstr(c.text, " c=\"\"\n"), "%s", c.text);
    free(c.text);
}

Test(log, background_writer_keeps_lines_whole_and_in_order)
{
    ism_log_setup("test", ISM_LOG_JSON);
    capture c;
    capture_start(&c);
    ism_log_async(true);
    char pad[1500];
    memset(pad, 'x', sizeof pad - 1);
    pad[sizeof pad - 1] = 0;
    for (int i = 0; i < 3000; i++) {
        /* under 1 MiB in all, so nothing may be dropped even if the writer never ran */
        ism_log_field f[] = {ISM_LI("i", i), ISM_LS("pad", i % 10 ? "" : pad)};
        ism_log_fields(ISM_LOG_INFO, "n", f, 2);
    }
    ism_log_async(false);
    capture_stop(&c);
    cr_assert_eq(ism_log_dropped(), 0);
    int next = 0;
    for (char *line = strtok(c.text, "\n"); line; line = strtok(NULL, "\n")) {
        json_t *o = json_loads(line, 0, NULL);
        cr_assert_not_null(o, "a broken line: %.80s", line);
        cr_assert_eq(json_integer_value(json_object_get(o, "i")), next);
        next++;
        json_decref(o);
    }
    cr_assert_eq(next, 3000);
    free(c.text);
}

static void give_up(int sig)
{
    (void)sig;
    _exit(3); /* the caller blocked: the test fails as a crash */
}

Test(log, a_stuck_reader_never_blocks_the_caller)
{
    signal(SIGPIPE, SIG_IGN);
    signal(SIGALRM, give_up);
    ism_log_setup("test", ISM_LOG_TEXT);
    int p[2];
    cr_assert_eq(pipe(p), 0); /* nobody reads p[0] */
    int saved = dup(STDERR_FILENO);
    dup2(p[1], STDERR_FILENO);
    ism_log_async(true);
    alarm(20);
    for (int i = 0; i < 40000; i++) { /* ~4 MB of lines into a 64 KB pipe */
        ism_log_field f[] = {ISM_LI("i", i), ISM_LS("filler", "0123456789012345678901234567890123456789012345678901234567890123456789")};
        ism_log_fields(ISM_LOG_INFO, "flood", f, 2);
    }
    alarm(0);
    unsigned long long lost = ism_log_dropped();
    close(p[0]); /* the writer's blocked write now fails and it can finish */
    ism_log_async(false); /* the rest goes into the broken pipe, not the console */
    dup2(saved, STDERR_FILENO);
    close(saved);
    close(p[1]);
    cr_assert_gt(lost, 0, "a full queue must drop lines");
}
