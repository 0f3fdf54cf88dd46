/* u32_lists.c — lists of uint32 values per key: their allocation and growth (u32_lists.h). */
#include "core/util/u32_lists.h"

#include "core/util/grow.h"

#include <stdlib.h>
#include <string.h>

/* Entries the array first holds: a call of rm_flip_from lists a few hundred to a few thousand
 * edges, so the first doublings are skipped. */
#define U32_LISTS_FIRST 1024

bool ism_u32_lists_init(ism_u32_lists *l, size_t nkeys)
{
    *l = (ism_u32_lists){0};
    if (nkeys > SIZE_MAX / sizeof *l->head ||
        !(l->head = malloc((nkeys ? nkeys : 1) * sizeof *l->head)))
        return false;
    memset(l->head, 0xff, nkeys * sizeof *l->head); /* every byte of ISM_U32_LISTS_END */
    return true;
}

void ism_u32_lists_free(ism_u32_lists *l)
{
    free(l->head);
    free(l->e);
    *l = (ism_u32_lists){0};
}

bool ism_u32_lists_add(ism_u32_lists *l, uint32_t key, uint32_t value)
{
    if (l->n >= ISM_U32_LISTS_END ||
        !ism_grow((void **)&l->e, &l->cap, l->n + 1, sizeof *l->e, U32_LISTS_FIRST))
        return false;
    l->e[l->n][0] = l->head[key];
    l->e[l->n][1] = value;
    l->head[key] = (uint32_t)l->n++;
    return true;
}
