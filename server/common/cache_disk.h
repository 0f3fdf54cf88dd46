/* cache_disk.h — the disk tier: content-addressed files that survive restarts.
 *
 * Layout: <dir>/v1/<first two hex digits of the key>/<name>, written by a background thread
 * to <dir>/v1/tmp/, then renamed into place, so a killed daemon leaves either the whole entry
 * or none (never fsynced: a cache may lose its latest entries to a power loss, and what such a
 * loss tears fails the checksum below). Each file is a 24-byte header — magic "ISMC", u32
 * version 1, u64 payload length, u32 CRC-32C of header bytes 0..15 and the payload, u32 zero —
 * then the payload. Every read checks all of it; a bad file is deleted, logged and counted
 * (counters.corrupt) and reads as a miss, so the entry is recomputed.
 *
 * A directory that cannot be created or written, a full disk, or a write queue over its byte
 * budget never fails a request: the entry is simply not stored (logged, counted in
 * counters.store_failures).
 *
 * Size bound: counters.bytes and counters.entries say what the directory holds (a scan at start,
 * then every store and removal). Past the bound set with ism_cache_disk_set_max, a background
 * thread removes the least recently used keys, all files of a key together (a read or a store
 * sets a file's mtime), until 90% of the bound is left, counting the files in
 * counters.evictions and logging `cache_pruned`.
 * At start it also removes temporary files left by writers that died mid-write. */
#ifndef ISM_CACHE_DISK_H
#define ISM_CACHE_DISK_H

#include <stdbool.h>
#include <stddef.h>

#include "server/common/cache.h"
#include "server/common/fd_keep.h"

/* A disk tier under dir (created if missing). max_pending bounds the bytes queued for writing
 * (puts are skipped while it holds that much). Returns a working tier even when dir is
 * unusable (it then stores nothing); NULL only when out of memory. */
ism_cache_tier *ism_cache_disk_new(const char *dir, size_t max_pending);

/* Whether the directory was usable at start-up. */
bool ism_cache_disk_usable(const ism_cache_tier *t);

/* Bounds the directory's size in bytes (0: no bound); prunes in the background when over. */
void ism_cache_disk_set_max(ism_cache_tier *t, unsigned long long max_bytes);

/* A descriptor (O_RDONLY, close-on-exec; the caller closes it) of the file holding name when
 * it is on disk (not only queued for writing) with a sound header and exactly the len bytes
 * of payload the caller holds, which start at *offset: for sending the payload without
 * copying it (sendfile). -1 otherwise; a file whose payload differs is dropped as damaged
 * (logged and counted like a bad read). The payload is compared with the caller's bytes the
 * first time the file is opened here and again whenever the file has changed since
 * (file_memo.h: its inode, size or change time differ), so a file written to after it was
 * stored is never sent; one left untouched is sent without being read. A file changed
 * moments before (not settled, file_memo.h), or any while another thread compares one, is
 * neither compared nor sent: -1 (one compare at a time holds up one thread at most). */
int ism_cache_disk_open_payload(ism_cache_tier *t, const char *name, const void *payload,
                                size_t len, long long *offset);
/* The same, but a file kept open for sending (fd_keep.h) is lent, not duplicated: then
 * *lease is set, and the caller gives the descriptor back with ism_fd_keep_give_back instead
 * of closing it (and must not move its offset: sendfile with an offset); else *lease is NULL
 * and the descriptor is the caller's to close, as above. */
int ism_cache_disk_borrow_payload(ism_cache_tier *t, const char *name, const void *payload,
                                  size_t len, long long *offset, ism_fd_lease **lease);

/* Waits until every queued write is on disk (or failed). */
void ism_cache_disk_flush(ism_cache_tier *t);

#endif
