/* fuzz_frame.c — libFuzzer target for the worker framing (proto/frame.h). The first input
 * byte is a mode, the rest a byte stream:
 *
 *   mode bits 0-2  the reader's payload limit (FRAME_LIMITS below)
 *   mode bit 3     repair the CRC-32C of every complete frame first, so that mutations
 *                  reach the payload decoders instead of dying at the checksum
 *   mode bit 4     also decode the whole stream as a REQUEST and as a RESULT payload
 *   mode bits 5-7  how the stream is cut into writes for the incremental reader
 *
 * Checks: ism_frame_parse over the buffer and ism_frame_read_fd over a non-blocking pipe fed
 * in pieces (partial headers and payloads) see the same frames and stop with matching
 * statuses; a parsed frame re-encodes to exactly its bytes and survives ism_frame_write_fd
 * (in two parts) and a blocking read; a decoded REQUEST or RESULT payload re-encodes to
 * exactly its payload.
 *
 * The regression tests include this file with ISM_FUZZ_NO_ENTRY defined and call
 * ism_fuzz_frame on every committed input. */
#include <fcntl.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "proto/frame.h"
#include "tests/fuzz/fuzz_check.h"

static const size_t FRAME_LIMITS[8] = {
    1u << 20, 64, 0, 23, 4096, 1u << 16, 100, ISM_FRAME_MAX_PAYLOAD,
};

#define FRAME_MAX_SEEN 512

typedef struct frame_seen {
    ism_frame_type type;
    uint64_t job;
    size_t off, len;   /* where its payload lies in the stream */
} frame_seen;

static uint32_t frame_le32(const unsigned char *p)
{
    return (uint32_t)p[0] | (uint32_t)p[1] << 8 | (uint32_t)p[2] << 16 | (uint32_t)p[3] << 24;
}

/* Writes the right checksum into every complete frame that starts where the previous one
 * ended (stops at the first thing that is not a frame header). */
static void frame_repair_crcs(unsigned char *buf, size_t n)
{
    size_t at = 0;
    while (n - at >= ISM_FRAME_HEADER_SIZE && memcmp(buf + at, "ISMF", 4) == 0) {
        uint32_t len = frame_le32(buf + at + 16);
        if (len > n - at - ISM_FRAME_HEADER_SIZE)
            break;
        uint32_t crc = ism_crc32c(ism_crc32c(0, buf + at, 20), buf + at + 24, len);
        for (int i = 0; i < 4; i++)
            buf[at + 20 + i] = (unsigned char)(crc >> (8 * i));
        at += ISM_FRAME_HEADER_SIZE + len;
    }
}

static void frame_check_job(const ism_frame *f)
{
    ism_frame_job j;
    if (!ism_frame_job_decode(f, &j))
        return;
    FUZZ_CHECK(strlen(j.format) < sizeof j.format, "job format not terminated");
    FUZZ_CHECK(j.json_len == 0 || (j.json >= f->payload && j.json + j.json_len <=
                                   f->payload + f->len), "job json outside the payload");
    ism_frame_builder b = {0};
    FUZZ_CHECK(ism_frame_job_encode(&j, &b), "job re-encode failed");
    FUZZ_CHECK(b.len == f->len && (b.len == 0 || memcmp(b.data, f->payload, b.len) == 0),
               "job re-encodes to other bytes (%zu vs %zu)", b.len, f->len);
    ism_frame_builder_free(&b);
}

static void frame_check_result(const ism_frame *f)
{
    ism_frame_result r;
    if (!ism_frame_result_decode(f, &r))
        return;
    FUZZ_CHECK(r.status >= 100 && r.status <= 599, "result status %u", r.status);
    ism_frame_builder head = {0};
    unsigned char tail[4];
    FUZZ_CHECK(ism_frame_result_encode(&r, &head, tail), "result re-encode failed");
    size_t at = head.len + r.body_len;
    FUZZ_CHECK(at + 4 == f->len && memcmp(head.data, f->payload, head.len) == 0 &&
               (r.body_len == 0 || memcmp(r.body, f->payload + head.len, r.body_len) == 0) &&
               memcmp(tail, f->payload + at, 4) == 0,
               "result re-encodes to other bytes");
    ism_frame_builder_free(&head);
}

/* A payload decoded as both messages (its own type's decoder must refuse the other). */
static void frame_check_payload(const unsigned char *p, size_t n, uint64_t job)
{
    unsigned char *copy = malloc(n ? n : 1);
    FUZZ_CHECK(copy != NULL, "out of memory");
    if (n)
        memcpy(copy, p, n);
    ism_frame f = {.type = ISM_FRAME_REQUEST, .job = job, .payload = copy, .len = n};
    frame_check_job(&f);
    ism_frame_result r;
    FUZZ_CHECK(!ism_frame_result_decode(&f, &r), "a REQUEST frame decoded as a RESULT");
    f.type = ISM_FRAME_RESULT;
    frame_check_result(&f);
    ism_frame_job j;
    FUZZ_CHECK(!ism_frame_job_decode(&f, &j), "a RESULT frame decoded as a REQUEST");
    free(copy);
}

/* The frame written in two parts by ism_frame_write_fd to a (blocking, empty) pipe and read
 * back; the pipe is empty again afterwards. */
static void frame_check_write(const ism_frame *f, size_t limit, const int fds[2])
{
    size_t cut = f->len / 3;
    ism_frame_part parts[2] = {{f->payload, cut}, {f->payload + cut, f->len - cut}};
    FUZZ_CHECK(ism_frame_write_fd(fds[1], f->type, f->job, parts, 2) == ISM_FRAME_OK,
               "write_fd failed");
    ism_frame_reader r;
    ism_frame_reader_init(&r, limit);
    ism_frame back;
    ism_frame_status st = ism_frame_read_fd(&r, fds[0], &back);
    FUZZ_CHECK(st == ISM_FRAME_OK, "a written frame reads back as '%s'",
               ism_frame_status_name(st));
    FUZZ_CHECK(back.type == f->type && back.job == f->job && back.len == f->len &&
               (f->len == 0 || memcmp(back.payload, f->payload, f->len) == 0),
               "a written frame reads back different");
    ism_frame_free(&back);
    ism_frame_reader_free(&r);
}

/* Whole-buffer parsing: the frames in order and the status that ended the walk. */
static ism_frame_status frame_parse_all(const unsigned char *buf, size_t n, size_t limit,
                                        frame_seen *seen, size_t *nseen, size_t *end)
{
    size_t at = 0;
    *nseen = 0;
    int echo[2];
    FUZZ_CHECK(pipe2(echo, O_CLOEXEC) == 0, "pipe2 failed");
    for (;;) {
        ism_frame f;
        size_t used = 0;
        ism_frame_status st = ism_frame_parse(buf + at, n - at, limit, &f, &used);
        if (st != ISM_FRAME_OK) {
            close(echo[0]);
            close(echo[1]);
            *end = at;
            return st;
        }
        FUZZ_CHECK(used == ISM_FRAME_HEADER_SIZE + f.len && used <= n - at,
                   "parse consumed %zu of %zu for a %zu-byte payload", used, n - at, f.len);
        FUZZ_CHECK(f.len <= limit, "payload %zu over the limit %zu", f.len, limit);
        FUZZ_CHECK(f.len == 0 || memcmp(f.payload, buf + at + 24, f.len) == 0,
                   "payload differs from the stream");
        ism_frame_part part = {f.payload, f.len};
        unsigned char *again = NULL;
        size_t again_len = 0;
        FUZZ_CHECK(ism_frame_encode(f.type, f.job, &part, 1, &again, &again_len),
                   "re-encode failed");
        FUZZ_CHECK(again_len == used && memcmp(again, buf + at, used) == 0,
                   "frame re-encodes to other bytes");
        free(again);
        frame_check_write(&f, limit, echo);
        if (f.type == ISM_FRAME_REQUEST)
            frame_check_job(&f);
        if (f.type == ISM_FRAME_RESULT)
            frame_check_result(&f);
        if (*nseen < FRAME_MAX_SEEN)
            seen[(*nseen)++] = (frame_seen){f.type, f.job, at + 24, f.len};
        ism_frame_free(&f);
        at += used;
    }
}

/* Compares one frame from the reader with the next one parsing saw. */
static void frame_match(const ism_frame *f, const unsigned char *buf, const frame_seen *seen,
                        size_t nseen, size_t *next)
{
    FUZZ_CHECK(*next < nseen, "the reader found frame %zu, parsing only %zu", *next + 1,
               nseen);
    const frame_seen *s = &seen[(*next)++];
    FUZZ_CHECK(f->type == s->type && f->job == s->job && f->len == s->len &&
               (f->len == 0 || memcmp(f->payload, buf + s->off, f->len) == 0),
               "the reader's frame %zu differs from the parsed one", *next);
}

int ism_fuzz_frame(const uint8_t *data, size_t size)
{
    if (size < 1)
        return 0;
    unsigned mode = data[0];
    size_t n = size - 1, limit = FRAME_LIMITS[mode & 7];
    unsigned char *buf = malloc(n ? n : 1);
    FUZZ_CHECK(buf != NULL, "out of memory");
    if (n)
        memcpy(buf, data + 1, n);
    if (mode & 8)
        frame_repair_crcs(buf, n);
    if (mode & 16)
        frame_check_payload(buf, n, mode);

    static frame_seen seen[FRAME_MAX_SEEN];
    size_t nseen = 0, end = 0;
    ism_frame_status parsed = frame_parse_all(buf, n, limit, seen, &nseen, &end);
    FUZZ_CHECK(parsed != ISM_FRAME_EOF && parsed != ISM_FRAME_TRUNCATED &&
               parsed != ISM_FRAME_IO_ERROR && parsed != ISM_FRAME_NO_MEMORY,
               "parse ended with '%s'", ism_frame_status_name(parsed));

    /* The same bytes through a pipe, in pieces of 1..max_piece bytes. */
    int fds[2];
    FUZZ_CHECK(pipe2(fds, O_NONBLOCK | O_CLOEXEC) == 0, "pipe2 failed");
    static const size_t PIECES[8] = {4096, 1, 3, 7, 24, 25, 100, 1000};
    size_t max_piece = PIECES[(mode >> 5) & 7];
    uint32_t rng = (uint32_t)n * 2654435761u + mode;
    ism_frame_reader r;
    ism_frame_reader_init(&r, limit);
    size_t next = 0, sent = 0;
    ism_frame_status st = ISM_FRAME_AGAIN;
    while (st == ISM_FRAME_AGAIN || st == ISM_FRAME_OK) {
        if (st == ISM_FRAME_AGAIN) {
            if (sent == n)
                break;
            rng = rng * 1103515245u + 12345u;
            size_t piece = 1 + (rng >> 8) % max_piece;
            if (piece > n - sent)
                piece = n - sent;
            FUZZ_CHECK(write(fds[1], buf + sent, piece) == (ssize_t)piece, "pipe write");
            sent += piece;
        }
        ism_frame f;
        st = ism_frame_read_fd(&r, fds[0], &f);
        if (st == ISM_FRAME_OK) {
            frame_match(&f, buf, seen, nseen, &next);
            ism_frame_free(&f);
        }
    }
    if (st == ISM_FRAME_AGAIN) { /* everything sent: the writer leaves */
        close(fds[1]);
        fds[1] = -1;
        ism_frame f;
        while ((st = ism_frame_read_fd(&r, fds[0], &f)) == ISM_FRAME_OK) {
            frame_match(&f, buf, seen, nseen, &next);
            ism_frame_free(&f);
        }
    }
    ism_frame_reader_free(&r);
    close(fds[0]);
    if (fds[1] >= 0)
        close(fds[1]);

    size_t counted = nseen < FRAME_MAX_SEEN ? nseen : next;
    FUZZ_CHECK(next == counted, "the reader found %zu frames, parsing %zu", next, nseen);
    if (parsed == ISM_FRAME_AGAIN) {
        ism_frame_status want = end == n ? ISM_FRAME_EOF : ISM_FRAME_TRUNCATED;
        FUZZ_CHECK(st == want, "parse wants more bytes, the reader says '%s' (expected '%s')",
                   ism_frame_status_name(st), ism_frame_status_name(want));
    } else {
        FUZZ_CHECK(st == parsed, "parse says '%s', the reader '%s'",
                   ism_frame_status_name(parsed), ism_frame_status_name(st));
    }
    free(buf);
    return 0;
}

#ifndef ISM_FUZZ_NO_ENTRY
int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);
int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    return ism_fuzz_frame(data, size);
}
#endif
