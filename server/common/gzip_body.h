/* gzip_body.h — Content-Encoding: gzip for the JSON documents the daemon sends (the features
 * JSON beside a mesh is mostly decimal digits: gzip makes it 2.3-10x smaller): whether a
 * request's Accept-Encoding takes gzip, and a blob's gzip bytes (zlib from Debian). The
 * meshes themselves are Draco (already entropy coded: gzip gains nothing) and never go
 * through here. */
#ifndef ISM_GZIP_BODY_H
#define ISM_GZIP_BODY_H

#include <stdbool.h>
#include <stddef.h>

#include "server/common/blob.h"

/* Bodies shorter than this go as they are: gzip's own 18 bytes of header and trailer and the
 * request's CPU outweigh what a few hundred bytes of JSON would save (a stats or error body). */
#define ISM_GZIP_MIN_BODY 1024

/* zlib's level. A document is compressed once per cache entry (ISM_GZIP_FEATURES_EXT), by
 * the worker pool's thread or, for an entry stored without it, by the HTTP thread, where its
 * CPU is a pause for every other connection of that thread. Since session 20 the features
 * print their polylines within the mesh's bound (proto/features.h): gyroid-ball's is 31.5 KB
 * (6.8M instructions at level 6, once; it was 376 KB, 42.5M at level 1, per request), and the
 * large documents are requested curves in full precision. Measured before that on the features JSON of session
 * 19 (default bound; bytes and CPU ms per compression at load 15-30, zlib 1.2.13):
 *   klein-bottle 20,195 B -> level 1 9,586 / 0.24 ms, level 6 8,584 / 0.63 ms
 *   crossing-spheres 61,852 -> 28,240 / 0.60, 26,423 / 3.09
 *   cube-minus-ball 177,360 -> 35,627 / 0.92, 23,821 / 3.66
 *   three-balls 326,709 -> 139,534 / 2.98, 126,517 / 17.5
 *   gyroid-ball 1,258,122 -> 554,084 / 11.8, 521,023 / 76.2 (level 9: no smaller than 6 by
 *   more than 6% on the singular presets, at 1.7-5.4x 6's CPU)
 * So: 6 (zlib's default) up to ISM_GZIP_FAST_ABOVE, where it costs a few ms; 1 above it,
 * where 6 would stall the thread for tens of ms to save 6-10%. */
#define ISM_GZIP_LEVEL 6
#define ISM_GZIP_FAST_LEVEL 1
#define ISM_GZIP_FAST_ABOVE (128u * 1024u)

/* The cache entry of a features document's gzip bytes, beside "<key>.features.json": made
 * once per entry (the worker pool when it stores a fresh result, else the first request that
 * takes gzip), so a client fetching the document again never costs a compression. */
#define ISM_GZIP_FEATURES_EXT "features.json.gz"

/* Whether an Accept-Encoding header value (NULL: absent) accepts gzip (RFC 9110 12.5.3):
 * "gzip", "x-gzip" or "*" listed with a q-value other than 0 (an explicit "gzip;q=0" refuses
 * it even beside "*"). */
bool ism_accepts_gzip(const char *accept_encoding);

/* A new blob holding data's gzip stream (RFC 1952), at the level above for its size; NULL when
 * out of memory. */
ism_blob *ism_gzip_blob(const void *data, size_t len);

#endif
