/* test_cache.c — the cache tiers (server/common/cache*.h): entry-name rules, the memory LRU's
 * byte bound and recency order, promotion from disk to memory, the disk tier's persistence
 * across instances, its detection of damaged files (any flipped byte, truncation; also a file
 * about to be sent as it is, whose bytes must be the caller's) and its refusal to fail when
 * the directory cannot be written. */
#include <criterion/criterion.h>
#include <fcntl.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include "server/common/cache.h"
#include "server/common/cache_disk.h"
#include "proto/request.h"
#include "server/common/cache_mem.h"
#include "server/common/file_memo.h"

#define KEY_A "aaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaa"
#define KEY_B "0123456789abcdef0123456789abcdef0123456789abcdef0123456789abcdef"

static ism_blob *filled(size_t n, unsigned char seed)
{
    ism_blob *b = ism_blob_new(n);
    for (size_t i = 0; i < n; i++)
        b->data[i] = (unsigned char)(seed + i * 13);
    return b;
}

static char *temp_dir(void)
{
    char *d = strdup("/tmp/ism_cache_test_XXXXXX");
    cr_assert_not_null(mkdtemp(d));
    return d;
}

static void remove_tree(const char *dir)
{
    /* test-owned temporary directory; exec with argv, no shell */
    pid_t pid = fork();
    if (pid == 0) {
        execlp("rm", "rm", "-rf", dir, (char *)NULL);
        _exit(127);
    }
    int st;
    waitpid(pid, &st, 0);
}

Test(cache_names, only_keys_and_known_kinds)
{
    char name[ISM_CACHE_NAME_MAX];
    cr_assert(ism_cache_name(name, KEY_A, "drc"));
    cr_assert_str_eq(name, KEY_A ".drc");
    cr_assert(ism_cache_name_valid(KEY_B ".stats.json"));
    cr_assert(ism_cache_name_valid(KEY_B ".request.json"));
    cr_assert(ism_cache_name_valid(KEY_B ".features.json.gz")); /* gzip_body.h */
    cr_assert_not(ism_cache_name_valid(KEY_B ".stats.json.gz"));
    cr_assert_not(ism_cache_name_valid(KEY_B ".drc.gz"));
    cr_assert_not(ism_cache_name_valid(KEY_B ".exe"));
    cr_assert_not(ism_cache_name_valid(KEY_B ".drc/../x"));
    cr_assert_not(ism_cache_name_valid("../" KEY_B ".drc"));
    cr_assert_not(ism_cache_name_valid("AAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAA.drc"));
    cr_assert_not(ism_cache_name(name, "abc", "drc"));
    cr_assert(ism_key_valid(KEY_A));
    cr_assert_not(ism_key_valid(KEY_A "a"));
    cr_assert_not(ism_key_valid(""));
    /* one wrong byte anywhere (the check has no early exit: every position counts) */
    const char bad[] = {'A', 'F', 'g', '/', ':', '`', '.', ' ', '\x80', '0' - 1};
    for (int pos = 0; pos < 64; pos++)
        for (size_t b = 0; b < sizeof bad; b++) {
            char key[65];
            memcpy(key, KEY_A, 65);
            key[pos] = bad[b];
            cr_assert_not(ism_key_valid(key), "byte %d = 0x%02x", pos, (unsigned char)bad[b]);
        }
    char shorter[64];
    memcpy(shorter, KEY_A, 63);
    shorter[63] = 0;
    cr_assert_not(ism_key_valid(shorter));
    /* a name that would not fit: refused, never cut short */
    char ext[ISM_CACHE_NAME_MAX];
    memset(ext, 'a', sizeof ext - 1);
    ext[sizeof ext - 1] = 0;
    cr_assert_not(ism_cache_name(name, KEY_A, ext));
}

static void name_n(char out[ISM_CACHE_NAME_MAX], int i)
{
    char key[65];
    for (int k = 0; k < 64; k++)
        key[k] = "0123456789abcdef"[(i >> (4 * (k % 4))) & 15];
    key[64] = 0;
    cr_assert(ism_cache_name(out, key, "drc"));
}

Test(cache_mem, bounded_in_bytes_least_recent_goes_first)
{
    ism_cache_tier *m = ism_cache_mem_new(10 * 1024);
    char names[12][ISM_CACHE_NAME_MAX];
    for (int i = 0; i < 12; i++)
        name_n(names[i], i);
    /* 1000-byte entries (+ overhead): about eight fit */
    for (int i = 0; i < 8; i++) {
        ism_blob *b = filled(1000, (unsigned char)i);
        m->put(m, names[i], b);
        ism_blob_unref(b);
    }
    ism_blob *first = m->get(m, names[0]); /* now the most recent */
    cr_assert_not_null(first);
    ism_blob_unref(first);
    for (int i = 8; i < 12; i++) {
        ism_blob *b = filled(1000, (unsigned char)i);
        m->put(m, names[i], b);
        ism_blob_unref(b);
    }
    cr_assert_leq(atomic_load(&m->counters.bytes), 10 * 1024);
    cr_assert_gt(atomic_load(&m->counters.evictions), 0);
    cr_assert(m->has(m, names[0]), "the entry used recently was evicted");
    cr_assert_not(m->has(m, names[1]), "the least recent entry survived");
    for (int i = 8; i < 12; i++) {
        ism_blob *b = m->get(m, names[i]);
        cr_assert_not_null(b);
        cr_assert_eq(b->len, 1000);
        cr_assert_eq(b->data[1], (unsigned char)(i + 13));
        ism_blob_unref(b);
    }
    /* one entry over half the budget is never kept */
    ism_blob *huge = filled(6000, 1);
    m->put(m, names[1], huge);
    cr_assert_not(m->has(m, names[1]));
    ism_blob_unref(huge);
    m->close(m);
}

Test(cache_mem, blob_outlives_eviction_while_referenced)
{
    ism_cache_tier *m = ism_cache_mem_new(3000);
    char a[ISM_CACHE_NAME_MAX], b[ISM_CACHE_NAME_MAX], c[ISM_CACHE_NAME_MAX];
    name_n(a, 1);
    name_n(b, 2);
    name_n(c, 3);
    ism_blob *x = filled(900, 5);
    m->put(m, a, x);
    ism_blob_unref(x);
    ism_blob *held = m->get(m, a);
    ism_blob *y = filled(900, 6);
    m->put(m, b, y);
    m->put(m, c, y); /* three do not fit: evicts a, the least recent */
    ism_blob_unref(y);
    cr_assert_not(m->has(m, a));
    cr_assert(m->has(m, b) && m->has(m, c));
    cr_assert_eq(held->len, 900);
    cr_assert_eq(held->data[2], (unsigned char)(5 + 26));
    ism_blob_unref(held);
    m->close(m);
}

static char *file_of(const char *dir, const char *name)
{
    char *p = malloc(4096);
    snprintf(p, 4096, "%s/v1/%.2s/%s", dir, name, name);
    return p;
}

Test(cache_disk, survives_a_new_instance_and_promotes_to_memory)
{
    char *dir = temp_dir();
    ism_cache_tier *d = ism_cache_disk_new(dir, 1 << 20);
    cr_assert(ism_cache_disk_usable(d));
    ism_blob *b = filled(50000, 9);
    d->put(d, KEY_A ".glb", b);
    ism_cache_disk_flush(d);
    cr_assert_eq(atomic_load(&d->counters.stores), 1);
    d->close(d);

    ism_cache c = {0};
    ism_cache_add_tier(&c, ism_cache_mem_new(1 << 20));
    ism_cache_add_tier(&c, ism_cache_disk_new(dir, 1 << 20));
    int tier = -2;
    ism_blob *got = ism_cache_get(&c, KEY_A ".glb", &tier);
    cr_assert_not_null(got);
    cr_assert_eq(tier, 1, "expected a disk hit");
    cr_assert_eq(got->len, b->len);
    cr_assert_eq(memcmp(got->data, b->data, b->len), 0);
    ism_blob_unref(got);
    got = ism_cache_get(&c, KEY_A ".glb", &tier);
    cr_assert_eq(tier, 0, "the disk hit was not promoted to memory");
    ism_blob_unref(got);
    cr_assert_null(ism_cache_get(&c, KEY_B ".glb", &tier));
    cr_assert_eq(tier, -1);
    cr_assert_eq(atomic_load(&c.tiers[1]->counters.hits), 1);
    ism_cache_close(&c);
    ism_blob_unref(b);
    remove_tree(dir);
    free(dir);
}

Test(cache_disk, any_damage_is_dropped_and_counted)
{
    char *dir = temp_dir();
    ism_blob *b = filled(3000, 3);
    char *path = file_of(dir, KEY_B ".drc");
    /* flip one byte at several places: header, checksum, payload start, middle, end */
    long offsets[] = {0, 5, 9, 17, 21, 24, 1500, 3023};
    for (size_t i = 0; i < sizeof offsets / sizeof offsets[0]; i++) {
        ism_cache_tier *d = ism_cache_disk_new(dir, 1 << 20);
        d->put(d, KEY_B ".drc", b);
        ism_cache_disk_flush(d);
        int fd = open(path, O_RDWR);
        cr_assert_geq(fd, 0);
        unsigned char c;
        cr_assert_eq(pread(fd, &c, 1, offsets[i]), 1);
        c ^= 0x10;
        cr_assert_eq(pwrite(fd, &c, 1, offsets[i]), 1);
        close(fd);
        cr_assert_null(d->get(d, KEY_B ".drc"), "flip at %ld not detected", offsets[i]);
        cr_assert_eq(atomic_load(&d->counters.corrupt), 1);
        cr_assert_neq(access(path, F_OK), 0, "the damaged file was kept");
        d->close(d);
    }
    /* truncated file */
    ism_cache_tier *d = ism_cache_disk_new(dir, 1 << 20);
    d->put(d, KEY_B ".drc", b);
    ism_cache_disk_flush(d);
    cr_assert_eq(truncate(path, 1000), 0);
    cr_assert_null(d->get(d, KEY_B ".drc"));
    cr_assert_eq(atomic_load(&d->counters.corrupt), 1);
    /* and a fresh store works again */
    d->put(d, KEY_B ".drc", b);
    ism_cache_disk_flush(d);
    ism_blob *got = d->get(d, KEY_B ".drc");
    cr_assert_not_null(got);
    cr_assert_eq(memcmp(got->data, b->data, b->len), 0);
    ism_blob_unref(got);
    d->close(d);
    free(path);
    ism_blob_unref(b);
    remove_tree(dir);
    free(dir);
}

/* Flips the byte at offset of path in place (the file keeps its size). */
static void flip_byte(const char *path, long offset)
{
    int fd = open(path, O_RDWR);
    cr_assert_geq(fd, 0);
    unsigned char c;
    cr_assert_eq(pread(fd, &c, 1, offset), 1);
    c ^= 0x40;
    cr_assert_eq(pwrite(fd, &c, 1, offset), 1);
    close(fd);
}

/* Waits (bounded) until the file at path has settled (file_memo.h): a check of it now could be
 * remembered, so open_payload compares it. */
static void wait_settled(const char *path)
{
    struct stat st;
    for (int i = 0; i < 1000; i++) {
        cr_assert_eq(stat(path, &st), 0);
        if (ism_file_memo_settled(&st))
            return;
        usleep(10000);
    }
    cr_assert_fail("%s never settled", path);
}

Test(cache_disk, a_file_is_sent_only_while_it_holds_the_callers_bytes)
{
    char *dir = temp_dir();
    size_t n = 200 * 1000; /* several comparison reads, the last one partial */
    ism_blob *b = filled(n, 7), *other = filled(n, 8);
    char *path = file_of(dir, KEY_A ".stl");
    ism_cache_tier *d = ism_cache_disk_new(dir, 1 << 20);
    /* other bytes of the same length than the file's: not sent, the file dropped as damaged */
    d->put(d, KEY_A ".stl", other);
    ism_cache_disk_flush(d);
    wait_settled(path);
    long long off = -1;
    cr_assert_eq(ism_cache_disk_open_payload(d, KEY_A ".stl", b->data, n, &off), -1);
    cr_assert_eq(atomic_load(&d->counters.corrupt), 1);
    cr_assert_neq(access(path, F_OK), 0);
    /* the caller's bytes: sent */
    d->put(d, KEY_A ".stl", b);
    ism_cache_disk_flush(d);
    wait_settled(path);
    int fd = ism_cache_disk_open_payload(d, KEY_A ".stl", b->data, n, &off);
    cr_assert_geq(fd, 0);
    cr_assert_eq(off, 24);
    unsigned char *sent = malloc(n);
    cr_assert_eq(pread(fd, sent, n, off), (ssize_t)n);
    cr_assert_eq(memcmp(sent, b->data, n), 0);
    close(fd);
    /* a byte flipped on disk after a send (first payload byte, the middle, the last) */
    long flips[] = {24, 24 + (long)n / 2, 24 + (long)n - 1};
    for (int i = 0; i < 3; i++) {
        d->put(d, KEY_A ".stl", b);
        ism_cache_disk_flush(d);
        wait_settled(path);
        fd = ism_cache_disk_open_payload(d, KEY_A ".stl", b->data, n, &off);
        cr_assert_geq(fd, 0);
        close(fd);
        flip_byte(path, flips[i]);
        /* changed moments ago: neither sent nor read (so not found damaged yet) */
        struct stat st;
        cr_assert_eq(stat(path, &st), 0);
        if (!ism_file_memo_settled(&st)) {
            cr_assert_eq(ism_cache_disk_open_payload(d, KEY_A ".stl", b->data, n, &off), -1,
                         "flip at %ld was sent at once", flips[i]);
            cr_assert_eq(atomic_load(&d->counters.corrupt), 1 + (unsigned long long)i);
            cr_assert_eq(access(path, F_OK), 0);
        }
        wait_settled(path);
        cr_assert_eq(ism_cache_disk_open_payload(d, KEY_A ".stl", b->data, n, &off), -1,
                     "flip at %ld was sent", flips[i]);
        cr_assert_eq(atomic_load(&d->counters.corrupt), 2 + (unsigned long long)i);
        cr_assert_neq(access(path, F_OK), 0, "the damaged file was kept");
    }
    d->close(d);
    free(sent);
    free(path);
    ism_blob_unref(b);
    ism_blob_unref(other);
    remove_tree(dir);
    free(dir);
}

/* After a send the file stays open for the next (fd_keep.h); a file removed from the directory
 * or replaced by another is not sent from that descriptor. */
Test(cache_disk, a_file_kept_open_is_not_sent_once_removed_or_replaced)
{
    char *dir = temp_dir(), *dir2 = temp_dir();
    size_t n = 100 * 1000;
    ism_blob *b = filled(n, 9), *other = filled(n, 10);
    char *path = file_of(dir, KEY_A ".drc"), *path2 = file_of(dir2, KEY_A ".drc");
    ism_cache_tier *d = ism_cache_disk_new(dir, 1 << 20), *d2 = ism_cache_disk_new(dir2, 1 << 20);
    d->put(d, KEY_A ".drc", b);
    ism_cache_disk_flush(d);
    wait_settled(path);
    long long off = -1;
    int fd = ism_cache_disk_open_payload(d, KEY_A ".drc", b->data, n, &off);
    cr_assert_geq(fd, 0);
    close(fd);
    cr_assert_eq(unlink(path), 0);
    cr_assert_eq(ism_cache_disk_open_payload(d, KEY_A ".drc", b->data, n, &off), -1,
                 "a removed file was sent");
    /* stored again: a new file, sent from itself, then from the descriptor kept of it */
    d->put(d, KEY_A ".drc", b);
    ism_cache_disk_flush(d);
    wait_settled(path);
    struct stat now, sent;
    cr_assert_eq(stat(path, &now), 0);
    unsigned char *got = malloc(n);
    for (int i = 0; i < 2; i++) {
        fd = ism_cache_disk_open_payload(d, KEY_A ".drc", b->data, n, &off);
        cr_assert_geq(fd, 0);
        cr_assert_eq(fstat(fd, &sent), 0);
        cr_assert_eq(sent.st_ino, now.st_ino, "sent from a file no longer in the directory");
        cr_assert_eq(pread(fd, got, n, off), (ssize_t)n);
        cr_assert_eq(memcmp(got, b->data, n), 0);
        close(fd);
    }
    /* a sound file of other bytes renamed over it: neither it nor the kept one is sent */
    d2->put(d2, KEY_A ".drc", other);
    ism_cache_disk_flush(d2);
    cr_assert_eq(rename(path2, path), 0);
    wait_settled(path);
    cr_assert_eq(ism_cache_disk_open_payload(d, KEY_A ".drc", b->data, n, &off), -1,
                 "the replaced file was sent, or its replacement holding other bytes");
    d->close(d);
    d2->close(d2);
    free(got);
    free(path);
    free(path2);
    ism_blob_unref(b);
    ism_blob_unref(other);
    remove_tree(dir);
    remove_tree(dir2);
    free(dir);
    free(dir2);
}

Test(cache_disk, unwritable_directory_stores_nothing_and_says_so)
{
    /* a path under a regular file can never be created, even by root */
    char *dir = temp_dir();
    char blocker[4200];
    snprintf(blocker, sizeof blocker, "%s/file", dir);
    int fd = open(blocker, O_WRONLY | O_CREAT, 0644);
    cr_assert_geq(fd, 0);
    close(fd);
    char sub[4300];
    snprintf(sub, sizeof sub, "%s/cache", blocker);
    ism_cache_tier *d = ism_cache_disk_new(sub, 1 << 20);
    cr_assert_not_null(d);
    cr_assert_not(ism_cache_disk_usable(d));
    ism_blob *b = filled(100, 1);
    d->put(d, KEY_A ".drc", b);
    ism_cache_disk_flush(d);
    cr_assert_eq(atomic_load(&d->counters.store_failures), 1);
    cr_assert_null(d->get(d, KEY_A ".drc"));
    ism_blob_unref(b);
    d->close(d);
    remove_tree(dir);
    free(dir);
}

Test(cache_disk, write_queue_over_budget_skips_and_counts)
{
    char *dir = temp_dir();
    ism_cache_tier *d = ism_cache_disk_new(dir, 1000);
    /* a queue below its budget takes an entry larger than it: a big mesh still reaches disk */
    ism_blob *big = filled(5000, 2);
    d->put(d, KEY_A ".ply", big);
    ism_cache_disk_flush(d);
    cr_assert_eq(atomic_load(&d->counters.store_failures), 0);
    cr_assert(d->has(d, KEY_A ".ply"));
    /* behind it, puts are skipped while the queue holds the budget: 200 puts of 5 KB take
     * microseconds each, a write a file each, so the writer cannot empty the queue between all
     * of them */
    char name[ISM_CACHE_NAME_MAX];
    for (int i = 0; i < 200; i++) {
        snprintf(name, sizeof name, "%064x.ply", i + 1);
        d->put(d, name, big);
    }
    ism_cache_disk_flush(d);
    unsigned long long failed = atomic_load(&d->counters.store_failures);
    cr_assert(failed >= 1 && failed < 200, "%llu of 200 puts skipped", failed);
    int kept = 0;
    for (int i = 0; i < 200; i++) {
        snprintf(name, sizeof name, "%064x.ply", i + 1);
        kept += d->has(d, name);
    }
    cr_assert_eq(kept, 200 - (int)failed);
    ism_blob_unref(big);
    d->close(d);
    remove_tree(dir);
    free(dir);
}
