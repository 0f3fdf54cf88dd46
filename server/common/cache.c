/* cache.c — the tier stack of cache.h: lookups that fall through and promote, stores that go
 * everywhere, and the entry-name rules every tier relies on (no tier ever sees a name that
 * could escape a directory). */
#include "server/common/cache.h"
#include "server/common/gzip_body.h"
#include "proto/computed.h"
#include "proto/request.h"

#include <stdio.h>
#include <string.h>

/* What else an entry can be besides a mesh file (the formats are proto/format.c's). */
static const char *const DOCUMENTS[] = {"stats.json", "features.json", "request.json",
                                        ISM_COMPUTED_EXT, ISM_GZIP_FEATURES_EXT};

bool ism_cache_name_valid(const char *name)
{
    if (strlen(name) < ISM_KEY_HEX_LEN + 2 || name[ISM_KEY_HEX_LEN] != '.')
        return false;
    char key[ISM_KEY_HEX_LEN + 1];
    memcpy(key, name, ISM_KEY_HEX_LEN);
    key[ISM_KEY_HEX_LEN] = 0;
    const char *ext = name + ISM_KEY_HEX_LEN + 1;
    if (!ism_key_valid(key))
        return false;
    if (ism_format_lookup(ext) >= 0)
        return true;
    for (size_t i = 0; i < sizeof DOCUMENTS / sizeof DOCUMENTS[0]; i++)
        if (strcmp(ext, DOCUMENTS[i]) == 0)
            return true;
    return false;
}

bool ism_cache_name(char out[ISM_CACHE_NAME_MAX], const char *key, const char *ext)
{
    /* "key.ext" by copies (snprintf's format parsing cost more than the checks) */
    size_t k = strlen(key), e = strlen(ext);
    if (k + 1 + e >= ISM_CACHE_NAME_MAX) {
        out[0] = 0;
        return false;
    }
    memcpy(out, key, k);
    out[k] = '.';
    memcpy(out + k + 1, ext, e + 1);
    return ism_cache_name_valid(out);
}

bool ism_cache_add_tier(ism_cache *c, ism_cache_tier *t)
{
    if (!t || c->ntiers >= ISM_CACHE_MAX_TIERS)
        return false;
    c->tiers[c->ntiers++] = t;
    return true;
}

ism_blob *ism_cache_get(ism_cache *c, const char *name, int *tier)
{
    if (tier)
        *tier = -1;
    if (!ism_cache_name_valid(name))
        return NULL;
    for (size_t i = 0; i < c->ntiers; i++) {
        if (c->tiers[i]->remote)
            continue;
        ism_blob *b = c->tiers[i]->get(c->tiers[i], name);
        if (b) {
            atomic_fetch_add(&c->tiers[i]->counters.hits, 1);
            for (size_t j = 0; j < i; j++)
                c->tiers[j]->put(c->tiers[j], name, b);
            if (tier)
                *tier = (int)i;
            return b;
        }
        atomic_fetch_add(&c->tiers[i]->counters.misses, 1);
    }
    return NULL;
}

ism_blob *ism_cache_get_fast(ism_cache *c, const char *name)
{
    if (c->ntiers == 0 || !ism_cache_name_valid(name))
        return NULL;
    return c->tiers[0]->get(c->tiers[0], name);
}

bool ism_cache_has(ism_cache *c, const char *name)
{
    if (!ism_cache_name_valid(name))
        return false;
    for (size_t i = 0; i < c->ntiers; i++)
        if (!c->tiers[i]->remote && c->tiers[i]->has(c->tiers[i], name))
            return true;
    return false;
}

void ism_cache_put(ism_cache *c, const char *name, ism_blob *b)
{
    if (!b || !ism_cache_name_valid(name))
        return;
    for (size_t i = 0; i < c->ntiers; i++)
        c->tiers[i]->put(c->tiers[i], name, b);
}

/* Stores into the tiers whose remote flag is remote. */
static void put_where(ism_cache *c, const char *name, ism_blob *b, bool remote)
{
    if (!b || !ism_cache_name_valid(name))
        return;
    for (size_t i = 0; i < c->ntiers; i++)
        if (c->tiers[i]->remote == remote)
            c->tiers[i]->put(c->tiers[i], name, b);
}

void ism_cache_put_local(ism_cache *c, const char *name, ism_blob *b)
{
    put_where(c, name, b, false);
}

void ism_cache_put_remote(ism_cache *c, const char *name, ism_blob *b)
{
    put_where(c, name, b, true);
}

ism_blob *ism_cache_put_features_gzip(ism_cache *c, const char *key, const ism_blob *plain)
{
    ism_blob *gz = ism_gzip_blob(plain->data, plain->len);
    char name[ISM_CACHE_NAME_MAX];
    if (gz && ism_cache_name(name, key, ISM_GZIP_FEATURES_EXT))
        ism_cache_put_local(c, name, gz);
    return gz;
}

void ism_cache_close(ism_cache *c)
{
    for (size_t i = c->ntiers; i-- > 0;)
        c->tiers[i]->close(c->tiers[i]);
    c->ntiers = 0;
}
