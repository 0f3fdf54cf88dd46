/* frame.h — the framing that isomeshd and its `isomesh --worker` processes speak over a pair
 * of pipes: length-prefixed, typed, checksummed messages, each naming the job it belongs to.
 *
 * A frame is a 24-byte header followed by its payload:
 *
 *   offset  size  field
 *   0       4     magic "ISMF"
 *   4       1     version (1)
 *   5       1     type (enum ism_frame_type)
 *   6       2     reserved, zero
 *   8       8     job id (little endian; 0 for HELLO)
 *   16      4     payload length in bytes (little endian)
 *   20      4     CRC-32C of header bytes 0..19 followed by the payload (little endian)
 *
 * Payloads are built from little-endian u32/u64 fields and u32-length-prefixed byte strings
 * (see the ism_frame_* payload helpers below). A frame whose magic, version, type, length or
 * checksum is wrong is an error for the whole channel: the reader never resynchronises, the
 * side that sees it drops the peer (the daemon kills and replaces the worker, the worker
 * exits). Nothing here knows about sockets or HTTP; the fd helpers work on any blocking or
 * non-blocking pipe and survive EINTR, short reads and short writes. */
#ifndef ISM_FRAME_H
#define ISM_FRAME_H

#include <stddef.h>
#include <stdint.h>
#include <stdbool.h>

#define ISM_FRAME_HEADER_SIZE 24
#define ISM_FRAME_VERSION 1
/* Absolute ceiling on one payload; readers pass their own (smaller) limit. */
#define ISM_FRAME_MAX_PAYLOAD (1024u * 1024u * 1024u)

typedef enum ism_frame_type {
    ISM_FRAME_HELLO = 1,    /* worker -> daemon, once at start: u32 pid, string version */
    ISM_FRAME_REQUEST = 2,  /* daemon -> worker: one job (ism_frame_job) */
    ISM_FRAME_PROGRESS = 3, /* worker -> daemon: u32 progress in millionths */
    ISM_FRAME_RESULT = 4,   /* worker -> daemon: the pipeline's answer (ism_frame_result) */
    ISM_FRAME_ERROR = 5,    /* worker -> daemon: u32 HTTP status, string error JSON */
    ISM_FRAME_SURFACE = 6,  /* worker -> daemon, right after a RESULT that announced it
                               (surface_len): the computed surface's entry, the whole payload */
} ism_frame_type;

/* Outcome of parsing or reading a frame. */
typedef enum ism_frame_status {
    ISM_FRAME_OK = 0,        /* a whole frame is ready */
    ISM_FRAME_AGAIN,         /* need more bytes (non-blocking fd had none) */
    ISM_FRAME_EOF,           /* the peer closed cleanly between frames */
    ISM_FRAME_TRUNCATED,     /* the peer closed in the middle of a frame */
    ISM_FRAME_BAD_MAGIC,     /* not a frame (or wrong version) */
    ISM_FRAME_BAD_TYPE,      /* unknown message type */
    ISM_FRAME_TOO_BIG,       /* payload length over the reader's limit */
    ISM_FRAME_BAD_CHECKSUM,  /* CRC-32C mismatch */
    ISM_FRAME_IO_ERROR,      /* read/write failed (errno kept) */
    ISM_FRAME_NO_MEMORY,
} ism_frame_status;

const char *ism_frame_status_name(ism_frame_status s);

/* A decoded frame; payload is malloc'd and owned by the frame (free with ism_frame_free). */
typedef struct ism_frame {
    ism_frame_type type;
    uint64_t job;
    unsigned char *payload;
    size_t len;
    /* How ism_frame_free lets go of payload: NULL, free(); else the allocator's that gave it
     * (ism_frame_reader.alloc). */
    void (*release)(unsigned char *payload);
} ism_frame;

void ism_frame_free(ism_frame *f);

/* CRC-32C (Castagnoli), continuing from crc (start with 0). Hardware instruction when the
 * CPU has one, slicing-by-8 tables otherwise. */
uint32_t ism_crc32c(uint32_t crc, const void *data, size_t len);

/* One part of a payload written without copying (like struct iovec). */
typedef struct ism_frame_part {
    const void *data;
    size_t len;
} ism_frame_part;

/* Writes the 24-byte header for a payload made of parts into hdr (checksum included). */
void ism_frame_header_encode(unsigned char hdr[ISM_FRAME_HEADER_SIZE], ism_frame_type type,
                             uint64_t job, const ism_frame_part *parts, size_t nparts);

/* Encodes a whole frame into one malloc'd buffer (*out, *out_len). False when out of memory
 * or the payload is over ISM_FRAME_MAX_PAYLOAD. */
bool ism_frame_encode(ism_frame_type type, uint64_t job, const ism_frame_part *parts,
                      size_t nparts, unsigned char **out, size_t *out_len);

/* Parses one frame from the start of buf. ISM_FRAME_OK fills f (payload copied) and
 * *consumed; ISM_FRAME_AGAIN when buf holds only part of a frame; an error otherwise. */
ism_frame_status ism_frame_parse(const void *buf, size_t len, size_t max_payload,
                                 ism_frame *f, size_t *consumed);

/* Writes a whole frame to a blocking fd, retrying EINTR and short writes. */
ism_frame_status ism_frame_write_fd(int fd, ism_frame_type type, uint64_t job,
                                    const ism_frame_part *parts, size_t nparts);

/* Incremental reader for one fd: keeps a partial frame between calls, reads no byte past
 * the end of the current frame. */
/* A reader's own allocator for a payload of len bytes of a frame of type: returns the bytes
 * and sets *release to what lets go of them, or returns NULL (the reader then mallocs).
 * Why: isomeshd reads a computed surface straight into the refcounted buffer its cache
 * keeps, instead of copying megabytes out of the frame. */
typedef unsigned char *(*ism_frame_alloc_fn)(ism_frame_type type, size_t len,
                                             void (**release)(unsigned char *payload));

typedef struct ism_frame_reader {
    unsigned char hdr[ISM_FRAME_HEADER_SIZE];
    size_t hdr_have;
    size_t max_payload;
    uint32_t want_crc;
    ism_frame cur;      /* payload being filled once the header is complete */
    size_t have;
    ism_frame_alloc_fn alloc; /* NULL (ism_frame_reader_init's): malloc */
} ism_frame_reader;

void ism_frame_reader_init(ism_frame_reader *r, size_t max_payload);
void ism_frame_reader_free(ism_frame_reader *r);

/* Reads from fd until one frame is complete (ISM_FRAME_OK: *f receives it, the reader is
 * ready for the next), the fd would block (ISM_FRAME_AGAIN), the peer closed (EOF or
 * TRUNCATED), or the stream is bad (an error; the reader is then unusable). On a blocking
 * fd it returns only with a frame, EOF or an error. */
ism_frame_status ism_frame_read_fd(ism_frame_reader *r, int fd, ism_frame *f);

/* ---- payload building and reading ----------------------------------------------------- */

/* A growable payload under construction. */
typedef struct ism_frame_builder {
    unsigned char *data;
    size_t len, cap;
    bool failed;        /* an allocation failed; the payload is incomplete */
} ism_frame_builder;

void ism_frame_builder_free(ism_frame_builder *b);
void ism_frame_put_u32(ism_frame_builder *b, uint32_t v);
void ism_frame_put_u64(ism_frame_builder *b, uint64_t v);
void ism_frame_put_bytes(ism_frame_builder *b, const void *data, size_t len); /* u32 len + bytes */
void ism_frame_put_str(ism_frame_builder *b, const char *s);                  /* NULL = "" */

/* Reads fields back in order; any read past the end sets failed and returns zeros. */
typedef struct ism_frame_cursor {
    const unsigned char *p;
    size_t left;
    bool failed;
} ism_frame_cursor;

void ism_frame_cursor_init(ism_frame_cursor *c, const void *data, size_t len);
uint32_t ism_frame_get_u32(ism_frame_cursor *c);
uint64_t ism_frame_get_u64(ism_frame_cursor *c);
/* A length-prefixed byte string: points into the payload (not terminated). */
const unsigned char *ism_frame_get_bytes(ism_frame_cursor *c, size_t *len);
/* A length-prefixed string copied into dst (size cap, always terminated); failed when it
 * does not fit or holds a NUL. */
void ism_frame_get_str(ism_frame_cursor *c, char *dst, size_t cap);

/* ---- the messages --------------------------------------------------------------------- */

/* REQUEST: the job the daemon asks a worker to run. */
typedef struct ism_frame_job {
    uint32_t max_depth;
    uint32_t threads;
    uint64_t max_triangles;
    uint64_t max_memory;
    uint32_t timeout_ms;       /* the daemon stops the job this long after sending it (0 =
                                  never): the worker's stages that can stop early do so
                                  before then */
    char format[8];            /* "" = the request's own format */
    const unsigned char *json; /* the request JSON (points into the payload when decoded) */
    size_t json_len;
    /* The stored computed surface of the request (proto/computed.h) to encode from instead
     * of polygonising; empty when there is none. */
    const unsigned char *computed;
    size_t computed_len;
} ism_frame_job;

bool ism_frame_job_encode(const ism_frame_job *j, ism_frame_builder *b);
bool ism_frame_job_decode(const ism_frame *f, ism_frame_job *j);

/* RESULT: what the pipeline answered. Byte fields point into the frame's payload when
 * decoded (keep the frame alive while using them). */
typedef struct ism_frame_result {
    uint32_t status;           /* HTTP-like: 200, 400, 422, 499, 500 */
    uint32_t worker_us;        /* wall time the worker spent on the job */
    char key[65];
    char surface_key[65];      /* the surface's key (request.h) */
    uint32_t polygonised;      /* 1: computed from scratch; 0: encoded from a stored surface */
    char format[8];
    char content_type[64];
    const unsigned char *body, *stats, *features, *canonical;
    size_t body_len, stats_len, features_len, canonical_len;
    /* Bytes of the computed surface's entry (newly computed) the SURFACE frame after this
     * one carries; 0: none follows. Why apart: the daemon answers the request as soon as the
     * RESULT is in, while the surface (a 100k-triangle kummer: 5.5 MB against its 385 KB
     * mesh) still crosses the pipe; in the same frame its crossing and checksum came first
     * (5-11 ms of a cold request's 17-22 ms in the daemon at load 9). */
    uint32_t surface_len;
} ism_frame_result;

/* RESULT frames are written in three parts so the mesh body is not copied: fills head with
 * every field up to and including the body's length, and tail with surface_len; the frame
 * is then {head, body, tail}. */
bool ism_frame_result_encode(const ism_frame_result *r, ism_frame_builder *head,
                             unsigned char tail[4]);
bool ism_frame_result_decode(const ism_frame *f, ism_frame_result *r);

#endif
