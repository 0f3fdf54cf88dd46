/* test_writers.c — core's PLY / OBJ / STL writers, read back by small independent readers:
 * element counts, positions, normals and indices survive, sizes match ism_*_size, empty
 * meshes give valid files, and a failing write callback makes the writer return false. */
#include <criterion/criterion.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "core/mesh/write_mesh.h"
#include "tests/unit/proto/meshes_for_tests.h"

typedef struct membuf {
    unsigned char *data;
    size_t len, cap;
    size_t fail_after; /* accept this many bytes in total, then fail (SIZE_MAX: never) */
} membuf;

static size_t mem_write(void *ctx, const void *p, size_t n)
{
    membuf *b = ctx;
    if (b->len + n > b->fail_after)
        return 0;
    if (b->len + n > b->cap) {
        b->cap = (b->len + n) * 2;
        b->data = realloc(b->data, b->cap);
    }
    memcpy(b->data + b->len, p, n);
    b->len += n;
    return n;
}

static uint32_t rd32(const unsigned char *p)
{
    return (uint32_t)p[0] | (uint32_t)p[1] << 8 | (uint32_t)p[2] << 16 | (uint32_t)p[3] << 24;
}

static float rdf(const unsigned char *p)
{
    uint32_t u = rd32(p);
    float f;
    memcpy(&f, &u, 4);
    return f;
}

Test(writers, ply_reads_back)
{
    ism_mesh m;
    test_mesh_torus(&m, 24, 12, 1, 0.3);
    membuf b = {.fail_after = SIZE_MAX};
    cr_assert(ism_write_ply(&m, mem_write, &b));
    cr_expect_eq(b.len, ism_ply_size(&m));
    b.data = realloc(b.data, b.len + 1);
    b.data[b.len] = 0; /* the header is text: make strstr safe */
    const char *end = strstr((const char *)b.data, "end_header\n");
    cr_assert_not_null(end);
    size_t nv = 0, nf = 0;
    const char *ev = strstr((const char *)b.data, "element vertex ");
    const char *ef = strstr((const char *)b.data, "element face ");
    cr_assert(ev && ef && sscanf(ev, "element vertex %zu", &nv) == 1 &&
              sscanf(ef, "element face %zu", &nf) == 1);
    cr_expect_eq(nv, m.nverts);
    cr_expect_eq(nf, m.ntris);
    cr_expect_not_null(strstr((const char *)b.data, "format binary_little_endian 1.0\n"));
    const unsigned char *p = (const unsigned char *)end + strlen("end_header\n");
    for (size_t i = 0; i < nv; i++, p += 24)
        for (int k = 0; k < 3; k++) {
            cr_assert_eq(rdf(p + 4 * k), (float)m.pos[3 * i + k]);
            cr_assert_eq(rdf(p + 12 + 4 * k), m.normal[3 * i + k]);
        }
    for (size_t t = 0; t < nf; t++, p += 13) {
        cr_assert_eq(p[0], 3);
        for (int k = 0; k < 3; k++)
            cr_assert_eq(rd32(p + 1 + 4 * k), m.tri[3 * t + k]);
    }
    cr_expect_eq((size_t)(p - b.data), b.len);
    free(b.data);
    ism_mesh_free(&m);
}

Test(writers, obj_reads_back)
{
    ism_mesh m;
    test_mesh_crossing_planes(&m, 4);
    membuf b = {.fail_after = SIZE_MAX};
    cr_assert(ism_write_obj(&m, mem_write, &b));
    b.data = realloc(b.data, b.len + 1);
    b.data[b.len] = 0;
    size_t nv = 0, nn = 0, nf = 0;
    char *save = NULL;
    for (char *line = strtok_r((char *)b.data, "\n", &save); line;
         line = strtok_r(NULL, "\n", &save)) {
        double x, y, z;
        unsigned long a, a2, bb, b2, c, c2;
        if (sscanf(line, "v %lf %lf %lf", &x, &y, &z) == 3) {
            cr_assert_float_eq(x, m.pos[3 * nv], 1e-8);
            cr_assert_float_eq(z, m.pos[3 * nv + 2], 1e-8);
            nv++;
        } else if (sscanf(line, "vn %lf %lf %lf", &x, &y, &z) == 3) {
            nn++;
        } else if (sscanf(line, "f %lu//%lu %lu//%lu %lu//%lu", &a, &a2, &bb, &b2, &c, &c2) ==
                   6) {
            cr_assert_eq(a - 1, m.tri[3 * nf]);
            cr_assert_eq(c - 1, m.tri[3 * nf + 2]);
            cr_assert_eq(a, a2);
            nf++;
        } else {
            cr_assert_eq(line[0], '#', "unexpected line %s", line);
        }
    }
    cr_expect_eq(nv, m.nverts);
    cr_expect_eq(nn, m.nverts);
    cr_expect_eq(nf, m.ntris);
    free(b.data);
    ism_mesh_free(&m);
}

Test(writers, stl_reads_back_with_unit_facet_normals)
{
    ism_mesh m;
    test_mesh_grid(&m, 5);
    double zero[3] = {0, 0, 0};
    uint32_t v = ism_mesh_add_vertex(&m, zero, NULL);
    ism_mesh_add_triangle(&m, 0, v, 0); /* a zero-area triangle: normal 0 */
    membuf b = {.fail_after = SIZE_MAX};
    cr_assert(ism_write_stl(&m, mem_write, &b));
    cr_expect_eq(b.len, ism_stl_size(&m));
    cr_expect(strncmp((const char *)b.data, "solid", 5) != 0, "binary STL must not start "
                                                               "with 'solid'");
    cr_assert_eq(rd32(b.data + 80), m.ntris);
    for (size_t t = 0; t < m.ntris; t++) {
        const unsigned char *p = b.data + 84 + 50 * t;
        float nz = rdf(p + 8);
        if (t + 1 < m.ntris)
            cr_assert_float_eq(nz, 1.0f, 1e-6, "grid facets face +z (winding)");
        else
            cr_assert_eq(nz, 0.0f);
        for (int c = 0; c < 3; c++)
            for (int k = 0; k < 3; k++)
                cr_assert_eq(rdf(p + 12 + 12 * c + 4 * k), (float)m.pos[3 * m.tri[3 * t + c] + k]);
    }
    free(b.data);
    ism_mesh_free(&m);
}

Test(writers, empty_meshes_give_valid_files)
{
    ism_mesh m;
    ism_mesh_init(&m);
    membuf b = {.fail_after = SIZE_MAX};
    cr_assert(ism_write_ply(&m, mem_write, &b));
    cr_expect_not_null(memmem(b.data, b.len, "element vertex 0\n", 17));
    cr_expect_eq(b.len, ism_ply_size(&m));
    b.len = 0;
    cr_assert(ism_write_stl(&m, mem_write, &b));
    cr_expect_eq(b.len, 84);
    cr_expect_eq(rd32(b.data + 80), 0);
    b.len = 0;
    cr_assert(ism_write_obj(&m, mem_write, &b));
    cr_expect_gt(b.len, 0);
    free(b.data);
}

Test(writers, a_failing_callback_is_reported)
{
    ism_mesh m;
    test_mesh_torus(&m, 64, 32, 1, 0.3);
    bool (*writers[3])(const ism_mesh *, ism_write_fn, void *) = {ism_write_ply, ism_write_obj,
                                                                    ism_write_stl};
    for (int i = 0; i < 3; i++) {
        size_t limits[] = {0, 10, 70000};
        for (int k = 0; k < 3; k++) {
            membuf b = {.fail_after = limits[k]};
            cr_expect(!writers[i](&m, mem_write, &b), "writer %d, limit %zu", i, limits[k]);
            free(b.data);
        }
    }
    ism_mesh_free(&m);
}
