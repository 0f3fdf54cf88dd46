/* write_sink.h — a small buffer between the mesh writers and the caller's write callback,
 * so that a writer can emit a few bytes at a time without one callback call per number.
 * Internal to core/mesh/write_*.c. */
#ifndef ISM_WRITE_SINK_H
#define ISM_WRITE_SINK_H

#include <stddef.h>
#include <stdint.h>
#include <stdbool.h>
#include <string.h>
#include "core/mesh/write_mesh.h"

typedef struct ism_sink {
    ism_write_fn write;
    void *ctx;
    bool failed;
    size_t used;
    unsigned char buf[1 << 16];
} ism_sink;

void ism_sink_init(ism_sink *s, ism_write_fn write, void *ctx);

/* Appends bytes (flushing as needed). Once a write fails, everything after is dropped. */
void ism_sink_put(ism_sink *s, const void *p, size_t n);

/* Appends printf-formatted text (each call at most 255 bytes). */
void ism_sink_printf(ism_sink *s, const char *fmt, ...) __attribute__((format(printf, 2, 3)));

/* Appends n bytes, n small: copied straight into the buffer while they fit (the writers emit
 * a mesh a number at a time: a call per number cost 70 instructions, a third of the CLI's
 * PLY time), else through ism_sink_put. Bytes that land after a failed write are dropped
 * at the next flush, as ism_sink_put drops them. */
static inline void ism_sink_put_small(ism_sink *s, const void *p, size_t n)
{
    if (n <= sizeof s->buf - s->used) {
        memcpy(s->buf + s->used, p, n);
        s->used += n;
    } else {
        ism_sink_put(s, p, n);
    }
}

/* Little-endian scalars. */
static inline void ism_sink_u8(ism_sink *s, uint8_t v) { ism_sink_put_small(s, &v, 1); }

static inline void ism_sink_u16le(ism_sink *s, uint16_t v)
{
    unsigned char b[2] = {(unsigned char)v, (unsigned char)(v >> 8)};
    ism_sink_put_small(s, b, 2);
}

static inline void ism_sink_u32le(ism_sink *s, uint32_t v)
{
    unsigned char b[4] = {(unsigned char)v, (unsigned char)(v >> 8), (unsigned char)(v >> 16),
                          (unsigned char)(v >> 24)};
    ism_sink_put_small(s, b, 4);
}

static inline void ism_sink_f32le(ism_sink *s, float v)
{
    uint32_t u;
    memcpy(&u, &v, 4);
    ism_sink_u32le(s, u);
}

/* PLY's face element of m: per triangle a uchar 3 and three int32 (write_ply.c; shared with
 * the service's PLY writer). */
void ism_ply_put_faces(ism_sink *s, const ism_mesh *m);

/* Flushes what is buffered; true when every byte was accepted by the callback. */
bool ism_sink_finish(ism_sink *s);

#endif
