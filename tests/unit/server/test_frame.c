/* test_frame.c — the worker framing (proto/frame.h): CRC-32C against its published check
 * value and the bitwise definition, frames surviving one-byte reads and writes through a
 * real pipe, every kind of damage (checksum, magic, type, length over the limit, truncation)
 * detected, non-blocking reads resuming where they stopped, and the REQUEST/RESULT payloads
 * decoding to what was encoded. */
#include <criterion/criterion.h>
#include <errno.h>
#include <fcntl.h>
#include <pthread.h>
#include <signal.h>
#include <stdlib.h>
#include <string.h>
#include <sys/wait.h>
#include <unistd.h>

#include "proto/frame.h"

/* Bit-at-a-time CRC-32C, straight from the definition. */
static uint32_t crc_reference(const unsigned char *p, size_t n)
{
    uint32_t c = 0xffffffffu;
    for (size_t i = 0; i < n; i++) {
        c ^= p[i];
        for (int k = 0; k < 8; k++)
            c = (c >> 1) ^ (0x82F63B78u & (0u - (c & 1)));
    }
    return ~c;
}

Test(crc32c, check_value_and_definition)
{
    cr_assert_eq(ism_crc32c(0, "123456789", 9), 0xE3069283u);
    unsigned char buf[1000];
    for (size_t i = 0; i < sizeof buf; i++)
        buf[i] = (unsigned char)(i * 131 + 7);
    for (size_t off = 0; off < 9; off++)
        for (size_t n = 0; n + off <= sizeof buf; n += 97)
            cr_assert_eq(ism_crc32c(0, buf + off, n), crc_reference(buf + off, n),
                         "offset %zu length %zu", off, n);
    /* continuing a CRC over two pieces equals one pass */
    uint32_t a = ism_crc32c(ism_crc32c(0, buf, 333), buf + 333, 667);
    cr_assert_eq(a, ism_crc32c(0, buf, 1000));
}

static unsigned char *sample_frame(size_t payload_len, size_t *len)
{
    unsigned char *payload = malloc(payload_len ? payload_len : 1);
    for (size_t i = 0; i < payload_len; i++)
        payload[i] = (unsigned char)(i ^ (i >> 8));
    ism_frame_part part = {payload, payload_len};
    unsigned char *out;
    cr_assert(ism_frame_encode(ISM_FRAME_PROGRESS, 0x0102030405060708ULL, &part, 1, &out, len));
    free(payload);
    return out;
}

Test(frame, parse_round_trip_and_partial_buffers)
{
    size_t len;
    unsigned char *buf = sample_frame(5000, &len);
    cr_assert_eq(len, ISM_FRAME_HEADER_SIZE + 5000);
    for (size_t cut = 0; cut < len; cut += 37) {
        ism_frame f = {0};
        size_t used = 0;
        cr_assert_eq(ism_frame_parse(buf, cut, 1 << 20, &f, &used), ISM_FRAME_AGAIN, "cut %zu", cut);
    }
    ism_frame f = {0};
    size_t used = 0;
    cr_assert_eq(ism_frame_parse(buf, len, 1 << 20, &f, &used), ISM_FRAME_OK);
    cr_assert_eq(used, len);
    cr_assert_eq(f.type, ISM_FRAME_PROGRESS);
    cr_assert_eq(f.job, 0x0102030405060708ULL);
    cr_assert_eq(f.len, 5000);
    for (size_t i = 0; i < 5000; i++)
        cr_assert_eq(f.payload[i], (unsigned char)(i ^ (i >> 8)));
    ism_frame_free(&f);
    free(buf);
}

Test(frame, every_flipped_byte_is_detected)
{
    size_t len;
    unsigned char *buf = sample_frame(300, &len);
    for (size_t i = 0; i < len; i++) {
        for (int bit = 0; bit < 8; bit += 3) {
            buf[i] ^= (unsigned char)(1 << bit);
            ism_frame f = {0};
            size_t used;
            ism_frame_status st = ism_frame_parse(buf, len, 1 << 20, &f, &used);
            /* a flipped length bit may also look like a frame that has not fully arrived */
            cr_assert(st != ISM_FRAME_OK, "byte %zu bit %d not detected", i, bit);
            buf[i] ^= (unsigned char)(1 << bit);
        }
    }
    free(buf);
}

Test(frame, damage_is_named)
{
    size_t len;
    unsigned char *buf = sample_frame(64, &len);
    ism_frame f = {0};
    size_t used;
    buf[ISM_FRAME_HEADER_SIZE + 10] ^= 0x40;
    cr_assert_eq(ism_frame_parse(buf, len, 1 << 20, &f, &used), ISM_FRAME_BAD_CHECKSUM);
    buf[ISM_FRAME_HEADER_SIZE + 10] ^= 0x40;
    buf[0] = 'X';
    cr_assert_eq(ism_frame_parse(buf, len, 1 << 20, &f, &used), ISM_FRAME_BAD_MAGIC);
    cr_assert_eq(ism_frame_parse(buf, 2, 1 << 20, &f, &used), ISM_FRAME_BAD_MAGIC);
    buf[0] = 'I';
    buf[5] = 77;
    cr_assert_eq(ism_frame_parse(buf, len, 1 << 20, &f, &used), ISM_FRAME_BAD_TYPE);
    buf[5] = ISM_FRAME_PROGRESS;
    cr_assert_eq(ism_frame_parse(buf, len, 63, &f, &used), ISM_FRAME_TOO_BIG);
    cr_assert_eq(ism_frame_parse(buf, len, 64, &f, &used), ISM_FRAME_OK);
    ism_frame_free(&f);
    free(buf);
}

Test(frame, oversized_length_is_refused_before_any_allocation)
{
    unsigned char hdr[ISM_FRAME_HEADER_SIZE];
    ism_frame_part part = {"", 0};
    ism_frame_header_encode(hdr, ISM_FRAME_RESULT, 1, &part, 1);
    hdr[16] = hdr[17] = hdr[18] = hdr[19] = 0xff; /* 4 GiB - 1 */
    int p[2];
    cr_assert_eq(pipe(p), 0);
    cr_assert_eq(write(p[1], hdr, sizeof hdr), (ssize_t)sizeof hdr);
    close(p[1]);
    ism_frame_reader r;
    ism_frame_reader_init(&r, (size_t)-1);
    ism_frame f = {0};
    cr_assert_eq(ism_frame_read_fd(&r, p[0], &f), ISM_FRAME_TOO_BIG);
    cr_assert_null(r.cur.payload);
    ism_frame_reader_free(&r);
    close(p[0]);
}

/* Writes a buffer one byte per write(2), with pauses, from another thread. */
typedef struct dribble {
    int fd;
    const unsigned char *data;
    size_t len;
} dribble;

static void *dribble_main(void *arg)
{
    dribble *d = arg;
    for (size_t i = 0; i < d->len; i++) {
        cr_assert_eq(write(d->fd, d->data + i, 1), 1);
        if (i % 64 == 0)
            usleep(100);
    }
    close(d->fd);
    return NULL;
}

Test(frame, blocking_reader_survives_one_byte_writes)
{
    /* three frames back to back, dribbled through a pipe */
    size_t l1, l2, l3;
    unsigned char *f1 = sample_frame(0, &l1), *f2 = sample_frame(1000, &l2),
                  *f3 = sample_frame(3, &l3);
    size_t len = l1 + l2 + l3;
    unsigned char *all = malloc(len);
    memcpy(all, f1, l1);
    memcpy(all + l1, f2, l2);
    memcpy(all + l1 + l2, f3, l3);
    int p[2];
    cr_assert_eq(pipe(p), 0);
    dribble d = {p[1], all, len};
    pthread_t t;
    pthread_create(&t, NULL, dribble_main, &d);
    ism_frame_reader r;
    ism_frame_reader_init(&r, 1 << 20);
    size_t want[] = {0, 1000, 3};
    for (int i = 0; i < 3; i++) {
        ism_frame f = {0};
        cr_assert_eq(ism_frame_read_fd(&r, p[0], &f), ISM_FRAME_OK, "frame %d", i);
        cr_assert_eq(f.len, want[i]);
        ism_frame_free(&f);
    }
    ism_frame f = {0};
    cr_assert_eq(ism_frame_read_fd(&r, p[0], &f), ISM_FRAME_EOF);
    pthread_join(t, NULL);
    ism_frame_reader_free(&r);
    close(p[0]);
    free(all);
    free(f1);
    free(f2);
    free(f3);
}

Test(frame, nonblocking_reader_resumes_and_reports_truncation)
{
    size_t len;
    unsigned char *buf = sample_frame(200, &len);
    int p[2];
    cr_assert_eq(pipe2(p, O_NONBLOCK), 0);
    ism_frame_reader r;
    ism_frame_reader_init(&r, 1 << 20);
    ism_frame f = {0};
    cr_assert_eq(ism_frame_read_fd(&r, p[0], &f), ISM_FRAME_AGAIN);
    size_t sent = 0, steps[] = {3, 20, 1, 100, 50};
    for (size_t i = 0; i < sizeof steps / sizeof steps[0]; i++) {
        cr_assert_eq(write(p[1], buf + sent, steps[i]), (ssize_t)steps[i]);
        sent += steps[i];
        cr_assert_eq(ism_frame_read_fd(&r, p[0], &f), ISM_FRAME_AGAIN, "after %zu bytes", sent);
    }
    cr_assert_eq(write(p[1], buf + sent, len - sent), (ssize_t)(len - sent));
    cr_assert_eq(ism_frame_read_fd(&r, p[0], &f), ISM_FRAME_OK);
    cr_assert_eq(f.len, 200);
    ism_frame_free(&f);
    /* half a frame, then the writer goes away */
    cr_assert_eq(write(p[1], buf, 30), 30);
    close(p[1]);
    cr_assert_eq(ism_frame_read_fd(&r, p[0], &f), ISM_FRAME_TRUNCATED);
    ism_frame_reader_free(&r);
    close(p[0]);
    free(buf);
}

Test(frame, reader_rejects_garbage_at_once)
{
    int p[2];
    cr_assert_eq(pipe(p), 0);
    cr_assert_eq(write(p[1], "hello, world, this is not a frame", 33), 33);
    ism_frame_reader r;
    ism_frame_reader_init(&r, 1 << 20);
    ism_frame f = {0};
    cr_assert_eq(ism_frame_read_fd(&r, p[0], &f), ISM_FRAME_BAD_MAGIC);
    ism_frame_reader_free(&r);
    close(p[0]);
    close(p[1]);
}

Test(frame, writer_handles_short_writes_into_a_full_pipe)
{
    /* a 1 MiB payload through a pipe far smaller than it: writev returns short counts */
    size_t n = 1 << 20;
    unsigned char *payload = malloc(n);
    for (size_t i = 0; i < n; i++)
        payload[i] = (unsigned char)(i * 7);
    int p[2];
    cr_assert_eq(pipe(p), 0);
    fcntl(p[1], F_SETPIPE_SZ, 4096);
    pid_t pid = fork();
    if (pid == 0) {
        close(p[0]);
        ism_frame_part parts[3] = {{payload, 1000}, {payload + 1000, n - 2000}, {payload + n - 1000, 1000}};
        _exit(ism_frame_write_fd(p[1], ISM_FRAME_RESULT, 9, parts, 3) == ISM_FRAME_OK ? 0 : 1);
    }
    close(p[1]);
    ism_frame_reader r;
    ism_frame_reader_init(&r, n);
    ism_frame f = {0};
    cr_assert_eq(ism_frame_read_fd(&r, p[0], &f), ISM_FRAME_OK);
    cr_assert_eq(f.len, n);
    cr_assert_eq(f.job, 9);
    cr_assert_eq(memcmp(f.payload, payload, n), 0);
    int status;
    waitpid(pid, &status, 0);
    cr_assert(WIFEXITED(status) && WEXITSTATUS(status) == 0);
    ism_frame_free(&f);
    ism_frame_reader_free(&r);
    close(p[0]);
    free(payload);
}

/* A reader's own allocator (isomeshd's: SURFACE payloads into the cache's refcounted buffer). */
static unsigned char hook_buf[64];
static int hook_released;

static void hook_release(unsigned char *payload)
{
    cr_assert_eq(payload, hook_buf);
    hook_released++;
}

static unsigned char *hook_alloc(ism_frame_type type, size_t len,
                                 void (**release)(unsigned char *payload))
{
    if (type != ISM_FRAME_SURFACE || len > sizeof hook_buf)
        return NULL;
    *release = hook_release;
    return hook_buf;
}

Test(frame, reader_allocator_gets_its_types_and_frees_them)
{
    int p[2];
    cr_assert_eq(pipe(p), 0);
    static const char surf[] = "ISMS surface entry", prog[] = "\x40\x42\x0f\x00";
    ism_frame_part a = {surf, sizeof surf}, b = {prog, 4};
    cr_assert_eq(ism_frame_write_fd(p[1], ISM_FRAME_SURFACE, 5, &a, 1), ISM_FRAME_OK);
    cr_assert_eq(ism_frame_write_fd(p[1], ISM_FRAME_PROGRESS, 5, &b, 1), ISM_FRAME_OK);
    ism_frame_reader r;
    ism_frame_reader_init(&r, 1 << 20);
    r.alloc = hook_alloc;
    ism_frame f = {0};
    cr_assert_eq(ism_frame_read_fd(&r, p[0], &f), ISM_FRAME_OK);
    cr_assert_eq(f.type, ISM_FRAME_SURFACE);
    cr_assert_eq(f.payload, hook_buf, "read into the allocator's bytes");
    cr_assert_eq(f.len, sizeof surf);
    cr_assert_eq(memcmp(f.payload, surf, sizeof surf), 0);
    ism_frame_free(&f);
    cr_assert_eq(hook_released, 1);
    cr_assert_null(f.payload);
    cr_assert_eq(ism_frame_read_fd(&r, p[0], &f), ISM_FRAME_OK);
    cr_assert_eq(f.type, ISM_FRAME_PROGRESS);
    cr_assert_neq(f.payload, hook_buf, "other types malloc'd");
    cr_assert_null(f.release);
    cr_assert_eq(memcmp(f.payload, prog, 4), 0);
    ism_frame_free(&f);
    cr_assert_eq(hook_released, 1);
    /* a surface whose header is in but not its payload: the reader's free lets go of it */
    cr_assert_eq(ism_frame_write_fd(p[1], ISM_FRAME_SURFACE, 6, &a, 1), ISM_FRAME_OK);
    cr_assert_eq(fcntl(p[0], F_SETFL, O_NONBLOCK), 0);
    unsigned char head[ISM_FRAME_HEADER_SIZE + 3];
    ism_frame_reader r2;
    ism_frame_reader_init(&r2, 1 << 20);
    r2.alloc = hook_alloc;
    int q[2];
    cr_assert_eq(pipe2(q, O_NONBLOCK), 0);
    cr_assert_eq(read(p[0], head, sizeof head), (ssize_t)sizeof head);
    cr_assert_eq(write(q[1], head, sizeof head), (ssize_t)sizeof head);
    cr_assert_eq(ism_frame_read_fd(&r2, q[0], &f), ISM_FRAME_AGAIN);
    ism_frame_reader_free(&r2);
    cr_assert_eq(hook_released, 2);
    ism_frame_reader_free(&r);
    close(p[0]);
    close(p[1]);
    close(q[0]);
    close(q[1]);
}

Test(frame, write_to_a_closed_pipe_fails_cleanly)
{
    signal(SIGPIPE, SIG_IGN);
    int p[2];
    cr_assert_eq(pipe(p), 0);
    close(p[0]);
    ism_frame_part part = {"abc", 3};
    cr_assert_eq(ism_frame_write_fd(p[1], ISM_FRAME_PROGRESS, 1, &part, 1), ISM_FRAME_IO_ERROR);
    close(p[1]);
}

Test(payload, job_round_trip_and_truncation)
{
    const char *json = "{\"preset\": \"sphere\"}";
    ism_frame_job j = {.max_depth = 9, .threads = 3, .max_triangles = 123456789012ULL,
                       .max_memory = 1ULL << 33, .timeout_ms = 61000, .format = "glb",
                       .json = (const unsigned char *)json, .json_len = strlen(json)};
    ism_frame_builder b = {0};
    cr_assert(ism_frame_job_encode(&j, &b));
    ism_frame f = {.type = ISM_FRAME_REQUEST, .job = 1, .payload = b.data, .len = b.len};
    ism_frame_job d;
    cr_assert(ism_frame_job_decode(&f, &d));
    cr_assert_eq(d.max_depth, 9);
    cr_assert_eq(d.threads, 3);
    cr_assert_eq(d.max_triangles, 123456789012ULL);
    cr_assert_eq(d.max_memory, 1ULL << 33);
    cr_assert_eq(d.timeout_ms, 61000);
    cr_assert_str_eq(d.format, "glb");
    cr_assert_eq(d.json_len, strlen(json));
    cr_assert_eq(memcmp(d.json, json, d.json_len), 0);
    for (size_t cut = 0; cut < b.len; cut++) {
        f.len = cut;
        cr_assert_not(ism_frame_job_decode(&f, &d), "cut at %zu accepted", cut);
    }
    f.type = ISM_FRAME_RESULT;
    f.len = b.len;
    cr_assert_not(ism_frame_job_decode(&f, &d));
    ism_frame_builder_free(&b);
}

Test(payload, result_round_trip_through_parts)
{
    ism_frame_result r = {.status = 200, .worker_us = 4321, .key = "ab12", .format = "drc",
                          .surface_key = "cd34", .polygonised = 1,
                          .content_type = "application/octet-stream"};
    r.surface_len = 5551234; /* announced: the SURFACE frame after carries it */
    unsigned char body[777];
    for (size_t i = 0; i < sizeof body; i++)
        body[i] = (unsigned char)(255 - i);
    r.body = body;
    r.body_len = sizeof body;
    r.stats = (const unsigned char *)"{\"triangles\":12}";
    r.stats_len = 16;
    r.canonical = (const unsigned char *)"{}";
    r.canonical_len = 2;
    ism_frame_builder head = {0};
    unsigned char tail[4];
    cr_assert(ism_frame_result_encode(&r, &head, tail));
    ism_frame_part parts[3] = {{head.data, head.len}, {body, sizeof body}, {tail, 4}};
    unsigned char *wire;
    size_t wlen;
    cr_assert(ism_frame_encode(ISM_FRAME_RESULT, 42, parts, 3, &wire, &wlen));
    ism_frame f = {0};
    size_t used;
    cr_assert_eq(ism_frame_parse(wire, wlen, 1 << 20, &f, &used), ISM_FRAME_OK);
    ism_frame_result d;
    cr_assert(ism_frame_result_decode(&f, &d));
    cr_assert_eq(d.status, 200);
    cr_assert_eq(d.worker_us, 4321);
    cr_assert_str_eq(d.key, "ab12");
    cr_assert_str_eq(d.surface_key, "cd34");
    cr_assert_eq(d.polygonised, 1);
    cr_assert_eq(d.surface_len, 5551234);
    cr_assert_str_eq(d.format, "drc");
    cr_assert_str_eq(d.content_type, "application/octet-stream");
    cr_assert_eq(d.body_len, sizeof body);
    cr_assert_eq(memcmp(d.body, body, sizeof body), 0);
    cr_assert_eq(d.stats_len, 16);
    cr_assert_eq(d.features_len, 0);
    cr_assert_eq(d.canonical_len, 2);
    /* a result with its body cut short does not decode */
    f.len -= 1;
    cr_assert_not(ism_frame_result_decode(&f, &d));
    ism_frame_free(&f);
    ism_frame_builder_free(&head);
    free(wire);
}

Test(payload, strings_must_fit_and_hold_no_nul)
{
    ism_frame_builder b = {0};
    ism_frame_put_bytes(&b, "ab\0cd", 5);
    ism_frame_put_str(&b, "0123456789");
    ism_frame_cursor c;
    char small[8];
    ism_frame_cursor_init(&c, b.data, b.len);
    ism_frame_get_str(&c, small, sizeof small);
    cr_assert(c.failed, "a NUL inside a string was accepted");
    ism_frame_cursor_init(&c, b.data, b.len);
    size_t n;
    ism_frame_get_bytes(&c, &n);
    ism_frame_get_str(&c, small, sizeof small);
    cr_assert(c.failed, "an over-long string was accepted");
    cr_assert_eq(small[0], 0);
    ism_frame_builder_free(&b);
}
