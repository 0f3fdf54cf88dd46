/* png.h — a PNG writer for 8-bit RGBA images (the daemon's thumbnails): rows filtered with
 * Sub, compressed by our own deflate (LZ77 over a 32 KiB window, fixed Huffman codes). */
#ifndef ISM_PNG_H
#define ISM_PNG_H

#include <stdbool.h>
#include <stddef.h>

/* Encodes a w x h image of RGBA pixels (row-major, 4 bytes each, straight alpha) as a PNG
 * file: *out malloc'd, *len its size. False when out of memory or w, h out of 1..16384. */
bool ism_png_rgba(const unsigned char *rgba, int w, int h, unsigned char **out, size_t *len);

/* zlib stream (RFC 1950) of n bytes compressed with fixed-Huffman deflate (RFC 1951); *out
 * malloc'd. False when out of memory. */
bool ism_zlib_compress(const unsigned char *in, size_t n, unsigned char **out, size_t *len);

#endif
