/* same_mesh.h — a mesh made by one path of the polygoniser (scalar or batched, n threads) and
 * whether two meshes are the same bit for bit (positions, normals, triangles, segments), for
 * the tests that compare the paths (unit_core's batch_identity, unit_proto's batch_presets):
 * one definition. */
#ifndef TESTS_UNIT_SAME_MESH_H
#define TESTS_UNIT_SAME_MESH_H

#include <criterion/criterion.h>
#include <stdbool.h>
#include <string.h>

#include "core/mesh/mesh.h"
#include "core/octree/polygonise.h"

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

/* t meshed with the options base (box, depths, max_error and threads replaced) in box to
 * depth 2..dmax (under max_error when > 0) on threads threads; st: its stats. */
static inline void test_mesh_with(const ism_tape *t, const ism_poly_options *base,
                                  const double box[6], int dmax, double max_error, int threads,
                                  ism_mesh *m, ism_poly_stats *st)
{
    ism_poly_options o = *base;
    memcpy(o.box, box, 6 * sizeof *box);
    o.min_depth = 2;
    o.max_depth = dmax;
    o.max_error = max_error;
    o.threads = threads;
    ism_error err;
    ism_mesh_init(m);
    cr_assert_eq(ism_polygonise(t, &o, m, st, &err), ISM_POLY_OK, "%s", err.message);
}

/* test_mesh_with the default options, by the scalar evaluators when scalar. */
static inline void test_mesh_of(const ism_tape *t, const double box[6], int dmax,
                                double max_error, int threads, bool scalar, ism_mesh *m,
                                ism_poly_stats *st)
{
    ism_poly_options o;
    ism_poly_options_default(&o);
    o.scalar_eval = scalar;
    test_mesh_with(t, &o, box, dmax, max_error, threads, m, st);
}

#endif
