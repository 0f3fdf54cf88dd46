/* test_cache_redis.c — the shared tier's stored form and settings (server/common/cache_redis.h):
 * a value decodes to the bytes that were encoded, and any damage (every flipped byte, any
 * truncation or extension, a value read under another entry's name) is refused with a
 * reason; Redis addresses parse or are refused; a tier whose Redis cannot be reached
 * answers as down, skips writes (counted) and closes promptly. The tier's behaviour against
 * a live Redis is tested end to end in tests/deploy/. */
#include <criterion/criterion.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "server/common/cache.h"
#include "server/common/cache_redis.h"

#define KEY_A "aaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaa"
#define KEY_B "0123456789abcdef0123456789abcdef0123456789abcdef0123456789abcdef"

static ism_blob *filled(size_t n, unsigned char seed)
{
    ism_blob *b = ism_blob_new(n);
    for (size_t i = 0; i < n; i++)
        b->data[i] = (unsigned char)(seed + i * 29);
    return b;
}

Test(redis_value, round_trip_keeps_every_byte)
{
    size_t sizes[] = {0, 1, 23, 24, 1000, 70000};
    for (size_t k = 0; k < sizeof sizes / sizeof sizes[0]; k++) {
        ism_blob *b = filled(sizes[k], (unsigned char)k);
        size_t len = 0;
        unsigned char *v = ism_redis_value_encode(KEY_A ".drc", b, &len);
        cr_assert_not_null(v);
        cr_assert_eq(len, sizes[k] + ISM_REDIS_HEADER_SIZE);
        const char *why = "unset";
        ism_blob *back = ism_redis_value_decode(KEY_A ".drc", v, len, &why);
        cr_assert_not_null(back, "size %zu: %s", sizes[k], why ? why : "-");
        cr_assert_eq(back->len, b->len);
        cr_assert(b->len == 0 || memcmp(back->data, b->data, b->len) == 0);
        ism_blob_unref(back);
        ism_blob_unref(b);
        free(v);
    }
}

Test(redis_value, every_flipped_byte_is_refused)
{
    ism_blob *b = filled(300, 7);
    size_t len = 0;
    unsigned char *v = ism_redis_value_encode(KEY_B ".stats.json", b, &len);
    for (size_t i = 0; i < len; i++) {
        for (int bit = 0; bit < 8; bit += 3) {
            v[i] ^= (unsigned char)(1u << bit);
            const char *why = NULL;
            ism_blob *got = ism_redis_value_decode(KEY_B ".stats.json", v, len, &why);
            cr_assert_null(got, "byte %zu bit %d accepted", i, bit);
            cr_assert_not_null(why);
            v[i] ^= (unsigned char)(1u << bit);
        }
    }
    free(v);
    ism_blob_unref(b);
}

Test(redis_value, truncation_extension_and_other_names_are_refused)
{
    ism_blob *b = filled(500, 3);
    size_t len = 0;
    unsigned char *v = ism_redis_value_encode(KEY_A ".glb", b, &len);
    const char *why = NULL;
    for (size_t cut = 0; cut < len; cut += 37) {
        cr_assert_null(ism_redis_value_decode(KEY_A ".glb", v, cut, &why), "cut at %zu", cut);
        cr_assert_not_null(why);
    }
    unsigned char *longer = malloc(len + 1);
    memcpy(longer, v, len);
    longer[len] = 0;
    cr_assert_null(ism_redis_value_decode(KEY_A ".glb", longer, len + 1, &why));
    cr_assert_null(ism_redis_value_decode(KEY_A ".drc", v, len, &why));
    cr_assert_str_eq(why, "checksum mismatch");
    cr_assert_null(ism_redis_value_decode(KEY_B ".glb", v, len, &why));
    ism_blob *ok = ism_redis_value_decode(KEY_A ".glb", v, len, &why);
    cr_assert_not_null(ok);
    ism_blob_unref(ok);
    free(longer);
    free(v);
    ism_blob_unref(b);
}

Test(redis_address, forms_and_refusals)
{
    char host[256];
    unsigned short port = 0;
    cr_assert(ism_redis_parse_address("10.0.0.5:6380", host, &port));
    cr_assert_str_eq(host, "10.0.0.5");
    cr_assert_eq(port, 6380);
    cr_assert(ism_redis_parse_address("cache.lab.example", host, &port));
    cr_assert_str_eq(host, "cache.lab.example");
    cr_assert_eq(port, 6379);
    cr_assert(ism_redis_parse_address("[::1]:7000", host, &port));
    cr_assert_str_eq(host, "::1");
    cr_assert_eq(port, 7000);
    const char *bad[] = {"", ":6379", "host:", "host:0", "host:65536", "host:12x", "::1:6379",
                         "[::1]", "[::1]6379", "ho st:1", "host;rm:1", "a/b:1"};
    for (size_t i = 0; i < sizeof bad / sizeof bad[0]; i++)
        cr_assert_not(ism_redis_parse_address(bad[i], host, &port), "accepted '%s'", bad[i]);
}

typedef struct probe_task {
    ism_redis_task base;
    int runs;
    int fetch_rc, lock_rc;
    bool up;
    bool saw_stopping;
} probe_task;

static long long probe_run(ism_redis_task *task, ism_cache_tier *t, bool stopping)
{
    probe_task *p = (probe_task *)task;
    p->runs++;
    p->saw_stopping = stopping;
    p->up = ism_cache_redis_up(t);
    const char *names[] = {KEY_A ".drc"};
    ism_blob *out[1];
    p->fetch_rc = ism_cache_redis_fetch(t, names, 1, out);
    p->lock_rc = ism_cache_redis_lock(t, KEY_A ".drc", "token", 1000);
    return 0;
}

/* Port 1 on loopback: nothing listens there, connections are refused at once. */
Test(redis_tier, unreachable_redis_is_down_and_never_blocks)
{
    ism_redis_settings s = {.host = "127.0.0.1", .port = 1, .max_pending = 1 << 20,
                            .max_entry = 1 << 20};
    ism_cache_tier *t = ism_cache_redis_new(&s);
    cr_assert_not_null(t);
    cr_assert(t->remote);
    ism_redis_counters *c = ism_cache_redis_counters(t);
    struct timespec pause = {0, 10000000};
    for (int i = 0; i < 300 && atomic_load(&c->outages) == 0; i++)
        nanosleep(&pause, NULL);
    cr_assert_eq(atomic_load(&c->outages), 1);
    cr_assert_eq(atomic_load(&c->up), 0);

    ism_cache cache = {0};
    cr_assert(ism_cache_add_tier(&cache, t));
    ism_blob *b = filled(100, 1);
    ism_cache_put(&cache, KEY_A ".drc", b);
    cr_assert_eq(atomic_load(&t->counters.store_failures), 1);
    cr_assert_null(ism_cache_get(&cache, KEY_A ".drc", NULL)); /* never asked: remote */
    cr_assert_eq(atomic_load(&t->counters.misses), 0);

    probe_task p = {.base.run = probe_run};
    ism_cache_redis_schedule(t, &p.base, 0);
    for (int i = 0; i < 300 && p.runs == 0; i++)
        nanosleep(&pause, NULL);
    cr_assert_eq(p.runs, 1);
    cr_assert_not(p.up);
    cr_assert_eq(p.fetch_rc, -1);
    cr_assert_eq(p.lock_rc, -1);
    /* Several reconnects later, still one outage. */
    nanosleep(&(struct timespec){0, 400000000}, NULL);
    cr_assert_eq(atomic_load(&c->outages), 1);
    cr_assert_geq(atomic_load(&c->errors), 2);
    ism_cache_close(&cache);
    ism_blob_unref(b);
}
