/* blob.h — immutable, reference-counted byte buffers: one cached mesh is shared by the cache
 * tiers, every response that is sending it and the jobs that point at it, and freed when the
 * last of them lets go. Always followed by a NUL byte (handy for JSON). */
#ifndef ISM_BLOB_H
#define ISM_BLOB_H

#include <stdatomic.h>
#include <stddef.h>

typedef struct ism_blob {
    atomic_size_t refs;
    size_t len;
    unsigned char data[]; /* len bytes, then a NUL */
} ism_blob;

/* A blob of len uninitialised bytes with one reference; NULL when out of memory. */
ism_blob *ism_blob_new(size_t len);
/* A blob holding a copy of data. */
ism_blob *ism_blob_copy(const void *data, size_t len);
ism_blob *ism_blob_from_str(const char *s);
/* The blob whose data (b->data, never a pointer into it) this is. */
ism_blob *ism_blob_of_data(unsigned char *data);
/* Adds a reference (NULL passes through). */
ism_blob *ism_blob_ref(ism_blob *b);
/* Drops a reference (NULL is fine); frees on the last. */
void ism_blob_unref(ism_blob *b);
/* Replaces *slot by b (a new reference) and drops the old one. */
void ism_blob_set(ism_blob **slot, ism_blob *b);

#endif
