/* cache_mem.c — the memory tier (cache_mem.h): a chained hash table of entries threaded on a
 * doubly linked recency list; a hit moves the entry to the front, a store evicts from the
 * back until the byte budget holds. One mutex; blobs are released outside it. */
#include "server/common/cache_mem.h"
#include "server/common/text_hash.h"

#include <pthread.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#define ENTRY_OVERHEAD 192 /* bytes counted per entry besides its data */

typedef struct entry {
    struct entry *hnext;          /* hash chain */
    struct entry *prev, *next;    /* recency list, most recent first */
    ism_blob *blob;
    size_t cost;
    char name[ISM_CACHE_NAME_MAX];
} entry;

typedef struct mem_tier {
    ism_cache_tier base;
    pthread_mutex_t lock;
    entry **buckets;
    size_t nbuckets, count;
    entry *head, *tail;
    size_t used, capacity;
} mem_tier;

static entry **slot_of(mem_tier *m, const char *name)
{
    entry **e = &m->buckets[ism_text_hash(name) & (m->nbuckets - 1)];
    while (*e && strcmp((*e)->name, name) != 0)
        e = &(*e)->hnext;
    return e;
}

static void list_unlink(mem_tier *m, entry *e)
{
    if (e->prev)
        e->prev->next = e->next;
    else
        m->head = e->next;
    if (e->next)
        e->next->prev = e->prev;
    else
        m->tail = e->prev;
    e->prev = e->next = NULL;
}

static void list_push_front(mem_tier *m, entry *e)
{
    e->prev = NULL;
    e->next = m->head;
    if (m->head)
        m->head->prev = e;
    m->head = e;
    if (!m->tail)
        m->tail = e;
}

static void grow_table(mem_tier *m)
{
    size_t n = m->nbuckets * 2;
    entry **nb = calloc(n, sizeof *nb);
    if (!nb)
        return; /* keep the longer chains */
    for (size_t i = 0; i < m->nbuckets; i++) {
        entry *e = m->buckets[i];
        while (e) {
            entry *next = e->hnext;
            entry **s = &nb[ism_text_hash(e->name) & (n - 1)];
            e->hnext = *s;
            *s = e;
            e = next;
        }
    }
    free(m->buckets);
    m->buckets = nb;
    m->nbuckets = n;
}

/* Removes e from table and list; returns it for freeing outside the lock. */
static entry *remove_entry(mem_tier *m, entry *e)
{
    entry **s = slot_of(m, e->name);
    if (*s == e)
        *s = e->hnext;
    list_unlink(m, e);
    m->used -= e->cost;
    m->count--;
    e->hnext = NULL;
    return e;
}

static void free_chain(entry *e)
{
    while (e) {
        entry *next = e->hnext;
        ism_blob_unref(e->blob);
        free(e);
        e = next;
    }
}

static void publish(mem_tier *m)
{
    atomic_store(&m->base.counters.bytes, m->used);
    atomic_store(&m->base.counters.entries, m->count);
}

static ism_blob *mem_get(ism_cache_tier *t, const char *name)
{
    mem_tier *m = (mem_tier *)t;
    pthread_mutex_lock(&m->lock);
    entry *e = *slot_of(m, name);
    ism_blob *b = NULL;
    if (e) {
        if (m->head != e) {
            list_unlink(m, e);
            list_push_front(m, e);
        }
        b = ism_blob_ref(e->blob);
    }
    pthread_mutex_unlock(&m->lock);
    return b;
}

static bool mem_has(ism_cache_tier *t, const char *name)
{
    mem_tier *m = (mem_tier *)t;
    pthread_mutex_lock(&m->lock);
    bool found = *slot_of(m, name) != NULL;
    pthread_mutex_unlock(&m->lock);
    return found;
}

static void mem_put(ism_cache_tier *t, const char *name, ism_blob *b)
{
    mem_tier *m = (mem_tier *)t;
    size_t cost = b->len + ENTRY_OVERHEAD;
    if (strlen(name) >= ISM_CACHE_NAME_MAX || cost > m->capacity / 2)
        return;
    entry *fresh = calloc(1, sizeof *fresh);
    if (!fresh)
        return;
    strcpy(fresh->name, name);
    fresh->blob = ism_blob_ref(b);
    fresh->cost = cost;

    entry *dead = NULL; /* chain of entries to free after unlocking */
    pthread_mutex_lock(&m->lock);
    entry **s = slot_of(m, name);
    if (*s) { /* same name, same bytes: only refresh its place */
        if (m->head != *s) {
            entry *e = *s;
            list_unlink(m, e);
            list_push_front(m, e);
        }
        pthread_mutex_unlock(&m->lock);
        free_chain(fresh);
        return;
    }
    while (m->tail && m->used + cost > m->capacity) {
        entry *old = remove_entry(m, m->tail);
        old->hnext = dead;
        dead = old;
        atomic_fetch_add(&m->base.counters.evictions, 1);
    }
    s = slot_of(m, name);
    fresh->hnext = *s;
    *s = fresh;
    list_push_front(m, fresh);
    m->used += cost;
    m->count++;
    if (m->count > m->nbuckets)
        grow_table(m);
    atomic_fetch_add(&m->base.counters.stores, 1);
    publish(m);
    pthread_mutex_unlock(&m->lock);
    free_chain(dead);
}

static void mem_close(ism_cache_tier *t)
{
    mem_tier *m = (mem_tier *)t;
    for (size_t i = 0; i < m->nbuckets; i++)
        free_chain(m->buckets[i]);
    free(m->buckets);
    pthread_mutex_destroy(&m->lock);
    free(m);
}

ism_cache_tier *ism_cache_mem_new(size_t capacity)
{
    mem_tier *m = calloc(1, sizeof *m);
    if (!m)
        return NULL;
    m->nbuckets = 1024;
    m->buckets = calloc(m->nbuckets, sizeof *m->buckets);
    if (!m->buckets) {
        free(m);
        return NULL;
    }
    pthread_mutex_init(&m->lock, NULL);
    m->capacity = capacity;
    m->base.name = "memory";
    m->base.get = mem_get;
    m->base.has = mem_has;
    m->base.put = mem_put;
    m->base.close = mem_close;
    return &m->base;
}
