/* zeroed.h — zero-filled arrays that threads will fill: allocated and written with zeros on
 * a pool's threads, instead of calloc's untouched pages. An untouched page read first (a
 * table probe, a memo lookup) is mapped to the kernel's shared zero page; the first write
 * then faults a second time, copies it, and must flush the other threads' TLBs — an
 * interprocessor interrupt per page, a VM exit on both sides under a hypervisor. Written
 * first, a page faults once and nothing is flushed, and the threads share the zeroing. */
#ifndef ISM_ZEROED_H
#define ISM_ZEROED_H

#include <stddef.h>

#include "core/util/parallel.h"

/* n elements of size bytes, every byte 0, starting on a cache line (free with free()); the
 * zeroing runs on pool's threads (a NULL pool: the calling thread) and what it cost is added
 * to *cost when not NULL. NULL when out of memory or n * size overflows. */
void *ism_zeroed_alloc(ism_pool *pool, size_t n, size_t size, ism_par_cost *cost);

#endif
