/* grow.h — the one growable-array step of core/: make room for `need` elements.
 *
 * Arrays in core/ are (pointer, count, capacity) triples grown by doubling; this is the only
 * place that doubles, checks the byte count for overflow and reallocs. On failure the array is
 * left as it was (still owned by the caller) and false is returned. */
#ifndef ISM_UTIL_GROW_H
#define ISM_UTIL_GROW_H

#include <stdbool.h>
#include <stdint.h>
#include <stdlib.h>

/* The capacity ism_grow leaves for need elements in an array of capacity cap (first: the
 * first allocation's); 0 when the doubling would overflow. Also for counting the room an
 * array would hold grown so (core/octree/dual.c's held_bytes). */
static inline size_t ism_grow_room(size_t cap, size_t need, size_t first)
{
    if (need <= cap)
        return cap;
    size_t n = cap ? cap : (first ? first : 1);
    while (n < need) {
        if (n > SIZE_MAX / 2)
            return 0;
        n *= 2;
    }
    return n;
}

/* Ensures *cap >= need for an array *p of elements of elem bytes; the first allocation holds
 * `first` elements (or more, when need is larger). */
static inline bool ism_grow(void **p, size_t *cap, size_t need, size_t elem, size_t first)
{
    if (need <= *cap)
        return true;
    size_t n = ism_grow_room(*cap, need, first);
    if (!n || (elem && n > SIZE_MAX / elem))
        return false;
    void *q = realloc(*p, n * elem);
    if (!q)
        return false;
    *p = q;
    *cap = n;
    return true;
}

#endif
