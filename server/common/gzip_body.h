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

/* zlib's level, measured on the features JSON at the default bound (full-precision digits;
 * bytes and CPU ms per compression): klein-bottle 28,462 B -> 13,642 / 0.21 at 1, 12,173 / 0.93
 * at 6, 11,516 / 1.62 at 9; steiner-roman 31,980 -> 3,972 / 3,307 / 3,122 (0.06 / 0.22 / 1.19
 * ms); kummer-16-nodes 17,771 -> 6,551 / 5,990 / 5,992. 6 (zlib's default) is within 6% of 9's
 * size at 0.2-0.85x its CPU; 1 gives up 8-20%. */
#define ISM_GZIP_LEVEL 6

/* Whether an Accept-Encoding header value (NULL: absent) accepts gzip (RFC 9110 12.5.3):
 * "gzip", "x-gzip" or "*" listed with a q-value other than 0 (an explicit "gzip;q=0" refuses
 * it even beside "*"). */
bool ism_accepts_gzip(const char *accept_encoding);

/* A new blob holding data's gzip stream (RFC 1952); NULL when out of memory. */
ism_blob *ism_gzip_blob(const void *data, size_t len);

#endif
