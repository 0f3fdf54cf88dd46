/* blob.c — reference-counted byte buffers (blob.h). */
#include "server/common/blob.h"

#include <stdint.h>
#include <stdlib.h>
#include <string.h>

ism_blob *ism_blob_new(size_t len)
{
    if (len > SIZE_MAX - sizeof(ism_blob) - 1)
        return NULL;
    ism_blob *b = malloc(sizeof *b + len + 1);
    if (!b)
        return NULL;
    atomic_init(&b->refs, 1);
    b->len = len;
    b->data[len] = 0;
    return b;
}

ism_blob *ism_blob_copy(const void *data, size_t len)
{
    ism_blob *b = ism_blob_new(len);
    if (b && len)
        memcpy(b->data, data, len);
    return b;
}

ism_blob *ism_blob_from_str(const char *s)
{
    return ism_blob_copy(s, strlen(s));
}

ism_blob *ism_blob_of_data(unsigned char *data)
{
    return (ism_blob *)(void *)(data - offsetof(ism_blob, data));
}

ism_blob *ism_blob_ref(ism_blob *b)
{
    if (b)
        atomic_fetch_add_explicit(&b->refs, 1, memory_order_relaxed);
    return b;
}

void ism_blob_unref(ism_blob *b)
{
    if (b && atomic_fetch_sub_explicit(&b->refs, 1, memory_order_acq_rel) == 1)
        free(b);
}

void ism_blob_set(ism_blob **slot, ism_blob *b)
{
    ism_blob *old = *slot;
    *slot = ism_blob_ref(b);
    ism_blob_unref(old);
}
