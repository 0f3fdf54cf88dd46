/* cache_redis.h — the shared tier: cache entries in one Redis server that every isomeshd of a
 * service reads and writes, so a mesh computed by one daemon is served by all of them, plus
 * the per-entry locks with which daemons agree on who computes a missing mesh.
 *
 * Keys ("isomesh" is the default namespace; another lets two services share one Redis):
 * "isomesh:v1:<name>" holds an entry (<name> as in cache.h: "<key>.<ext>"), and
 * "isomesh:v1:lock:<name>" the lock of a computation in progress (a random token, SET NX PX,
 * released or extended only by its holder through a compare-and-act script). Entries carry no
 * expiry: bound Redis with maxmemory and an LRU policy (deploy/README.md).
 *
 * Values: a 24-byte header — magic "ISMR", u32 version 1, u64 payload length, u32 CRC-32C of
 * the entry name, header bytes 0..15 and the payload, u32 zero — then the payload. Every read
 * checks all of it; a bad value is deleted, logged and counted (counters.corrupt) and reads as
 * a miss. The name inside the checksum rejects a value stored under another key.
 *
 * Threads: one connection, used only by the tier's own thread. Writes (put) are queued for it
 * within a byte budget and never wait. Reads and locks are made by tasks (ism_redis_task) that
 * the caller schedules and that run on that thread, so no caller ever waits on the network:
 * the tier sits in the cache stack as a remote tier that ism_cache_get never asks.
 *
 * Failures: connect and command timeouts are short (REDIS_CONNECT_TIMEOUT_MS, _COMMAND_), a
 * failed call drops the connection and marks Redis down; while down, every call answers -1 at
 * once without touching the network, writes are skipped (counted in store_failures), and the
 * thread reconnects with a back-off from 100 ms to 2 s. Each outage is logged once when it
 * starts ("redis_unavailable") and once when it ends ("redis_recovered"). */
#ifndef ISM_CACHE_REDIS_H
#define ISM_CACHE_REDIS_H

#include <stdatomic.h>
#include <stdbool.h>
#include <stddef.h>

#include "server/common/cache.h"
#include "core/util/clock.h"

#define ISM_REDIS_CONNECT_TIMEOUT_MS 250
#define ISM_REDIS_COMMAND_TIMEOUT_MS 250
#define ISM_REDIS_HEADER_SIZE 24
#define ISM_REDIS_DEFAULT_NAMESPACE "isomesh" /* keys start "<namespace>:v1:" */
#define ISM_REDIS_PREFIX_MAX 80

typedef struct ism_redis_settings {
    char host[256];
    unsigned short port;
    size_t max_pending;      /* puts are skipped while this much is queued */
    size_t max_entry;        /* larger entries are not shared */
    char namespace_[64];     /* keys start "<namespace_>:v1:"; "" = ISM_REDIS_DEFAULT_NAMESPACE */
    char username[128];      /* AUTH on every connection when password is set */
    char password[256];
} ism_redis_settings;

/* Figures beside the tier's cache counters (read by /metrics). */
typedef struct ism_redis_counters {
    atomic_llong up;                     /* 1 while connected */
    atomic_llong asking;                 /* computations asking Redis or awaiting another daemon */
    atomic_ullong connects;              /* successful connections */
    atomic_ullong outages;               /* times Redis became unreachable */
    atomic_ullong errors;                /* failed connects and commands */
    atomic_ullong locks_acquired;        /* computations this daemon took on */
    atomic_ullong lock_waits;            /* computations found running elsewhere and awaited */
    atomic_ullong lock_takeovers;        /* awaited computations taken over (lock freed or expired) */
    atomic_ullong locks_lost;            /* locks that expired while still computing */
    atomic_ullong stale_locks;           /* locks without a daemon's expiry found and removed */
    atomic_ullong fallbacks;             /* computations done locally because Redis was down */
} ism_redis_counters;

/* Parses "HOST:PORT", "[IPV6]:PORT" or "HOST" (port 6379). False on anything else. */
bool ism_redis_parse_address(const char *s, char host[256], unsigned short *port);

/* Reads the first line of path, "PASSWORD" or "USER PASSWORD" (Redis ACL), into s. The file
 * must be a regular file nobody but its owner and group may read. False with err on error. */
bool ism_redis_load_password(const char *path, ism_redis_settings *s, char *err, size_t cap);

/* A tier for the Redis server in settings, with its thread started (it connects in the
 * background: the tier works, as down, until it can). NULL when out of memory. */
ism_cache_tier *ism_cache_redis_new(const ism_redis_settings *settings);
ism_redis_counters *ism_cache_redis_counters(ism_cache_tier *t);

/* ---- tasks: work that runs on the tier's thread ---------------------------------------- */

typedef struct ism_redis_task ism_redis_task;
struct ism_redis_task {
    ism_redis_task *next;    /* owned by the tier while scheduled */
    long long due_ns;
    /* Runs on the tier's thread (stopping: the tier is closing; clean up and return 0).
     * Returns when to run again (CLOCK_MONOTONIC ns), or 0 when finished (the task then
     * belongs to its owner again; run may have freed it). */
    long long (*run)(ism_redis_task *task, ism_cache_tier *t, bool stopping);
};

/* Runs task on the tier's thread at due_ns (0 = now). Thread-safe, never blocks on I/O. */
void ism_cache_redis_schedule(ism_cache_tier *t, ism_redis_task *task, long long due_ns);

/* The calls below are for tasks only (the tier's thread). -1 means Redis is unavailable. */

bool ism_cache_redis_up(ism_cache_tier *t);
/* Reads names[0..n): out[i] gets the checked payload or NULL. 0 on success, -1 otherwise
 * (out all NULL). Does not count hits or misses (the caller knows what it asked for). */
int ism_cache_redis_fetch(ism_cache_tier *t, const char *const *names, size_t n, ism_blob **out);
/* How many of names[0..n) exist (n at most 8). */
int ism_cache_redis_count(ism_cache_tier *t, const char *const *names, size_t n);
/* 1 when someone holds the lock of name, 0 when nobody does, 2 when a stale lock was found
 * and removed: one without expiry or lasting longer than max_ttl_ms (no daemon sets such). */
int ism_cache_redis_locked(ism_cache_tier *t, const char *name, long max_ttl_ms);
/* 1 when the lock of name was free and is now held with token for ttl_ms, 0 when taken. */
int ism_cache_redis_lock(ism_cache_tier *t, const char *name, const char *token, long ttl_ms);
/* The same, but 2 when the lock is taken by a token that starts with kin (another of this
 * daemon's tasks); a lock without expiry, or with more than ttl_ms left, is taken over. */
int ism_cache_redis_lock_kin(ism_cache_tier *t, const char *name, const char *token,
                             long ttl_ms, const char *kin);
/* 1 when token still held the lock and it now lasts ttl_ms more, 0 when it was lost. */
int ism_cache_redis_renew(ism_cache_tier *t, const char *name, const char *token, long ttl_ms);
/* 1 when token held the lock and released it, 0 when it was not the holder. */
int ism_cache_redis_unlock(ism_cache_tier *t, const char *name, const char *token);
/* "<namespace>:v1:": what every key of this tier starts with. */
const char *ism_cache_redis_prefix(const ism_cache_tier *t);
/* Any one command (argv/lens as hiredis's redisCommandArgv): its reply, to free with
 * freeReplyObject, or NULL when Redis is unavailable or answered an error (counted, logged,
 * and an I/O failure marks Redis down like any other call). */
struct redisReply *ism_cache_redis_call(ism_cache_tier *t, const char *what, int argc,
                                       const char **argv, const size_t *lens);
/* Writes every queued put now (so what a computation stored is in Redis before its lock goes). */
void ism_cache_redis_flush(ism_cache_tier *t);

/* ---- the stored form (exposed for tests) ------------------------------------------------ */

/* Header + payload of b for name, malloc'd; NULL when out of memory. */
unsigned char *ism_redis_value_encode(const char *name, const ism_blob *b, size_t *len);
/* The checked payload of a stored value, or NULL with *why saying what is wrong (or NULL
 * when only memory ran out). */
ism_blob *ism_redis_value_decode(const char *name, const void *data, size_t len,
                                 const char **why);

#endif
