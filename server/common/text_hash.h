/* text_hash.h — the hash of a NUL-terminated string for the servers' chained hash tables
 * (cache names, in-flight computations, users' queues): FNV-1a over its bytes. Only bucket
 * choice depends on it; nothing stores or sends it. */
#ifndef ISM_TEXT_HASH_H
#define ISM_TEXT_HASH_H

#include <stdint.h>

static inline uint64_t ism_text_hash(const char *s)
{
    uint64_t h = 1469598103934665603ULL;
    for (; *s; s++) {
        h ^= (unsigned char)*s;
        h *= 1099511628211ULL;
    }
    return h;
}

#endif
