/* same_mesh.h — whether two meshes are the same bit for bit (positions, normals, triangles,
 * segments), for the tests that compare two paths of the polygoniser (unit_core's
 * batch_identity, unit_proto's batch_presets): one definition. */
#ifndef TESTS_UNIT_SAME_MESH_H
#define TESTS_UNIT_SAME_MESH_H

#include <stdbool.h>
#include <string.h>

#include "core/mesh/mesh.h"

/* n bytes at p and q equal (either may be NULL when n is 0). */
static inline bool test_same_bytes(const void *p, const void *q, size_t n)
{
    return n == 0 || memcmp(p, q, n) == 0;
}

static inline bool test_same_mesh(const ism_mesh *a, const ism_mesh *b)
{
    return a->nverts == b->nverts && a->ntris == b->ntris && a->nsegs == b->nsegs &&
           test_same_bytes(a->pos, b->pos, a->nverts * 3 * sizeof *a->pos) &&
           test_same_bytes(a->normal, b->normal, a->nverts * 3 * sizeof *a->normal) &&
           test_same_bytes(a->tri, b->tri, a->ntris * 3 * sizeof *a->tri) &&
           test_same_bytes(a->seg, b->seg, a->nsegs * 2 * sizeof *a->seg);
}

#endif
