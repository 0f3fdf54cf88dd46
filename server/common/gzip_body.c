/* gzip_body.c — Accept-Encoding's gzip test and a blob's gzip stream (gzip_body.h). */
#include "server/common/gzip_body.h"

#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include <zlib.h>

/* The q-value of one list element's parameters p..end (";q=0.5"); 1 when none is given. */
static double q_value(const char *p, const char *end)
{
    while (p < end) {
        while (p < end && (*p == ';' || *p == ' ' || *p == '\t'))
            p++;
        if (end - p >= 2 && (p[0] == 'q' || p[0] == 'Q') && p[1] == '=') {
            char buf[16];
            size_t n = (size_t)(end - p - 2);
            n = n < sizeof buf - 1 ? n : sizeof buf - 1;
            memcpy(buf, p + 2, n);
            buf[n] = '\0';
            return strtod(buf, NULL);
        }
        while (p < end && *p != ';')
            p++;
    }
    return 1.0;
}

bool ism_accepts_gzip(const char *v)
{
    if (!v)
        return false;
    int gzip = -1, star = -1; /* -1 unnamed, 0 refused, 1 accepted */
    const char *p = v;
    while (*p) {
        while (*p == ',' || *p == ' ' || *p == '\t')
            p++;
        const char *e = p + strcspn(p, ",");
        const char *name_end = p + strcspn(p, ";, \t");
        if (name_end > e)
            name_end = e;
        size_t n = (size_t)(name_end - p);
        int ok = q_value(name_end, e) > 0.0;
        if ((n == 4 && !strncasecmp(p, "gzip", 4)) || (n == 6 && !strncasecmp(p, "x-gzip", 6)))
            gzip = gzip == 0 ? 0 : ok;
        else if (n == 1 && *p == '*')
            star = ok;
        p = e;
    }
    return gzip >= 0 ? gzip == 1 : star == 1;
}

ism_blob *ism_gzip_blob(const void *data, size_t len)
{
    if (len > (1u << 30)) /* zlib counts in uInt; no JSON document comes near */
        return NULL;
    z_stream z;
    memset(&z, 0, sizeof z);
    /* windowBits 15 + 16: a gzip header and trailer instead of zlib's */
    int level = len > ISM_GZIP_FAST_ABOVE ? ISM_GZIP_FAST_LEVEL : ISM_GZIP_LEVEL;
    if (deflateInit2(&z, level, Z_DEFLATED, 15 + 16, 8, Z_DEFAULT_STRATEGY) != Z_OK)
        return NULL;
    uLong bound = deflateBound(&z, (uLong)len);
    ism_blob *b = ism_blob_new(bound);
    if (!b) {
        deflateEnd(&z);
        return NULL;
    }
    z.next_in = (Bytef *)data;
    z.avail_in = (uInt)len;
    z.next_out = b->data;
    z.avail_out = (uInt)bound;
    int rc = deflate(&z, Z_FINISH);
    size_t out = bound - z.avail_out;
    deflateEnd(&z);
    if (rc != Z_STREAM_END) { /* deflateBound is an upper bound: cannot happen */
        ism_blob_unref(b);
        return NULL;
    }
    b->len = out;
    b->data[out] = '\0';
    return b;
}
