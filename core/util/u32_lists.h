/* u32_lists.h — a list of uint32 values per uint32 key, newest first: a head per key and the
 * entries in one growable array, each with its key's next entry. Made for a handful of values
 * a key (a look-up is a short walk, an addition two writes: no hashing, nothing rebuilt as it
 * grows), with every key below a count known at the start. */
#ifndef ISM_UTIL_U32_LISTS_H
#define ISM_UTIL_U32_LISTS_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

/* A head or next entry that is none: entries are numbered below it, so a list holds at most
 * ISM_U32_LISTS_END entries in all. */
#define ISM_U32_LISTS_END UINT32_MAX

typedef struct ism_u32_lists {
    uint32_t *head;   /* per key: its newest entry, or ISM_U32_LISTS_END */
    uint32_t (*e)[2]; /* per entry: its key's next entry (ISM_U32_LISTS_END: none), the value */
    size_t n, cap;
} ism_u32_lists;

/* Empty lists for keys 0 .. nkeys - 1; false when out of memory (nothing then to free). */
bool ism_u32_lists_init(ism_u32_lists *l, size_t nkeys);
void ism_u32_lists_free(ism_u32_lists *l);
/* Adds value to key's list; false when out of memory or every entry number is used (l is
 * then as it was). */
bool ism_u32_lists_add(ism_u32_lists *l, uint32_t key, uint32_t value);

/* value is in key's list. */
static inline bool ism_u32_lists_has(const ism_u32_lists *l, uint32_t key, uint32_t value)
{
    for (uint32_t i = l->head[key]; i != ISM_U32_LISTS_END; i = l->e[i][0])
        if (l->e[i][1] == value)
            return true;
    return false;
}

#endif
