/* cache_line.h — the cache line, and memory that shares none with any other allocation: what
 * one thread writes often (its evaluator registers, its shortened tapes) must not sit in a line
 * another thread writes too (false sharing: the line bounces between the cores' caches). */
#ifndef ISM_CACHE_LINE_H
#define ISM_CACHE_LINE_H

#include <stddef.h>
#include <stdint.h>
#include <stdlib.h>

/* Bytes of a cache line: per-thread state written often is aligned to it, so two threads'
 * writes never share a line. */
#define ISM_CACHE_LINE 64

/* n bytes (at least 1) starting on a cache line and padded to a whole number of lines, so
 * the allocator puts nothing else in them; free with free(). NULL when out of memory. */
static inline void *ism_line_alloc(size_t n)
{
    if (n > SIZE_MAX - ISM_CACHE_LINE)
        return NULL;
    size_t lines = n ? (n + ISM_CACHE_LINE - 1) / ISM_CACHE_LINE : 1;
    return aligned_alloc(ISM_CACHE_LINE, lines * ISM_CACHE_LINE);
}

#endif
