/* frame.c — the worker IPC framing of frame.h: CRC-32C, header encoding, whole-buffer parsing,
 * an incremental fd reader that survives partial reads, an fd writer that survives short
 * writes, and the payload layouts of the REQUEST and RESULT messages. */
#include "proto/frame.h"
#include "core/util/le_bytes.h"

#include <errno.h>
#include <pthread.h>
#include <stdlib.h>
#include <string.h>
#include <sys/uio.h>
#include <unistd.h>

static const unsigned char MAGIC[4] = {'I', 'S', 'M', 'F'};

const char *ism_frame_status_name(ism_frame_status s)
{
    switch (s) {
    case ISM_FRAME_OK: return "ok";
    case ISM_FRAME_AGAIN: return "again";
    case ISM_FRAME_EOF: return "end of stream";
    case ISM_FRAME_TRUNCATED: return "truncated frame";
    case ISM_FRAME_BAD_MAGIC: return "bad magic or version";
    case ISM_FRAME_BAD_TYPE: return "unknown frame type";
    case ISM_FRAME_TOO_BIG: return "frame too big";
    case ISM_FRAME_BAD_CHECKSUM: return "bad checksum";
    case ISM_FRAME_IO_ERROR: return "i/o error";
    case ISM_FRAME_NO_MEMORY: return "out of memory";
    }
    return "unknown";
}

void ism_frame_free(ism_frame *f)
{
    if (f->release)
        f->release(f->payload);
    else
        free(f->payload);
    f->payload = NULL;
    f->release = NULL;
    f->len = 0;
}

/* ---- CRC-32C ------------------------------------------------------------------------- */

#define CRC32C_POLY 0x82F63B78u /* Castagnoli, bit-reflected */

static uint32_t crc_table[8][256];
static pthread_once_t crc_once = PTHREAD_ONCE_INIT;
static bool crc_have_hw;

static void crc_init(void)
{
    for (uint32_t i = 0; i < 256; i++) {
        uint32_t c = i;
        for (int k = 0; k < 8; k++)
            c = (c & 1) ? (c >> 1) ^ CRC32C_POLY : c >> 1;
        crc_table[0][i] = c;
    }
    for (uint32_t i = 0; i < 256; i++)
        for (int t = 1; t < 8; t++)
            crc_table[t][i] = (crc_table[t - 1][i] >> 8) ^ crc_table[0][crc_table[t - 1][i] & 0xff];
#if defined(__x86_64__)
    __builtin_cpu_init();
    crc_have_hw = __builtin_cpu_supports("sse4.2");
#endif
}

static uint32_t crc_soft(uint32_t c, const unsigned char *p, size_t n)
{
    while (n && ((uintptr_t)p & 7)) {
        c = (c >> 8) ^ crc_table[0][(c ^ *p++) & 0xff];
        n--;
    }
    while (n >= 8) {
        uint32_t lo = (uint32_t)p[0] | (uint32_t)p[1] << 8 | (uint32_t)p[2] << 16 | (uint32_t)p[3] << 24;
        lo ^= c;
        c = crc_table[7][lo & 0xff] ^ crc_table[6][(lo >> 8) & 0xff] ^
            crc_table[5][(lo >> 16) & 0xff] ^ crc_table[4][lo >> 24] ^
            crc_table[3][p[4]] ^ crc_table[2][p[5]] ^ crc_table[1][p[6]] ^ crc_table[0][p[7]];
        p += 8;
        n -= 8;
    }
    while (n--)
        c = (c >> 8) ^ crc_table[0][(c ^ *p++) & 0xff];
    return c;
}

#if defined(__x86_64__)
__attribute__((target("sse4.2")))
static uint32_t crc_hw(uint32_t c, const unsigned char *p, size_t n)
{
    uint64_t c64 = c;
    while (n && ((uintptr_t)p & 7)) {
        c64 = __builtin_ia32_crc32qi((uint32_t)c64, *p++);
        n--;
    }
    while (n >= 8) {
        uint64_t v;
        memcpy(&v, p, 8);
        c64 = __builtin_ia32_crc32di(c64, v);
        p += 8;
        n -= 8;
    }
    while (n--)
        c64 = __builtin_ia32_crc32qi((uint32_t)c64, *p++);
    return (uint32_t)c64;
}
#endif

uint32_t ism_crc32c(uint32_t crc, const void *data, size_t len)
{
    pthread_once(&crc_once, crc_init);
    uint32_t c = ~crc;
#if defined(__x86_64__)
    if (crc_have_hw)
        return ~crc_hw(c, data, len);
#endif
    return ~crc_soft(c, data, len);
}

/* ---- little-endian fields ------------------------------------------------------------ */

/* ---- header -------------------------------------------------------------------------- */

static size_t parts_len(const ism_frame_part *parts, size_t nparts)
{
    size_t n = 0;
    for (size_t i = 0; i < nparts; i++)
        n += parts[i].len;
    return n;
}

void ism_frame_header_encode(unsigned char hdr[ISM_FRAME_HEADER_SIZE], ism_frame_type type,
                             uint64_t job, const ism_frame_part *parts, size_t nparts)
{
    memcpy(hdr, MAGIC, 4);
    hdr[4] = ISM_FRAME_VERSION;
    hdr[5] = (unsigned char)type;
    hdr[6] = hdr[7] = 0;
    ism_put_le64(hdr + 8, job);
    ism_put_le32(hdr + 16, (uint32_t)parts_len(parts, nparts));
    uint32_t crc = ism_crc32c(0, hdr, 20);
    for (size_t i = 0; i < nparts; i++)
        crc = ism_crc32c(crc, parts[i].data, parts[i].len);
    ism_put_le32(hdr + 20, crc);
}

static bool known_type(unsigned t)
{
    return t >= ISM_FRAME_HELLO && t <= ISM_FRAME_SURFACE;
}

/* Checks a complete header; on success fills type, job and the payload length. */
static ism_frame_status header_check(const unsigned char *hdr, size_t max_payload,
                                     ism_frame *f, uint32_t *crc)
{
    if (memcmp(hdr, MAGIC, 4) != 0 || hdr[4] != ISM_FRAME_VERSION || hdr[6] || hdr[7])
        return ISM_FRAME_BAD_MAGIC;
    if (!known_type(hdr[5]))
        return ISM_FRAME_BAD_TYPE;
    uint32_t len = ism_get_le32(hdr + 16);
    if (len > max_payload || len > ISM_FRAME_MAX_PAYLOAD)
        return ISM_FRAME_TOO_BIG;
    f->type = (ism_frame_type)hdr[5];
    f->job = ism_get_le64(hdr + 8);
    f->len = len;
    *crc = ism_get_le32(hdr + 20);
    return ISM_FRAME_OK;
}

bool ism_frame_encode(ism_frame_type type, uint64_t job, const ism_frame_part *parts,
                      size_t nparts, unsigned char **out, size_t *out_len)
{
    size_t n = parts_len(parts, nparts);
    if (n > ISM_FRAME_MAX_PAYLOAD)
        return false;
    unsigned char *buf = malloc(ISM_FRAME_HEADER_SIZE + n);
    if (!buf)
        return false;
    ism_frame_header_encode(buf, type, job, parts, nparts);
    size_t at = ISM_FRAME_HEADER_SIZE;
    for (size_t i = 0; i < nparts; i++) {
        if (parts[i].len)
            memcpy(buf + at, parts[i].data, parts[i].len);
        at += parts[i].len;
    }
    *out = buf;
    *out_len = at;
    return true;
}

ism_frame_status ism_frame_parse(const void *buf, size_t len, size_t max_payload,
                                 ism_frame *f, size_t *consumed)
{
    const unsigned char *p = buf;
    if (len < ISM_FRAME_HEADER_SIZE) {
        /* Reject garbage early when the bytes we have already cannot start a frame. */
        size_t m = len < 4 ? len : 4;
        return memcmp(p, MAGIC, m) == 0 ? ISM_FRAME_AGAIN : ISM_FRAME_BAD_MAGIC;
    }
    ism_frame h = {0};
    uint32_t want;
    ism_frame_status st = header_check(p, max_payload, &h, &want);
    if (st != ISM_FRAME_OK)
        return st;
    if (len - ISM_FRAME_HEADER_SIZE < h.len)
        return ISM_FRAME_AGAIN;
    uint32_t crc = ism_crc32c(ism_crc32c(0, p, 20), p + ISM_FRAME_HEADER_SIZE, h.len);
    if (crc != want)
        return ISM_FRAME_BAD_CHECKSUM;
    h.payload = malloc(h.len ? h.len : 1);
    if (!h.payload)
        return ISM_FRAME_NO_MEMORY;
    memcpy(h.payload, p + ISM_FRAME_HEADER_SIZE, h.len);
    *f = h;
    *consumed = ISM_FRAME_HEADER_SIZE + h.len;
    return ISM_FRAME_OK;
}

/* ---- writing to an fd ---------------------------------------------------------------- */

ism_frame_status ism_frame_write_fd(int fd, ism_frame_type type, uint64_t job,
                                    const ism_frame_part *parts, size_t nparts)
{
    enum { MAX_PARTS = 15 };
    if (nparts > MAX_PARTS || parts_len(parts, nparts) > ISM_FRAME_MAX_PAYLOAD)
        return ISM_FRAME_TOO_BIG;
    unsigned char hdr[ISM_FRAME_HEADER_SIZE];
    ism_frame_header_encode(hdr, type, job, parts, nparts);
    struct iovec iov[MAX_PARTS + 1];
    int n = 0;
    iov[n++] = (struct iovec){hdr, sizeof hdr};
    for (size_t i = 0; i < nparts; i++)
        if (parts[i].len)
            iov[n++] = (struct iovec){(void *)parts[i].data, parts[i].len};
    struct iovec *v = iov;
    while (n > 0) {
        ssize_t w = writev(fd, v, n);
        if (w < 0) {
            if (errno == EINTR)
                continue;
            return ISM_FRAME_IO_ERROR;
        }
        size_t done = (size_t)w;
        while (n > 0 && done >= v->iov_len) {
            done -= v->iov_len;
            v++;
            n--;
        }
        if (n > 0) {
            v->iov_base = (char *)v->iov_base + done;
            v->iov_len -= done;
        }
    }
    return ISM_FRAME_OK;
}

/* ---- incremental reader -------------------------------------------------------------- */

void ism_frame_reader_init(ism_frame_reader *r, size_t max_payload)
{
    memset(r, 0, sizeof *r);
    r->max_payload = max_payload < ISM_FRAME_MAX_PAYLOAD ? max_payload : ISM_FRAME_MAX_PAYLOAD;
}

void ism_frame_reader_free(ism_frame_reader *r)
{
    ism_frame_free(&r->cur);
    r->hdr_have = r->have = 0;
}

/* read() that retries EINTR: >0 bytes, 0 at end of stream, -1 would block, -2 error. */
static ssize_t read_some(int fd, void *buf, size_t n)
{
    for (;;) {
        ssize_t got = read(fd, buf, n);
        if (got >= 0)
            return got;
        if (errno == EINTR)
            continue;
        if (errno == EAGAIN || errno == EWOULDBLOCK)
            return -1;
        return -2;
    }
}

ism_frame_status ism_frame_read_fd(ism_frame_reader *r, int fd, ism_frame *f)
{
    while (r->hdr_have < ISM_FRAME_HEADER_SIZE) {
        ssize_t got = read_some(fd, r->hdr + r->hdr_have, ISM_FRAME_HEADER_SIZE - r->hdr_have);
        if (got == -1)
            return ISM_FRAME_AGAIN;
        if (got == -2)
            return ISM_FRAME_IO_ERROR;
        if (got == 0)
            return r->hdr_have ? ISM_FRAME_TRUNCATED : ISM_FRAME_EOF;
        /* Fail fast on a stream that does not even start like a frame. */
        size_t before = r->hdr_have;
        r->hdr_have += (size_t)got;
        if (before < 4) {
            size_t m = r->hdr_have < 4 ? r->hdr_have : 4;
            if (memcmp(r->hdr, MAGIC, m) != 0)
                return ISM_FRAME_BAD_MAGIC;
        }
        if (r->hdr_have == ISM_FRAME_HEADER_SIZE) {
            ism_frame_status st = header_check(r->hdr, r->max_payload, &r->cur, &r->want_crc);
            if (st != ISM_FRAME_OK)
                return st;
            r->cur.release = NULL;
            r->cur.payload = r->alloc ? r->alloc(r->cur.type, r->cur.len, &r->cur.release)
                                      : NULL;
            if (!r->cur.payload) {
                r->cur.release = NULL;
                r->cur.payload = malloc(r->cur.len ? r->cur.len : 1);
            }
            if (!r->cur.payload)
                return ISM_FRAME_NO_MEMORY;
            r->have = 0;
        }
    }
    while (r->have < r->cur.len) {
        ssize_t got = read_some(fd, r->cur.payload + r->have, r->cur.len - r->have);
        if (got == -1)
            return ISM_FRAME_AGAIN;
        if (got == -2)
            return ISM_FRAME_IO_ERROR;
        if (got == 0)
            return ISM_FRAME_TRUNCATED;
        r->have += (size_t)got;
    }
    uint32_t crc = ism_crc32c(ism_crc32c(0, r->hdr, 20), r->cur.payload, r->cur.len);
    if (crc != r->want_crc)
        return ISM_FRAME_BAD_CHECKSUM;
    *f = r->cur;
    memset(&r->cur, 0, sizeof r->cur);
    r->hdr_have = r->have = 0;
    return ISM_FRAME_OK;
}

/* ---- payload builder and cursor ------------------------------------------------------ */

void ism_frame_builder_free(ism_frame_builder *b)
{
    free(b->data);
    memset(b, 0, sizeof *b);
}

static unsigned char *builder_grow(ism_frame_builder *b, size_t n)
{
    if (b->failed)
        return NULL;
    if (n > ISM_FRAME_MAX_PAYLOAD || b->len > ISM_FRAME_MAX_PAYLOAD - n) {
        b->failed = true;
        return NULL;
    }
    if (b->len + n > b->cap) {
        size_t cap = b->cap ? b->cap : 256;
        while (cap < b->len + n)
            cap *= 2;
        unsigned char *d = realloc(b->data, cap);
        if (!d) {
            b->failed = true;
            return NULL;
        }
        b->data = d;
        b->cap = cap;
    }
    unsigned char *at = b->data + b->len;
    b->len += n;
    return at;
}

void ism_frame_put_u32(ism_frame_builder *b, uint32_t v)
{
    unsigned char *p = builder_grow(b, 4);
    if (p)
        ism_put_le32(p, v);
}

void ism_frame_put_u64(ism_frame_builder *b, uint64_t v)
{
    unsigned char *p = builder_grow(b, 8);
    if (p)
        ism_put_le64(p, v);
}

void ism_frame_put_bytes(ism_frame_builder *b, const void *data, size_t len)
{
    if (len > UINT32_MAX) {
        b->failed = true;
        return;
    }
    ism_frame_put_u32(b, (uint32_t)len);
    unsigned char *p = builder_grow(b, len);
    if (p && len)
        memcpy(p, data, len);
}

void ism_frame_put_str(ism_frame_builder *b, const char *s)
{
    ism_frame_put_bytes(b, s ? s : "", s ? strlen(s) : 0);
}

void ism_frame_cursor_init(ism_frame_cursor *c, const void *data, size_t len)
{
    c->p = data;
    c->left = len;
    c->failed = false;
}

static const unsigned char *cursor_take(ism_frame_cursor *c, size_t n)
{
    if (c->failed || c->left < n) {
        c->failed = true;
        return NULL;
    }
    const unsigned char *at = c->p;
    c->p += n;
    c->left -= n;
    return at;
}

uint32_t ism_frame_get_u32(ism_frame_cursor *c)
{
    const unsigned char *p = cursor_take(c, 4);
    return p ? ism_get_le32(p) : 0;
}

uint64_t ism_frame_get_u64(ism_frame_cursor *c)
{
    const unsigned char *p = cursor_take(c, 8);
    return p ? ism_get_le64(p) : 0;
}

const unsigned char *ism_frame_get_bytes(ism_frame_cursor *c, size_t *len)
{
    uint32_t n = ism_frame_get_u32(c);
    const unsigned char *p = cursor_take(c, n);
    *len = p ? n : 0;
    return p;
}

void ism_frame_get_str(ism_frame_cursor *c, char *dst, size_t cap)
{
    size_t n;
    const unsigned char *p = ism_frame_get_bytes(c, &n);
    if (!p || n >= cap || memchr(p, 0, n)) {
        c->failed = true;
        if (cap)
            dst[0] = 0;
        return;
    }
    memcpy(dst, p, n);
    dst[n] = 0;
}

/* ---- REQUEST and RESULT payloads ----------------------------------------------------- */

bool ism_frame_job_encode(const ism_frame_job *j, ism_frame_builder *b)
{
    ism_frame_put_u32(b, j->max_depth);
    ism_frame_put_u32(b, j->threads);
    ism_frame_put_u64(b, j->max_triangles);
    ism_frame_put_u64(b, j->max_memory);
    ism_frame_put_u32(b, j->timeout_ms);
    ism_frame_put_str(b, j->format);
    ism_frame_put_bytes(b, j->json, j->json_len);
    ism_frame_put_bytes(b, j->computed, j->computed_len);
    return !b->failed;
}

bool ism_frame_job_decode(const ism_frame *f, ism_frame_job *j)
{
    if (f->type != ISM_FRAME_REQUEST)
        return false;
    ism_frame_cursor c;
    ism_frame_cursor_init(&c, f->payload, f->len);
    memset(j, 0, sizeof *j);
    j->max_depth = ism_frame_get_u32(&c);
    j->threads = ism_frame_get_u32(&c);
    j->max_triangles = ism_frame_get_u64(&c);
    j->max_memory = ism_frame_get_u64(&c);
    j->timeout_ms = ism_frame_get_u32(&c);
    ism_frame_get_str(&c, j->format, sizeof j->format);
    j->json = ism_frame_get_bytes(&c, &j->json_len);
    j->computed = ism_frame_get_bytes(&c, &j->computed_len);
    return !c.failed && c.left == 0;
}

bool ism_frame_result_encode(const ism_frame_result *r, ism_frame_builder *head,
                             unsigned char tail[4])
{
    ism_frame_put_u32(head, r->status);
    ism_frame_put_u32(head, r->worker_us);
    ism_frame_put_str(head, r->key);
    ism_frame_put_str(head, r->surface_key);
    ism_frame_put_u32(head, r->polygonised);
    ism_frame_put_str(head, r->format);
    ism_frame_put_str(head, r->content_type);
    ism_frame_put_bytes(head, r->stats, r->stats_len);
    ism_frame_put_bytes(head, r->features, r->features_len);
    ism_frame_put_bytes(head, r->canonical, r->canonical_len);
    if (r->body_len > UINT32_MAX)
        head->failed = true;
    ism_frame_put_u32(head, (uint32_t)r->body_len); /* the body itself is the second part */
    ism_put_le32(tail, r->surface_len);              /* then this */
    return !head->failed;
}

bool ism_frame_result_decode(const ism_frame *f, ism_frame_result *r)
{
    if (f->type != ISM_FRAME_RESULT)
        return false;
    ism_frame_cursor c;
    ism_frame_cursor_init(&c, f->payload, f->len);
    memset(r, 0, sizeof *r);
    r->status = ism_frame_get_u32(&c);
    r->worker_us = ism_frame_get_u32(&c);
    ism_frame_get_str(&c, r->key, sizeof r->key);
    ism_frame_get_str(&c, r->surface_key, sizeof r->surface_key);
    r->polygonised = ism_frame_get_u32(&c);
    ism_frame_get_str(&c, r->format, sizeof r->format);
    ism_frame_get_str(&c, r->content_type, sizeof r->content_type);
    r->stats = ism_frame_get_bytes(&c, &r->stats_len);
    r->features = ism_frame_get_bytes(&c, &r->features_len);
    r->canonical = ism_frame_get_bytes(&c, &r->canonical_len);
    r->body = ism_frame_get_bytes(&c, &r->body_len);
    r->surface_len = ism_frame_get_u32(&c);
    return !c.failed && c.left == 0 && r->status >= 100 && r->status <= 599;
}
