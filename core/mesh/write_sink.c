/* write_sink.c — the buffered byte sink of the mesh writers: collects small pieces (numbers,
 * text lines) in a 64 KiB buffer and hands them to the caller's callback in large writes,
 * remembering the first failed write so that writers need not check every call. */
#include "core/mesh/write_sink.h"

#include <stdarg.h>
#include <stdio.h>
#include <string.h>

void ism_sink_init(ism_sink *s, ism_write_fn write, void *ctx)
{
    s->write = write;
    s->ctx = ctx;
    s->failed = false;
    s->used = 0;
}

static void flush(ism_sink *s)
{
    if (s->used && !s->failed && s->write(s->ctx, s->buf, s->used) != s->used)
        s->failed = true;
    s->used = 0;
}

void ism_sink_put(ism_sink *s, const void *p, size_t n)
{
    const unsigned char *b = p;
    while (n && !s->failed) {
        if (s->used == sizeof s->buf)
            flush(s);
        size_t room = sizeof s->buf - s->used;
        size_t k = n < room ? n : room;
        memcpy(s->buf + s->used, b, k);
        s->used += k;
        b += k;
        n -= k;
    }
}

void ism_sink_printf(ism_sink *s, const char *fmt, ...)
{
    char line[256];
    va_list ap;
    va_start(ap, fmt);
    int n = vsnprintf(line, sizeof line, fmt, ap);
    va_end(ap);
    if (n < 0 || (size_t)n >= sizeof line) {
        s->failed = true;
        return;
    }
    ism_sink_put(s, line, (size_t)n);
}

bool ism_sink_finish(ism_sink *s)
{
    flush(s);
    return !s->failed;
}
