/* cache_disk.c — the disk tier (cache_disk.h): checked reads on the caller's thread, atomic
 * checksummed writes on one background writer thread fed by a byte-bounded queue, and a pruner
 * thread that keeps the directory under its size bound (least recently used first). */
#include "server/common/cache_disk.h"
#include "core/util/le_bytes.h"
#include "server/common/fd_io.h"
#include "server/common/fd_keep.h"
#include "server/common/file_memo.h"

#include <dirent.h>
#include <errno.h>
#include <fcntl.h>
#include <pthread.h>
#include <signal.h>
#include <stdatomic.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <time.h>
#include <unistd.h>

#include "proto/frame.h"
#include "server/common/log.h"

#define HEADER_SIZE 24
#define FILE_VERSION 1
#define MAX_ENTRY ((uint64_t)2 << 30) /* 2 GiB: larger files are not ours */
#define FAILURE_LOG_INTERVAL_S 10
#define PRUNE_LOW_WATER(max) ((max) / 10 * 9) /* a prune frees down to 90% of the bound */
#define PRUNE_RETRY_S 1                       /* still over after a pass: wait this long */
#define COMPARE_CHUNK ((size_t)64 << 10)      /* a payload is compared in reads this large */

typedef struct pending {
    struct pending *next;
    ism_blob *blob;
    char name[ISM_CACHE_NAME_MAX];
} pending;

typedef struct disk_tier {
    ism_cache_tier base;
    int root_fd;            /* <dir>/v1, or -1 when unusable */
    char root_path[4096];
    bool usable;
    pthread_t writer;
    bool writer_started;
    pthread_mutex_t lock;
    pthread_cond_t wake, idle;
    pending *head, *tail;
    size_t pending_bytes, max_pending;
    pending *writing;       /* the entry being written now (popped from the queue) */
    bool stopping;
    time_t last_failure_log;
    unsigned long long tmp_seq;
    /* size bound: counters.bytes and counters.entries hold what the directory holds (a scan
     * at start, then every store and removal); the pruner wakes when bytes pass max_bytes */
    unsigned long long max_bytes; /* 0 = no bound */
    pthread_t pruner;
    bool pruner_started;
    pthread_cond_t prune_wake;
    /* Held while files appear in or leave the directory together with the counters' update
     * (writer: rename + count; reader: drop + uncount; pruner: scan + unlink + correction), so
     * the pruner's correction never counts a file twice or drops one it never saw. */
    pthread_mutex_t dir_lock;
    ism_file_memo *sent_ok; /* files whose payload was found equal to the bytes to send */
    ism_fd_keep *kept;      /* those files kept open for the next send (open_payload) */
    atomic_bool comparing;  /* a payload comparison runs (open_payload): one at a time */
} disk_tier;

/* ---- helpers ------------------------------------------------------------------------- */

static bool rel_path(char out[ISM_CACHE_NAME_MAX + 4], const char *name)
{
    if (!ism_cache_name_valid(name))
        return false;
    snprintf(out, ISM_CACHE_NAME_MAX + 4, "%.2s/%s", name, name);
    return true;
}

static bool mkdir_p(const char *path)
{
    char buf[4096];
    if (snprintf(buf, sizeof buf, "%s", path) >= (int)sizeof buf)
        return false;
    for (char *p = buf + 1; *p; p++) {
        if (*p == '/') {
            *p = 0;
            if (mkdir(buf, 0755) != 0 && errno != EEXIST)
                return false;
            *p = '/';
        }
    }
    return mkdir(buf, 0755) == 0 || errno == EEXIST;
}

static bool pread_all(int fd, void *buf, size_t n, off_t off)
{
    unsigned char *p = buf;
    while (n) {
        ssize_t got = pread(fd, p, n, off);
        if (got < 0 && errno == EINTR)
            continue;
        if (got <= 0)
            return false;
        p += got;
        n -= (size_t)got;
        off += got;
    }
    return true;
}

static void log_store_failure(disk_tier *d, const char *name, const char *what, int err)
{
    atomic_fetch_add(&d->base.counters.store_failures, 1);
    time_t now = time(NULL);
    pthread_mutex_lock(&d->lock);
    bool quiet = d->last_failure_log && now - d->last_failure_log < FAILURE_LOG_INTERVAL_S;
    if (!quiet)
        d->last_failure_log = now;
    pthread_mutex_unlock(&d->lock);
    if (quiet)
        return;
    ism_log_field f[] = {ISM_LS("name", name), ISM_LS("what", what),
                         ISM_LS("error", err ? strerror(err) : "-"),
                         ISM_LS("dir", d->root_path)};
    ism_log_fields(ISM_LOG_WARN, "cache_store_failed", f, sizeof f / sizeof f[0]);
}

/* ---- reads --------------------------------------------------------------------------- */

static void forget(disk_tier *d, unsigned long long bytes)
{
    atomic_fetch_sub(&d->base.counters.bytes, bytes);
    atomic_fetch_sub(&d->base.counters.entries, 1);
}

/* counted: the file's size when it is a regular file the tier counts, else -1 */
static void drop_corrupt(disk_tier *d, const char *rel, const char *name, const char *why,
                         long long counted)
{
    ism_fd_keep_drop(d->kept, name);
    pthread_mutex_lock(&d->dir_lock);
    if (unlinkat(d->root_fd, rel, 0) == 0 && counted >= 0)
        forget(d, (unsigned long long)counted);
    pthread_mutex_unlock(&d->dir_lock);
    atomic_fetch_add(&d->base.counters.corrupt, 1);
    ism_log_field f[] = {ISM_LS("name", name), ISM_LS("why", why), ISM_LS("dir", d->root_path)};
    ism_log_fields(ISM_LOG_WARN, "cache_corrupt_entry_dropped", f, sizeof f / sizeof f[0]);
}

/* An entry queued for writing (or being written) answers reads before it reaches the disk,
 * so a tier without memory above it never misses what it was just given. */
static ism_blob *pending_get(disk_tier *d, const char *name)
{
    ism_blob *b = NULL;
    pthread_mutex_lock(&d->lock);
    if (d->writing && !strcmp(d->writing->name, name))
        b = ism_blob_ref(d->writing->blob);
    for (pending *p = d->head; p && !b; p = p->next)
        if (!strcmp(p->name, name))
            b = ism_blob_ref(p->blob);
    pthread_mutex_unlock(&d->lock);
    return b;
}

static ism_blob *disk_get(ism_cache_tier *t, const char *name)
{
    disk_tier *d = (disk_tier *)t;
    char rel[ISM_CACHE_NAME_MAX + 4];
    if (d->root_fd < 0 || !rel_path(rel, name))
        return NULL;
    ism_blob *queued = pending_get(d, name);
    if (queued)
        return queued;
    int fd = openat(d->root_fd, rel, O_RDONLY | O_CLOEXEC | O_NOFOLLOW);
    if (fd < 0)
        return NULL;
    ism_blob *b = NULL;
    const char *why = NULL;
    struct stat st;
    unsigned char hdr[HEADER_SIZE];
    long long counted = -1;
    if (fstat(fd, &st) != 0 || !S_ISREG(st.st_mode)) {
        why = "not a regular file";
    } else if ((counted = (long long)st.st_size) < 0) {
        why = "bad size";
    } else if ((uint64_t)st.st_size < HEADER_SIZE || (uint64_t)st.st_size > MAX_ENTRY + HEADER_SIZE) {
        why = "bad size";
    } else if (!pread_all(fd, hdr, HEADER_SIZE, 0)) {
        why = "short read";
    } else if (memcmp(hdr, "ISMC", 4) != 0 || ism_get_le32(hdr + 4) != FILE_VERSION || ism_get_le32(hdr + 20) != 0) {
        why = "bad header";
    } else {
        uint64_t len = (uint64_t)ism_get_le32(hdr + 8) | (uint64_t)ism_get_le32(hdr + 12) << 32;
        if (len != (uint64_t)st.st_size - HEADER_SIZE) {
            why = "length does not match the file size";
        } else if (!(b = ism_blob_new((size_t)len))) {
            why = NULL; /* out of memory: a miss, not corruption */
        } else if (!pread_all(fd, b->data, (size_t)len, HEADER_SIZE)) {
            why = "short read";
        } else if (ism_crc32c(ism_crc32c(0, hdr, 16), b->data, (size_t)len) != ism_get_le32(hdr + 16)) {
            why = "checksum mismatch";
        }
    }
    if (!why && b)
        futimens(fd, NULL); /* used now: the pruner removes the least recently used first */
    close(fd);
    if (why) {
        ism_blob_unref(b);
        drop_corrupt(d, rel, name, why, counted);
        return NULL;
    }
    return b;
}

/* Whether the payload of fd (from HEADER_SIZE) is exactly payload[0..len). -1 on a read
 * error or out of memory (nothing is known then). */
static int payload_equals(int fd, const unsigned char *payload, size_t len)
{
    unsigned char *buf = malloc(len < COMPARE_CHUNK ? len + 1 : COMPARE_CHUNK);
    if (!buf)
        return -1;
    int same = 1;
    for (size_t at = 0; at < len && same == 1; at += COMPARE_CHUNK) {
        size_t n = len - at < COMPARE_CHUNK ? len - at : COMPARE_CHUNK;
        if (!pread_all(fd, buf, n, (off_t)(HEADER_SIZE + at)))
            same = -1;
        else if (memcmp(buf, payload + at, n) != 0)
            same = 0;
    }
    free(buf);
    return same;
}

/* The file kept open for name (fd_keep.h) when it still holds the payload found equal to the
 * caller's: still in the directory, of the payload's size, unchanged since the comparison
 * (file_memo.h); lent when lease is not NULL (*lease set), else duplicated. Else -1, and the
 * kept file is let go. */
static int kept_payload(disk_tier *d, const char *name, size_t len, ism_fd_lease **lease)
{
    ism_fd_lease *l;
    int fd = ism_fd_keep_borrow(d->kept, name, &l);
    if (fd < 0)
        return -1;
    struct stat st;
    if (fstat(fd, &st) == 0 && st.st_nlink > 0 && (uint64_t)st.st_size == (uint64_t)len + HEADER_SIZE &&
        ism_file_memo_holds(d->sent_ok, name, &st)) {
        if (!lease) {
            int dup = fcntl(fd, F_DUPFD_CLOEXEC, 0);
            ism_fd_keep_give_back(l);
            return dup;
        }
        *lease = l;
        return fd;
    }
    ism_fd_keep_give_back(l);
    ism_fd_keep_drop(d->kept, name);
    return -1;
}

int ism_cache_disk_open_payload(ism_cache_tier *t, const char *name, const void *payload,
                                size_t len, long long *offset)
{
    return ism_cache_disk_borrow_payload(t, name, payload, len, offset, NULL);
}

int ism_cache_disk_borrow_payload(ism_cache_tier *t, const char *name, const void *payload,
                                  size_t len, long long *offset, ism_fd_lease **lease)
{
    disk_tier *d = (disk_tier *)t;
    char rel[ISM_CACHE_NAME_MAX + 4];
    if (lease)
        *lease = NULL;
    if (d->root_fd < 0 || !rel_path(rel, name))
        return -1;
    *offset = HEADER_SIZE;
    int fd = kept_payload(d, name, len, lease);
    if (fd >= 0)
        return fd;
    fd = openat(d->root_fd, rel, O_RDONLY | O_CLOEXEC | O_NOFOLLOW);
    if (fd < 0)
        return -1;
    struct stat st;
    unsigned char hdr[HEADER_SIZE];
    bool sound = fstat(fd, &st) == 0 && S_ISREG(st.st_mode) &&
                 (uint64_t)st.st_size == (uint64_t)len + HEADER_SIZE &&
                 pread_all(fd, hdr, HEADER_SIZE, 0) && memcmp(hdr, "ISMC", 4) == 0 &&
                 ism_get_le32(hdr + 4) == FILE_VERSION && ism_get_le32(hdr + 20) == 0 &&
                 ((uint64_t)ism_get_le32(hdr + 8) | (uint64_t)ism_get_le32(hdr + 12) << 32) ==
                     (uint64_t)len;
    if (sound && !ism_file_memo_holds(d->sent_ok, name, &st)) {
        /* The caller's bytes go instead of the file (which waits) while a check would hold
         * up the caller's (a polling) thread for nothing: when the file changed moments ago
         * (the check could not be remembered, so every send would read it whole), and while
         * another thread compares (clients that arrive together ask for the same file: a
         * second compare would stall a second polling thread, and so on up to all). */
        if (!ism_file_memo_settled(&st) || atomic_exchange(&d->comparing, true)) {
            close(fd);
            return -1;
        }
        int same = payload_equals(fd, payload, len);
        if (same == 0)
            drop_corrupt(d, rel, name, "payload differs from the bytes it was stored with",
                         (long long)st.st_size);
        else if (same == 1)
            ism_file_memo_put(d->sent_ok, name, &st);
        atomic_store(&d->comparing, false);
        sound = same == 1;
    }
    if (!sound) {
        close(fd);
        return -1;
    }
    if (ism_file_memo_holds(d->sent_ok, name, &st))
        ism_fd_keep_put(d->kept, name, fd); /* the next send skips the open and the header */
    return fd;
}

static bool disk_has(ism_cache_tier *t, const char *name)
{
    disk_tier *d = (disk_tier *)t;
    char rel[ISM_CACHE_NAME_MAX + 4];
    struct stat st;
    if (d->root_fd < 0 || !rel_path(rel, name))
        return false;
    ism_blob *queued = pending_get(d, name);
    if (queued) {
        ism_blob_unref(queued);
        return true;
    }
    return fstatat(d->root_fd, rel, &st, AT_SYMLINK_NOFOLLOW) == 0 && S_ISREG(st.st_mode);
}

/* ---- writes -------------------------------------------------------------------------- */

static void disk_put(ism_cache_tier *t, const char *name, ism_blob *b)
{
    disk_tier *d = (disk_tier *)t;
    if (!d->usable) {
        log_store_failure(d, name, "cache directory unusable", 0);
        return;
    }
    pending *p = calloc(1, sizeof *p);
    if (!p) {
        log_store_failure(d, name, "out of memory", ENOMEM);
        return;
    }
    snprintf(p->name, sizeof p->name, "%s", name);
    pthread_mutex_lock(&d->lock);
    /* skipped only while the queue holds max_pending: an entry of any size joins a queue
     * below it, so a mesh larger than the bound still reaches the disk */
    if (d->stopping || d->pending_bytes >= d->max_pending) {
        pthread_mutex_unlock(&d->lock);
        free(p);
        log_store_failure(d, name, "write queue full", 0);
        return;
    }
    p->blob = ism_blob_ref(b);
    d->pending_bytes += b->len;
    if (d->tail)
        d->tail->next = p;
    else
        d->head = p;
    d->tail = p;
    pthread_cond_signal(&d->wake);
    pthread_mutex_unlock(&d->lock);
}

/* Writes one entry: a temporary file, renamed into its shard directory. No fsync: the rename
 * keeps readers from ever seeing a partial file (a killed daemon leaves only a temporary one),
 * and what a power loss may tear fails its checksum and is dropped on read. Two fsyncs per file
 * held the writer to a few hundred files a second under load (bench_load.py: its queue grew by
 * thousands of entries a minute). */
static void store_entry(disk_tier *d, const char *name, const ism_blob *b)
{
    char rel[ISM_CACHE_NAME_MAX + 4];
    if (!rel_path(rel, name))
        return;
    struct stat st;
    if (fstatat(d->root_fd, rel, &st, AT_SYMLINK_NOFOLLOW) == 0)
        return; /* content-addressed: already there */
    unsigned char hdr[HEADER_SIZE] = {0};
    memcpy(hdr, "ISMC", 4);
    ism_put_le32(hdr + 4, FILE_VERSION);
    ism_put_le32(hdr + 8, (uint32_t)b->len);
    ism_put_le32(hdr + 12, (uint32_t)((uint64_t)b->len >> 32));
    ism_put_le32(hdr + 16, ism_crc32c(ism_crc32c(0, hdr, 16), b->data, b->len));

    char tmp[ISM_CACHE_NAME_MAX + 64];
    snprintf(tmp, sizeof tmp, "tmp/%s.%ld.%llu.tmp", name, (long)getpid(), ++d->tmp_seq);
    int fd = openat(d->root_fd, tmp, O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC | O_NOFOLLOW, 0644);
    if (fd < 0) {
        log_store_failure(d, name, "create", errno);
        return;
    }
    const char *what = NULL;
    int err = 0;
    if (!ism_write_all(fd, hdr, HEADER_SIZE) || !ism_write_all(fd, b->data, b->len))
        what = "write", err = errno;
    if (close(fd) != 0 && !what)
        what = "close", err = errno;
    char shard[3] = {name[0], name[1], 0};
    if (!what && mkdirat(d->root_fd, shard, 0755) != 0 && errno != EEXIST)
        what = "mkdir", err = errno;
    pthread_mutex_lock(&d->dir_lock);
    if (!what && renameat(d->root_fd, tmp, d->root_fd, rel) != 0)
        what = "rename", err = errno;
    if (!what) {
        atomic_fetch_add(&d->base.counters.bytes, (unsigned long long)HEADER_SIZE + b->len);
        atomic_fetch_add(&d->base.counters.entries, 1);
    }
    pthread_mutex_unlock(&d->dir_lock);
    if (what) {
        unlinkat(d->root_fd, tmp, 0);
        log_store_failure(d, name, what, err);
        return;
    }
    atomic_fetch_add(&d->base.counters.stores, 1);
    pthread_mutex_lock(&d->lock);
    if (d->max_bytes && atomic_load(&d->base.counters.bytes) > d->max_bytes)
        pthread_cond_signal(&d->prune_wake);
    pthread_mutex_unlock(&d->lock);
}

static void *writer_main(void *arg)
{
    disk_tier *d = arg;
    pthread_mutex_lock(&d->lock);
    for (;;) {
        while (!d->head && !d->stopping)
            pthread_cond_wait(&d->wake, &d->lock);
        if (!d->head)
            break; /* stopping and drained */
        pending *p = d->head;
        d->head = p->next;
        if (!d->head)
            d->tail = NULL;
        d->writing = p;
        pthread_mutex_unlock(&d->lock);
        store_entry(d, p->name, p->blob);
        pthread_mutex_lock(&d->lock);
        d->writing = NULL;
        d->pending_bytes -= p->blob->len;
        ism_blob_unref(p->blob);
        free(p);
        if (!d->head)
            pthread_cond_broadcast(&d->idle);
    }
    pthread_cond_broadcast(&d->idle);
    pthread_mutex_unlock(&d->lock);
    return NULL;
}

/* ---- the size bound ------------------------------------------------------------------ */

typedef struct entry_info {
    long long used_ns; /* mtime: the last store or read */
    unsigned long long size;
    char name[ISM_CACHE_NAME_MAX];
} entry_info;

typedef struct entry_list {
    entry_info *v;
    size_t n, cap;
    bool failed;
} entry_list;

static void list_add(entry_list *l, const char *name, const struct stat *st)
{
    if (l->failed)
        return;
    if (l->n == l->cap) {
        size_t cap = l->cap ? l->cap * 2 : 1024;
        entry_info *v = realloc(l->v, cap * sizeof *v);
        if (!v) {
            l->failed = true;
            return;
        }
        l->v = v;
        l->cap = cap;
    }
    entry_info *e = &l->v[l->n++];
    e->used_ns = (long long)st->st_mtim.tv_sec * 1000000000LL + st->st_mtim.tv_nsec;
    e->size = (unsigned long long)st->st_size;
    size_t n = strnlen(name, sizeof e->name - 1); /* valid names are shorter */
    memcpy(e->name, name, n);
    e->name[n] = 0;
}

static bool is_shard(const char *n)
{
    return strlen(n) == 2 && strspn(n, "0123456789abcdef") == 2;
}

/* Every entry file under the root (regular files with valid names in shard directories):
 * their total size and count, and, when list is not NULL, each of them. */
static void scan(disk_tier *d, entry_list *list, unsigned long long *bytes,
                 unsigned long long *entries)
{
    *bytes = *entries = 0;
    int rfd = openat(d->root_fd, ".", O_RDONLY | O_DIRECTORY | O_CLOEXEC);
    DIR *root = rfd >= 0 ? fdopendir(rfd) : NULL;
    if (!root) {
        if (rfd >= 0)
            close(rfd);
        return;
    }
    struct dirent *de;
    while ((de = readdir(root))) {
        if (!is_shard(de->d_name))
            continue;
        int sfd = openat(d->root_fd, de->d_name, O_RDONLY | O_DIRECTORY | O_NOFOLLOW | O_CLOEXEC);
        DIR *shard = sfd >= 0 ? fdopendir(sfd) : NULL;
        if (!shard) {
            if (sfd >= 0)
                close(sfd);
            continue;
        }
        struct dirent *fe;
        while ((fe = readdir(shard))) {
            struct stat st;
            if (!ism_cache_name_valid(fe->d_name) || strncmp(fe->d_name, de->d_name, 2) != 0 ||
                fstatat(dirfd(shard), fe->d_name, &st, AT_SYMLINK_NOFOLLOW) != 0 ||
                !S_ISREG(st.st_mode))
                continue;
            *bytes += (unsigned long long)st.st_size;
            *entries += 1;
            if (list)
                list_add(list, fe->d_name, &st);
        }
        closedir(shard);
    }
    closedir(root);
}

/* The writer's pid in a temporary file's name ("<name>.<pid>.<seq>.tmp", "probe.<pid>"); 0 when
 * the name is not one of ours. */
static long tmp_owner(const char *p)
{
    char buf[256];
    size_t n = strlen(p);
    if (!strncmp(p, "probe.", 6)) {
        snprintf(buf, sizeof buf, "%s", p + 6);
    } else {
        if (n < 4 || n >= sizeof buf || strcmp(p + n - 4, ".tmp") != 0)
            return 0;
        memcpy(buf, p, n - 4);
        buf[n - 4] = 0;
        char *seq = strrchr(buf, '.');
        if (!seq)
            return 0;
        *seq = 0;
        char *pid = strrchr(buf, '.');
        if (!pid)
            return 0;
        memmove(buf, pid + 1, strlen(pid + 1) + 1);
    }
    char *end;
    long v = strtol(buf, &end, 10);
    return *end == 0 && v > 0 ? v : 0;
}

/* Temporary files of writers that are gone (a daemon killed mid-write) will never be renamed
 * into place: remove them. Those of live processes (another daemon on the same directory)
 * stay. */
static void clean_tmp(disk_tier *d)
{
    int tfd = openat(d->root_fd, "tmp", O_RDONLY | O_DIRECTORY | O_NOFOLLOW | O_CLOEXEC);
    DIR *tmp = tfd >= 0 ? fdopendir(tfd) : NULL;
    if (!tmp) {
        if (tfd >= 0)
            close(tfd);
        return;
    }
    long long removed = 0;
    struct dirent *de;
    while ((de = readdir(tmp))) {
        long pid = tmp_owner(de->d_name);
        if (pid <= 0 || pid == (long)getpid() || kill((pid_t)pid, 0) == 0 || errno != ESRCH)
            continue; /* not ours, or its writer may still be at work */
        if (unlinkat(dirfd(tmp), de->d_name, 0) == 0)
            removed++;
    }
    closedir(tmp);
    if (removed) {
        ism_log_field f[] = {ISM_LI("files", removed), ISM_LS("dir", d->root_path)};
        ism_log_fields(ISM_LOG_INFO, "cache_tmp_cleaned", f, 2);
    }
}

static int by_key(const void *a, const void *b)
{
    return strncmp(((const entry_info *)a)->name, ((const entry_info *)b)->name, 64);
}

static int by_use(const void *a, const void *b)
{
    const entry_info *x = a, *y = b;
    if (x->used_ns != y->used_ns)
        return x->used_ns < y->used_ns ? -1 : 1;
    return by_key(a, b);
}

/* The files of one key (its mesh formats, stats, features, request) go together: each gets the
 * key's latest use, so a mesh read every minute keeps the request its other formats need. */
static void group_by_key(entry_list *l)
{
    qsort(l->v, l->n, sizeof *l->v, by_key);
    for (size_t i = 0; i < l->n;) {
        size_t j = i;
        long long used = 0;
        while (j < l->n && by_key(&l->v[i], &l->v[j]) == 0)
            used = l->v[j].used_ns > used ? l->v[j].used_ns : used, j++;
        for (size_t k = i; k < j; k++)
            l->v[k].used_ns = used;
        i = j;
    }
    qsort(l->v, l->n, sizeof *l->v, by_use);
}

/* One pass: the least recently used keys go until the directory is at the low-water mark. */
static void prune(disk_tier *d, unsigned long long max)
{
    entry_list l = {0};
    unsigned long long bytes, entries;
    pthread_mutex_lock(&d->dir_lock);
    unsigned long long counted_bytes = atomic_load(&d->base.counters.bytes);
    unsigned long long counted_entries = atomic_load(&d->base.counters.entries);
    scan(d, &l, &bytes, &entries);
    unsigned long long low = PRUNE_LOW_WATER(max), freed = 0, removed = 0;
    if (!l.failed && bytes > max) {
        group_by_key(&l);
        for (size_t i = 0; i < l.n; i++) {
            bool same_key = i > 0 && by_key(&l.v[i], &l.v[i - 1]) == 0;
            if (bytes - freed <= low && !same_key)
                break;
            char rel[ISM_CACHE_NAME_MAX + 4];
            snprintf(rel, sizeof rel, "%.2s/%s", l.v[i].name, l.v[i].name);
            if (unlinkat(d->root_fd, rel, 0) == 0) {
                ism_fd_keep_drop(d->kept, l.v[i].name); /* its space is freed now */
                freed += l.v[i].size;
                removed++;
            }
        }
    }
    free(l.v);
    /* the scan corrects what the counters believed (files removed by hand, say); no store or
     * drop happens meanwhile (dir_lock), so the correction is exact */
    atomic_fetch_add(&d->base.counters.bytes, bytes - counted_bytes - freed);
    atomic_fetch_add(&d->base.counters.entries, entries - counted_entries - removed);
    pthread_mutex_unlock(&d->dir_lock);
    atomic_fetch_add(&d->base.counters.evictions, removed);
    if (removed) {
        ism_log_field f[] = {ISM_LI("removed", (long long)removed), ISM_LI("freed", (long long)freed),
                             ISM_LI("bytes", (long long)(bytes - freed)),
                             ISM_LI("limit", (long long)max), ISM_LS("dir", d->root_path)};
        ism_log_fields(ISM_LOG_INFO, "cache_pruned", f, sizeof f / sizeof f[0]);
    }
}

static bool over_limit(disk_tier *d)
{
    return d->max_bytes && atomic_load(&d->base.counters.bytes) > d->max_bytes;
}

static void *pruner_main(void *arg)
{
    disk_tier *d = arg;
    clean_tmp(d);
    unsigned long long bytes, entries;
    pthread_mutex_lock(&d->dir_lock);
    scan(d, NULL, &bytes, &entries);
    atomic_store(&d->base.counters.bytes, bytes);
    atomic_store(&d->base.counters.entries, entries);
    pthread_mutex_unlock(&d->dir_lock);
    pthread_mutex_lock(&d->lock);
    while (!d->stopping) {
        if (!over_limit(d)) {
            pthread_cond_wait(&d->prune_wake, &d->lock);
            continue;
        }
        unsigned long long max = d->max_bytes;
        pthread_mutex_unlock(&d->lock);
        prune(d, max);
        pthread_mutex_lock(&d->lock);
        if (!d->stopping && over_limit(d)) { /* stores kept coming, or unlink failed */
            struct timespec until;
            clock_gettime(CLOCK_REALTIME, &until);
            until.tv_sec += PRUNE_RETRY_S;
            pthread_cond_timedwait(&d->prune_wake, &d->lock, &until);
        }
    }
    pthread_mutex_unlock(&d->lock);
    return NULL;
}

void ism_cache_disk_set_max(ism_cache_tier *t, unsigned long long max_bytes)
{
    disk_tier *d = (disk_tier *)t;
    pthread_mutex_lock(&d->lock);
    d->max_bytes = max_bytes;
    pthread_cond_signal(&d->prune_wake);
    pthread_mutex_unlock(&d->lock);
}

void ism_cache_disk_flush(ism_cache_tier *t)
{
    disk_tier *d = (disk_tier *)t;
    pthread_mutex_lock(&d->lock);
    while (d->writer_started && (d->head || d->writing))
        pthread_cond_wait(&d->idle, &d->lock);
    pthread_mutex_unlock(&d->lock);
}

bool ism_cache_disk_usable(const ism_cache_tier *t)
{
    return ((const disk_tier *)t)->usable;
}

static void disk_close(ism_cache_tier *t)
{
    disk_tier *d = (disk_tier *)t;
    pthread_mutex_lock(&d->lock);
    d->stopping = true;
    pthread_cond_broadcast(&d->wake);
    pthread_cond_broadcast(&d->prune_wake);
    pthread_mutex_unlock(&d->lock);
    if (d->writer_started)
        pthread_join(d->writer, NULL);
    if (d->pruner_started)
        pthread_join(d->pruner, NULL);
    while (d->head) { /* only when the writer never started */
        pending *p = d->head;
        d->head = p->next;
        ism_blob_unref(p->blob);
        free(p);
    }
    if (d->root_fd >= 0)
        close(d->root_fd);
    pthread_mutex_destroy(&d->lock);
    pthread_mutex_destroy(&d->dir_lock);
    pthread_cond_destroy(&d->wake);
    pthread_cond_destroy(&d->idle);
    pthread_cond_destroy(&d->prune_wake);
    ism_file_memo_free(d->sent_ok);
    ism_fd_keep_free(d->kept);
    free(d);
}

/* Opens <dir>/v1 and proves it writable with a probe file. */
static bool open_root(disk_tier *d, const char *dir)
{
    char tmpdir[4096 + 8];
    if (snprintf(d->root_path, sizeof d->root_path, "%s/v1", dir) >= (int)sizeof d->root_path)
        return false;
    snprintf(tmpdir, sizeof tmpdir, "%s/tmp", d->root_path);
    if (!mkdir_p(tmpdir))
        return false;
    d->root_fd = open(d->root_path, O_RDONLY | O_DIRECTORY | O_CLOEXEC);
    if (d->root_fd < 0)
        return false;
    char probe[64];
    snprintf(probe, sizeof probe, "tmp/probe.%ld", (long)getpid());
    int fd = openat(d->root_fd, probe, O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
    if (fd < 0)
        return false;
    close(fd);
    unlinkat(d->root_fd, probe, 0);
    return true;
}

ism_cache_tier *ism_cache_disk_new(const char *dir, size_t max_pending)
{
    disk_tier *d = calloc(1, sizeof *d);
    if (!d)
        return NULL;
    d->root_fd = -1;
    d->max_pending = max_pending;
    d->sent_ok = ism_file_memo_new(); /* NULL: every send compares */
    d->kept = ism_fd_keep_new();      /* NULL: every send opens the file */
    pthread_mutex_init(&d->lock, NULL);
    pthread_mutex_init(&d->dir_lock, NULL);
    pthread_cond_init(&d->wake, NULL);
    pthread_cond_init(&d->idle, NULL);
    pthread_cond_init(&d->prune_wake, NULL);
    d->base.name = "disk";
    d->base.get = disk_get;
    d->base.has = disk_has;
    d->base.put = disk_put;
    d->base.close = disk_close;
    d->usable = open_root(d, dir);
    if (!d->usable) {
        ism_log_field f[] = {ISM_LS("dir", dir), ISM_LS("error", strerror(errno))};
        ism_log_fields(ISM_LOG_WARN, "cache_dir_unusable", f, 2);
    } else if (pthread_create(&d->writer, NULL, writer_main, d) == 0) {
        d->writer_started = true;
        d->pruner_started = pthread_create(&d->pruner, NULL, pruner_main, d) == 0;
    } else {
        d->usable = false;
    }
    return &d->base;
}
