/* fd_keep.c — the table of fd_keep.h: FD_KEEP_SLOTS slots, direct-mapped by the name's hash (a
 * newer name takes a slot over), under one read-write lock. A descriptor is duplicated under
 * the lock (read), so a slot taken over (its descriptor closed, under the write lock) never
 * hands out a closed or reused number. Why not a mutex: every cached mesh the own sender
 * answers duplicates its file here, on any polling thread; under one mutex the dup syscall
 * made the threads queue (16 connections on 2 threads, one mesh: 0.44 futex calls per
 * request under strace, most of them here), readers now pass each other. */
#include "server/common/fd_keep.h"

#include <fcntl.h>
#include <pthread.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "server/common/cache.h"
#include "server/common/text_hash.h"

/* Files kept open at most: each holds a descriptor (and, once its name is removed from the
 * directory, its disk space until a send notices and drops it). 64 large meshes served
 * alternately stay open; a 65th shares a slot and reopens now and then. */
#define FD_KEEP_SLOTS 64

typedef struct slot {
    char name[ISM_CACHE_NAME_MAX]; /* "" when free */
    int fd;
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
    for (unsigned i = 0; i < FD_KEEP_SLOTS; i++)
        k->slots[i].fd = -1;
    return k;
}

/* Empties s; returns the descriptor it held (-1: none), for the caller to close once the
 * lock is let go (closing the last descriptor of a removed file frees its blocks). */
static int clear(slot *s)
{
    int fd = s->fd;
    s->fd = -1;
    s->name[0] = 0;
    return fd;
}

static void close_if(int fd)
{
    if (fd >= 0)
        close(fd);
}

void ism_fd_keep_free(ism_fd_keep *k)
{
    if (!k)
        return;
    for (unsigned i = 0; i < FD_KEEP_SLOTS; i++)
        close_if(clear(&k->slots[i]));
    pthread_rwlock_destroy(&k->lock);
    free(k);
}

static slot *slot_of(ism_fd_keep *k, const char *name)
{
    return &k->slots[ism_text_hash(name) % FD_KEEP_SLOTS];
}

int ism_fd_keep_get(ism_fd_keep *k, const char *name)
{
    if (!k)
        return -1;
    pthread_rwlock_rdlock(&k->lock);
    slot *s = slot_of(k, name);
    int fd = s->fd >= 0 && !strcmp(s->name, name) ? fcntl(s->fd, F_DUPFD_CLOEXEC, 0) : -1;
    pthread_rwlock_unlock(&k->lock);
    return fd;
}

void ism_fd_keep_put(ism_fd_keep *k, const char *name, int fd)
{
    if (!k || strlen(name) >= ISM_CACHE_NAME_MAX)
        return;
    int mine = fcntl(fd, F_DUPFD_CLOEXEC, 0);
    if (mine < 0)
        return;
    pthread_rwlock_wrlock(&k->lock);
    slot *s = slot_of(k, name);
    int old = clear(s);
    s->fd = mine;
    strcpy(s->name, name);
    pthread_rwlock_unlock(&k->lock);
    close_if(old);
}

void ism_fd_keep_drop(ism_fd_keep *k, const char *name)
{
    if (!k)
        return;
    pthread_rwlock_wrlock(&k->lock);
    slot *s = slot_of(k, name);
    int old = !strcmp(s->name, name) ? clear(s) : -1;
    pthread_rwlock_unlock(&k->lock);
    close_if(old);
}
