/* cache.h — the mesh cache as an ordered stack of tiers (memory, disk, a shared Redis), each
 * behind the same small interface. A lookup walks the local tiers from the fastest and copies
 * a hit into the faster tiers it missed; a store goes to every tier. A remote tier (Redis) is
 * never read by a lookup: its reads are network calls that the daemon makes off the HTTP
 * thread, on the computation's path (server/isomeshd/shared_cache.h).
 *
 * Entries are named "<key>.<ext>": the 64-hex-digit cache key of a request (pipeline.h) and
 * what the bytes are: a mesh file ("drc", "glb", "ply", "obj", "stl"), its statistics
 * ("stats.json"), its non-manifold features ("features.json") and their gzip bytes
 * ("features.json.gz", server/common/gzip_body.h) or the canonical request that
 * produced it ("request.json"); or, under a surface key, the computed surface every encoding
 * is made from ("mesh", versioned format in proto/computed.h). Content-addressed: one name
 * always means the same bytes. */
#ifndef ISM_CACHE_H
#define ISM_CACHE_H

#include <stdatomic.h>
#include <stdbool.h>
#include <stddef.h>

#include "server/common/blob.h"

#define ISM_CACHE_NAME_MAX 96
#define ISM_CACHE_MAX_TIERS 4

/* Figures every tier keeps (read by /metrics). */
typedef struct ism_cache_counters {
    atomic_ullong hits, misses;
    atomic_ullong stores, store_failures; /* failures: disk full or unwritable, skipped writes */
    atomic_ullong corrupt;                /* entries that failed their checksum (dropped) */
    atomic_ullong evictions;
    atomic_ullong bytes, entries;         /* current size, where the tier knows it */
} ism_cache_counters;

typedef struct ism_cache_tier ism_cache_tier;
struct ism_cache_tier {
    const char *name; /* "memory", "disk", ... */
    bool remote;      /* reads go over the network: ism_cache_get and _has skip it */
    ism_cache_counters counters;
    /* A new reference to the entry's bytes, or NULL on a miss (ism_cache_get counts). */
    ism_blob *(*get)(ism_cache_tier *t, const char *name);
    /* Whether the tier holds the entry (no counting, no promotion). */
    bool (*has)(ism_cache_tier *t, const char *name);
    /* Stores the entry (the tier takes its own reference; it may store it later). */
    void (*put)(ism_cache_tier *t, const char *name, ism_blob *b);
    /* Finishes pending work and frees the tier. */
    void (*close)(ism_cache_tier *t);
};

typedef struct ism_cache {
    ism_cache_tier *tiers[ISM_CACHE_MAX_TIERS];
    size_t ntiers;
} ism_cache;

/* Appends a tier below the existing ones (the first added is the fastest). */
bool ism_cache_add_tier(ism_cache *c, ism_cache_tier *t);
/* Looks name up in the local tiers, fastest first; *tier gets the index of the tier that hit (or -1).
 * A hit below the first tier is copied into the tiers above it. */
ism_blob *ism_cache_get(ism_cache *c, const char *name, int *tier);
/* Looks name up in the first tier only, without counting (cheap; used under locks). */
ism_blob *ism_cache_get_fast(ism_cache *c, const char *name);
bool ism_cache_has(ism_cache *c, const char *name);
void ism_cache_put(ism_cache *c, const char *name, ism_blob *b);
/* Stores into the local tiers only (an entry that came from a remote tier, or one whose
 * remote writes wait for another entry: ism_cache_put_remote later). */
void ism_cache_put_local(ism_cache *c, const char *name, ism_blob *b);
/* Stores into the remote tiers only (the rest of a put_local). */
void ism_cache_put_remote(ism_cache *c, const char *name, ism_blob *b);
/* The gzip bytes of key's features document plain (gzip_body.h), stored as its
 * ISM_GZIP_FEATURES_EXT entry in the local tiers only (a peer that fetches the plain entry
 * makes its own): a new reference to them, or NULL when out of memory (nothing stored). */
ism_blob *ism_cache_put_features_gzip(ism_cache *c, const char *key, const ism_blob *plain);
/* Closes every tier, slowest last. */
void ism_cache_close(ism_cache *c);

/* True when name is "<64 lowercase hex>.<ext>" with ext one of the kinds listed above. */
bool ism_cache_name_valid(const char *name);
/* Writes "<key>.<ext>" into out (ISM_CACHE_NAME_MAX bytes); false when it would be invalid. */
bool ism_cache_name(char out[ISM_CACHE_NAME_MAX], const char *key, const char *ext);

#endif
