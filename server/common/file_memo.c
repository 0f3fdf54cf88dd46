/* file_memo.c — the memo of file_memo.h: a direct-mapped table of FILE_MEMO_SLOTS records
 * (the name's hash picks the slot, a newer record takes it over), under one mutex. */
#include "server/common/file_memo.h"

#include <pthread.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "server/common/cache.h"
#include "server/common/text_hash.h"

/* Records kept: every large body a daemon serves often (sendfile is for bodies of 1 MB or
 * more, so 1024 of them are at least 1 GB of cache) in a table of about 140 KB. */
#define FILE_MEMO_SLOTS 1024
/* A file changed less than this before its check is checked again at every use: file times
 * are taken from the kernel's coarse clock (a tick of 1-10 ms behind the real one), so two
 * changes within one tick look like one; 50 ms is five of the longest ticks. (It was 2 s for
 * every file: 450 clients arriving within 2 s of a 8.3 MB mesh's store each had it compared
 * in full on a polling thread, 3.7 GB read, and /healthz waited 0.2-0.7 s behind them.) */
#define FILE_MEMO_RACY_NS 50000000LL
/* The same for a file whose change time is a whole second (nanoseconds 0): its file system
 * may keep whole seconds (ext4 with small inodes) or two (FAT), so a change up to 2 s later
 * can share its time; 3 s is past that and a tick. */
#define FILE_MEMO_RACY_WHOLE_SECONDS_NS 3000000000LL

typedef struct record {
    char name[ISM_CACHE_NAME_MAX]; /* "" when the slot is free */
    dev_t dev;
    ino_t ino;
    off_t size;
    struct timespec ctime;
} record;

struct ism_file_memo {
    pthread_mutex_t lock;
    record slots[FILE_MEMO_SLOTS];
};

ism_file_memo *ism_file_memo_new(void)
{
    ism_file_memo *m = calloc(1, sizeof *m);
    if (m)
        pthread_mutex_init(&m->lock, NULL);
    return m;
}

void ism_file_memo_free(ism_file_memo *m)
{
    if (!m)
        return;
    pthread_mutex_destroy(&m->lock);
    free(m);
}

static record *slot_of(ism_file_memo *m, const char *name)
{
    return &m->slots[ism_text_hash(name) % FILE_MEMO_SLOTS];
}

static bool same_identity(const record *r, const struct stat *st)
{
    return r->dev == st->st_dev && r->ino == st->st_ino && r->size == st->st_size &&
           r->ctime.tv_sec == st->st_ctim.tv_sec && r->ctime.tv_nsec == st->st_ctim.tv_nsec;
}

bool ism_file_memo_holds(ism_file_memo *m, const char *name, const struct stat *st)
{
    if (!m)
        return false;
    pthread_mutex_lock(&m->lock);
    const record *r = slot_of(m, name);
    bool holds = !strcmp(r->name, name) && same_identity(r, st);
    pthread_mutex_unlock(&m->lock);
    return holds;
}

bool ism_file_memo_settled(const struct stat *st)
{
    struct timespec now;
    clock_gettime(CLOCK_REALTIME, &now);
    long long age_ns = (long long)(now.tv_sec - st->st_ctim.tv_sec) * 1000000000LL +
                       (now.tv_nsec - st->st_ctim.tv_nsec);
    return age_ns >= (st->st_ctim.tv_nsec ? FILE_MEMO_RACY_NS : FILE_MEMO_RACY_WHOLE_SECONDS_NS);
}

void ism_file_memo_put(ism_file_memo *m, const char *name, const struct stat *st)
{
    if (!m || !ism_file_memo_settled(st) || strlen(name) >= ISM_CACHE_NAME_MAX)
        return;
    pthread_mutex_lock(&m->lock);
    record *r = slot_of(m, name);
    strcpy(r->name, name);
    r->dev = st->st_dev;
    r->ino = st->st_ino;
    r->size = st->st_size;
    r->ctime = st->st_ctim;
    pthread_mutex_unlock(&m->lock);
}
