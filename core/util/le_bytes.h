/* le_bytes.h — unsigned integers written to and read from byte buffers in little-endian
 * order, whatever the host's: the framing between daemon and workers, the cache's stored
 * entries and glTF's binary chunks all use it. */
#ifndef ISM_LE_BYTES_H
#define ISM_LE_BYTES_H

#include <stdint.h>

static inline void ism_put_le32(unsigned char *p, uint32_t v)
{
    for (int i = 0; i < 4; i++)
        p[i] = (unsigned char)(v >> (8 * i));
}

static inline void ism_put_le64(unsigned char *p, uint64_t v)
{
    for (int i = 0; i < 8; i++)
        p[i] = (unsigned char)(v >> (8 * i));
}

static inline uint32_t ism_get_le32(const unsigned char *p)
{
    return (uint32_t)p[0] | (uint32_t)p[1] << 8 | (uint32_t)p[2] << 16 | (uint32_t)p[3] << 24;
}

static inline uint64_t ism_get_le64(const unsigned char *p)
{
    return (uint64_t)ism_get_le32(p) | (uint64_t)ism_get_le32(p + 4) << 32;
}

#endif
