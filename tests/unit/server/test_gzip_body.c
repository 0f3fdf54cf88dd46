/* test_gzip_body.c — Accept-Encoding's gzip test against RFC 9110's rules (names case-blind,
 * q=0 refuses, an explicit gzip entry overrides "*"), and the gzip stream inflating back to
 * the very bytes given (zlib's own inflate, as a browser's). */
#include <criterion/criterion.h>
#include <stdlib.h>
#include <string.h>
#include <zlib.h>

#include "server/common/gzip_body.h"

Test(gzip_body, accept_encoding_values)
{
    static const struct {
        const char *v;
        bool gzip;
    } cases[] = {
        {NULL, false},
        {"", false},
        {"gzip", true},
        {"GZip", true},
        {"x-gzip", true},
        {"gzip, deflate, br, zstd", true}, /* what Chromium's fetch sends */
        {"br;q=1.0, gzip;q=0.5", true},
        {"gzip;q=0", false},
        {"gzip; q=0.000", false},
        {"gzip;q=0.001", true},
        {"*", true},
        {"*;q=0", false},
        {"*, gzip;q=0", false},
        {"gzip;q=0, *", false},
        {"identity", false},
        {"br", false},
        {"deflate", false},
        {"gzipped", false},
        {"agzip", false},
        {" , ,gzip", true},
    };
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++)
        cr_expect_eq(ism_accepts_gzip(cases[i].v), cases[i].gzip, "\"%s\"",
                     cases[i].v ? cases[i].v : "(absent)");
}

/* Inflates a gzip stream (windowBits 15 + 16 accepts only gzip's header) into out. */
static size_t gunzip(const unsigned char *in, size_t n, unsigned char *out, size_t cap)
{
    z_stream z;
    memset(&z, 0, sizeof z);
    cr_assert_eq(inflateInit2(&z, 15 + 16), Z_OK);
    z.next_in = (Bytef *)in;
    z.avail_in = (uInt)n;
    z.next_out = out;
    z.avail_out = (uInt)cap;
    int rc = inflate(&z, Z_FINISH);
    size_t got = cap - z.avail_out;
    inflateEnd(&z);
    cr_assert_eq(rc, Z_STREAM_END, "the stream does not end where gzip's trailer says");
    return got;
}

Test(gzip_body, inflates_back_to_the_bytes)
{
    /* features-like text (digits repeat, as in coordinate lists), an empty body, and bytes
     * no compressor can shrink */
    size_t n = 400000; /* halves above ISM_GZIP_FAST_ABOVE: both levels run */
    unsigned char *text = malloc(n), *back = malloc(n + 64);
    cr_assert(text && back);
    unsigned s = 12345;
    for (size_t i = 0; i < n; i++) {
        s = s * 1103515245u + 12345u;
        text[i] = i < n / 2 ? (unsigned char)"0123456789.,-[]"[(s >> 16) % 15]
                            : (unsigned char)(s >> 24);
    }
    const size_t lens[] = {ISM_GZIP_FAST_ABOVE / 2, n / 2, 0, n};
    for (size_t t = 0; t < 4; t++) {
        ism_blob *gz = ism_gzip_blob(text, lens[t]);
        cr_assert_not_null(gz);
        cr_expect_eq(gz->data[0], 0x1f); /* gzip's magic (RFC 1952 2.3.1) */
        cr_expect_eq(gz->data[1], 0x8b);
        cr_expect_eq(gz->data[gz->len], 0, "blobs end in a NUL");
        size_t got = gunzip(gz->data, gz->len, back, n + 64);
        cr_expect_eq(got, lens[t]);
        cr_expect(memcmp(back, text, lens[t]) == 0);
        if (t < 2) /* 15 equally likely symbols: Huffman codes of 3-4 bits, ~0.5 B a byte */
            cr_expect_lt(gz->len, lens[t] * 6 / 10, "%zu of %zu", gz->len, lens[t]);
        else /* stored blocks: 5 bytes per 16K block besides the 18 of header and trailer */
            cr_expect_leq(gz->len, lens[t] + 5 * (lens[t] / 16384 + 1) + 18, "%zu of %zu",
                          gz->len, lens[t]);
        ism_blob_unref(gz);
    }
    free(text);
    free(back);
}
