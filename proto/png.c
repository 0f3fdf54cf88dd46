/* png.c — the PNG writer of png.h: chunk framing with CRC-32, the zlib wrapper with Adler-32,
 * and a small deflate (hash-chained LZ77, one block of fixed Huffman codes). Thumbnails are
 * mostly empty background and smooth shading, which this compresses 5-20x. */
#include "proto/png.h"

#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#define MAX_SIDE 16384           /* larger images are refused: bounded memory */
#define WINDOW 32768             /* deflate's largest distance */
#define HASH_BITS 15
#define MIN_MATCH 3
#define MAX_MATCH 258
#define MAX_CHAIN 32             /* candidates tried per position: speed over ratio */

/* ---- bit output, least significant bit first (RFC 1951 3.1.1) ------------------------ */

typedef struct bits {
    unsigned char *p;
    size_t n;
    uint64_t acc;
    int nacc;
} bits;

static void put_bits(bits *b, uint32_t v, int n)
{
    b->acc |= (uint64_t)v << b->nacc;
    b->nacc += n;
    while (b->nacc >= 8) {
        b->p[b->n++] = (unsigned char)b->acc;
        b->acc >>= 8;
        b->nacc -= 8;
    }
}

/* A Huffman code is sent most significant bit first. */
static void put_code(bits *b, uint32_t code, int n)
{
    uint32_t r = 0;
    for (int i = 0; i < n; i++)
        r |= ((code >> i) & 1u) << (n - 1 - i);
    put_bits(b, r, n);
}

/* The fixed literal/length code of symbol s (RFC 1951 3.2.6). */
static void put_litlen(bits *b, unsigned s)
{
    if (s < 144)
        put_code(b, 0x30 + s, 8);
    else if (s < 256)
        put_code(b, 0x190 + (s - 144), 9);
    else if (s < 280)
        put_code(b, s - 256, 7);
    else
        put_code(b, 0xc0 + (s - 280), 8);
}

static const uint16_t len_base[29] = {3,  4,  5,  6,  7,  8,  9,  10, 11,  13,  15,  17,  19,  23, 27,
                                      31, 35, 43, 51, 59, 67, 83, 99, 115, 131, 163, 195, 227, 258};
static const uint8_t len_extra[29] = {0, 0, 0, 0, 0, 0, 0, 0, 1, 1, 1, 1, 2, 2, 2,
                                      2, 3, 3, 3, 3, 4, 4, 4, 4, 5, 5, 5, 5, 0};
static const uint16_t dist_base[30] = {1,    2,    3,    4,    5,    7,     9,     13,    17,  25,
                                       33,   49,   65,   97,   129,  193,   257,   385,   513, 769,
                                       1025, 1537, 2049, 3073, 4097, 6145, 8193, 12289, 16385, 24577};
static const uint8_t dist_extra[30] = {0, 0, 0, 0, 1, 1, 2, 2,  3,  3,  4,  4,  5,  5,  6,
                                       6, 7, 7, 8, 8, 9, 9, 10, 10, 11, 11, 12, 12, 13, 13};

static void put_match(bits *b, unsigned len, unsigned dist)
{
    int i = 28;
    while (len_base[i] > len)
        i--;
    put_litlen(b, 257 + (unsigned)i);
    put_bits(b, len - len_base[i], len_extra[i]);
    int d = 29;
    while (dist_base[d] > dist)
        d--;
    put_code(b, (uint32_t)d, 5);
    put_bits(b, dist - dist_base[d], dist_extra[d]);
}

/* ---- LZ77 ---------------------------------------------------------------------------- */

static uint32_t hash3(const unsigned char *p)
{
    uint32_t v = (uint32_t)p[0] << 16 | (uint32_t)p[1] << 8 | p[2];
    return (v * 2654435761u) >> (32 - HASH_BITS);
}

/* The longest earlier match of in[i..] (length >= MIN_MATCH), or length 0. */
static unsigned longest(const unsigned char *in, size_t n, size_t i, const int32_t *head,
                        const int32_t *prev, unsigned *dist)
{
    unsigned best = 0;
    size_t max = n - i < MAX_MATCH ? n - i : MAX_MATCH;
    int32_t c = head[hash3(in + i)];
    for (int tries = 0; c >= 0 && i - (size_t)c <= WINDOW && tries < MAX_CHAIN; tries++) {
        size_t l = 0;
        while (l < max && in[(size_t)c + l] == in[i + l])
            l++;
        if (l > best) {
            best = (unsigned)l;
            *dist = (unsigned)(i - (size_t)c);
            if (l == max)
                break;
        }
        c = prev[(size_t)c % WINDOW];
    }
    return best >= MIN_MATCH ? best : 0;
}

static void insert(const unsigned char *in, size_t i, int32_t *head, int32_t *prev)
{
    uint32_t h = hash3(in + i);
    prev[i % WINDOW] = head[h];
    head[h] = (int32_t)i;
}

/* One final block of fixed codes; b->p has room for 9/8 n + 8 bytes. */
static bool deflate_fixed(const unsigned char *in, size_t n, bits *b)
{
    int32_t *head = malloc(sizeof *head << HASH_BITS), *prev = malloc(sizeof *prev * WINDOW);
    if (!head || !prev) {
        free(head);
        free(prev);
        return false;
    }
    memset(head, 0xff, sizeof *head << HASH_BITS);
    put_bits(b, 1, 1); /* BFINAL */
    put_bits(b, 1, 2); /* BTYPE 01: fixed Huffman codes */
    size_t i = 0;
    while (i < n) {
        unsigned dist = 0, len = n - i >= MIN_MATCH ? longest(in, n, i, head, prev, &dist) : 0;
        if (len) {
            put_match(b, len, dist);
            for (size_t k = i; k < i + len && k + MIN_MATCH <= n; k++)
                insert(in, k, head, prev);
            i += len;
        } else {
            put_litlen(b, in[i]);
            if (i + MIN_MATCH <= n)
                insert(in, i, head, prev);
            i++;
        }
    }
    put_litlen(b, 256);
    if (b->nacc)
        put_bits(b, 0, 8 - b->nacc);
    free(head);
    free(prev);
    return true;
}

static void put_be32(unsigned char *p, uint32_t v)
{
    p[0] = (unsigned char)(v >> 24);
    p[1] = (unsigned char)(v >> 16);
    p[2] = (unsigned char)(v >> 8);
    p[3] = (unsigned char)v;
}

bool ism_zlib_compress(const unsigned char *in, size_t n, unsigned char **out, size_t *len)
{
    /* A literal costs at most 9 bits: 9/8 n, plus header, end code and check value. */
    bits b = {malloc(n + n / 8 + 16), 0, 0, 0};
    if (!b.p)
        return false;
    b.p[b.n++] = 0x78; /* deflate, 32 KiB window */
    b.p[b.n++] = 0x01; /* fastest level; (0x78 << 8 | 0x01) % 31 == 0 */
    if (!deflate_fixed(in, n, &b)) {
        free(b.p);
        return false;
    }
    uint32_t s1 = 1, s2 = 0;
    for (size_t i = 0; i < n; i++) {
        s1 = (s1 + in[i]) % 65521;
        s2 = (s2 + s1) % 65521;
    }
    put_be32(b.p + b.n, s2 << 16 | s1);
    *out = b.p;
    *len = b.n + 4;
    return true;
}

/* ---- PNG ----------------------------------------------------------------------------- */

static uint32_t crc32(const unsigned char *p, size_t n)
{
    uint32_t c = 0xffffffffu;
    for (size_t i = 0; i < n; i++) {
        c ^= p[i];
        for (int k = 0; k < 8; k++)
            c = (c >> 1) ^ (0xedb88320u & (0u - (c & 1u)));
    }
    return ~c;
}

/* Appends chunk type (4 letters) with data at o; returns the new end. */
static unsigned char *chunk(unsigned char *o, const char *type, const unsigned char *data,
                            size_t n)
{
    put_be32(o, (uint32_t)n);
    memcpy(o + 4, type, 4);
    if (n)
        memcpy(o + 8, data, n);
    put_be32(o + 8 + n, crc32(o + 4, n + 4));
    return o + 12 + n;
}

/* Rows with filter type 1 (Sub): each byte minus the same channel of the pixel to its left. */
static unsigned char *filter_rows(const unsigned char *rgba, int w, int h, size_t *n)
{
    size_t stride = (size_t)w * 4;
    *n = (stride + 1) * (size_t)h;
    unsigned char *f = malloc(*n);
    if (!f)
        return NULL;
    for (int y = 0; y < h; y++) {
        const unsigned char *row = rgba + stride * (size_t)y;
        unsigned char *o = f + (stride + 1) * (size_t)y;
        o[0] = 1;
        for (size_t i = 0; i < stride; i++)
            o[1 + i] = (unsigned char)(row[i] - (i >= 4 ? row[i - 4] : 0));
    }
    return f;
}

bool ism_png_rgba(const unsigned char *rgba, int w, int h, unsigned char **out, size_t *len)
{
    if (w < 1 || h < 1 || w > MAX_SIDE || h > MAX_SIDE)
        return false;
    size_t raw_len, z_len;
    unsigned char *raw = filter_rows(rgba, w, h, &raw_len), *z = NULL;
    bool ok = raw && ism_zlib_compress(raw, raw_len, &z, &z_len);
    free(raw);
    static const unsigned char sig[8] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};
    unsigned char *file = ok ? malloc(sizeof sig + 25 + 12 + z_len + 12) : NULL;
    if (!file) {
        free(z);
        return false;
    }
    unsigned char ihdr[13];
    put_be32(ihdr, (uint32_t)w);
    put_be32(ihdr + 4, (uint32_t)h);
    ihdr[8] = 8;  /* bits per channel */
    ihdr[9] = 6;  /* RGBA */
    ihdr[10] = ihdr[11] = ihdr[12] = 0; /* deflate, adaptive filtering, no interlace */
    memcpy(file, sig, sizeof sig);
    unsigned char *o = chunk(file + sizeof sig, "IHDR", ihdr, sizeof ihdr);
    o = chunk(o, "IDAT", z, z_len);
    o = chunk(o, "IEND", NULL, 0);
    free(z);
    *out = file;
    *len = (size_t)(o - file);
    return true;
}
