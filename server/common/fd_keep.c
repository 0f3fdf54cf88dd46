/* fd_keep.c — the table of fd_keep.h: FD_KEEP_SLOTS slots, direct-mapped by the name's hash (a
 * newer name takes a slot over), under one read-write lock. Each kept descriptor is a
 * reference-counted lease (the slot holds one reference, each borrower one more); it is
 * lent under the lock (read), so a slot taken over (its reference let go, under the write
 * lock) never hands out a closed or reused number, and a lent one is closed by the last
 * give-back. Why not a mutex: every cached mesh the own sender answers takes its file here,
 * on any polling thread; under one mutex (when a lookup made a dup under it) the threads
 * queued (16 connections on 2 threads, one mesh: 0.44 futex calls per request under strace,
 * most of them here), readers now pass each other. */
#include "server/common/fd_keep.h"

#include <fcntl.h>
#include <pthread.h>
#include <stdatomic.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "server/common/cache.h"
#include "server/common/text_hash.h"

/* Files kept open at most: each holds a descriptor (and, once its name is removed from the
 * directory, its disk space until a send notices and drops it). 64 large meshes served
 * alternately stay open; a 65th shares a slot and reopens now and then. */
#define FD_KEEP_SLOTS 64

struct ism_fd_lease {
    atomic_int refs;
    int fd;
};

typedef struct slot {
    char name[ISM_CACHE_NAME_MAX]; /* "" when free */
    ism_fd_lease *kept;            /* NULL when free */
} slot;

struct ism_fd_keep {
    pthread_rwlock_t lock;
    slot slots[FD_KEEP_SLOTS];
};

ism_fd_keep *ism_fd_keep_new(void)
{
    ism_fd_keep *k = calloc(1, sizeof *k);
    if (!k)
        return NULL;
    pthread_rwlock_init(&k->lock, NULL);
    return k;
}

/* Empties s; returns the lease it held (NULL: none), for the caller to give back once the
 * lock is let go (closing the last descriptor of a removed file frees its blocks). */
static ism_fd_lease *clear(slot *s)
{
    ism_fd_lease *l = s->kept;
    s->kept = NULL;
    s->name[0] = 0;
    return l;
}

void ism_fd_keep_give_back(ism_fd_lease *l)
{
    if (l && atomic_fetch_sub(&l->refs, 1) == 1) {
        close(l->fd);
        free(l);
    }
}

void ism_fd_keep_free(ism_fd_keep *k)
{
    if (!k)
        return;
    for (unsigned i = 0; i < FD_KEEP_SLOTS; i++)
        ism_fd_keep_give_back(clear(&k->slots[i]));
    pthread_rwlock_destroy(&k->lock);
    free(k);
}

static slot *slot_of(ism_fd_keep *k, const char *name)
{
    return &k->slots[ism_text_hash(name) % FD_KEEP_SLOTS];
}

int ism_fd_keep_borrow(ism_fd_keep *k, const char *name, ism_fd_lease **lease)
{
    *lease = NULL;
    if (!k)
        return -1;
    pthread_rwlock_rdlock(&k->lock);
    slot *s = slot_of(k, name);
    if (s->kept && !strcmp(s->name, name)) {
        atomic_fetch_add(&s->kept->refs, 1);
        *lease = s->kept;
    }
    pthread_rwlock_unlock(&k->lock);
    return *lease ? (*lease)->fd : -1;
}

void ism_fd_keep_put(ism_fd_keep *k, const char *name, int fd)
{
    if (!k || strlen(name) >= ISM_CACHE_NAME_MAX)
        return;
    ism_fd_lease *mine = malloc(sizeof *mine);
    if (!mine)
        return;
    mine->fd = fcntl(fd, F_DUPFD_CLOEXEC, 0);
    if (mine->fd < 0) {
        free(mine);
        return;
    }
    atomic_init(&mine->refs, 1); /* the slot's */
    pthread_rwlock_wrlock(&k->lock);
    slot *s = slot_of(k, name);
    ism_fd_lease *old = clear(s);
    s->kept = mine;
    strcpy(s->name, name);
    pthread_rwlock_unlock(&k->lock);
    ism_fd_keep_give_back(old);
}

void ism_fd_keep_drop(ism_fd_keep *k, const char *name)
{
    if (!k)
        return;
    pthread_rwlock_wrlock(&k->lock);
    slot *s = slot_of(k, name);
    ism_fd_lease *old = !strcmp(s->name, name) ? clear(s) : NULL;
    pthread_rwlock_unlock(&k->lock);
    ism_fd_keep_give_back(old);
}
