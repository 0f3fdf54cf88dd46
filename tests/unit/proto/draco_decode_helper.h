/* draco_decode_helper.h — test-only: decodes a Draco bitstream with libdraco's own decoder
 * (draco_decode_helper.cc) into plain arrays, finding every attribute by its unique id as
 * the viewer does, so tests can compare what arrives with what was sent. */
#ifndef ISM_TEST_DRACO_DECODE_HELPER_H
#define ISM_TEST_DRACO_DECODE_HELPER_H

#include <stddef.h>
#include <stdint.h>
#include <stdbool.h>

#ifdef __cplusplus
extern "C" {
#endif

#define TEST_DRACO_MAX_IDS 8

typedef struct test_draco_mesh {
    size_t npoints, nfaces;
    float *pos;                 /* 3 per point (dequantised) */
    uint32_t *faces;            /* 3 per face */
    float *normal;              /* unique id 1, or NULL when absent */
    float *mean;                /* unique id 2 */
    float *gauss;               /* unique id 3 */
    uint8_t *cls;               /* unique id 4 */
    int nattributes;
    int type_of[TEST_DRACO_MAX_IDS];      /* draco attribute type by unique id, -1 absent */
    char name_of[TEST_DRACO_MAX_IDS][32]; /* metadata "name" by unique id */
} test_draco_mesh;

bool test_draco_decode(const void *data, size_t len, test_draco_mesh *out, char *err,
                       size_t errlen);
void test_draco_mesh_free(test_draco_mesh *m);

#ifdef __cplusplus
}
#endif

#endif
