/* meshes_for_tests.c — the test meshes of meshes_for_tests.h, built vertex by vertex. */
#include "tests/unit/proto/meshes_for_tests.h"

#include <math.h>
#include <stdlib.h>

static uint32_t vert(ism_mesh *m, double x, double y, double z, float nx, float ny, float nz)
{
    double p[3] = {x, y, z};
    float n[3] = {nx, ny, nz};
    return ism_mesh_add_vertex(m, p, n);
}

void test_mesh_grid(ism_mesh *m, int n)
{
    ism_mesh_init(m);
    for (int j = 0; j <= n; j++)
        for (int i = 0; i <= n; i++)
            vert(m, (double)i / n, (double)j / n, 0, 0, 0, 1);
    for (int j = 0; j < n; j++)
        for (int i = 0; i < n; i++) {
            uint32_t a = (uint32_t)(j * (n + 1) + i), b = a + 1, c = a + (uint32_t)n + 2,
                     d = a + (uint32_t)n + 1;
            ism_mesh_add_triangle(m, a, b, c);
            ism_mesh_add_triangle(m, a, c, d);
        }
}

void test_mesh_torus(ism_mesh *m, int nu, int nv, double R, double r)
{
    ism_mesh_init(m);
    for (int i = 0; i < nu; i++)
        for (int j = 0; j < nv; j++) {
            double u = 2 * M_PI * i / nu, v = 2 * M_PI * j / nv;
            vert(m, (R + r * cos(v)) * cos(u), (R + r * cos(v)) * sin(u), r * sin(v),
                 (float)(cos(v) * cos(u)), (float)(cos(v) * sin(u)), (float)sin(v));
        }
    for (int i = 0; i < nu; i++)
        for (int j = 0; j < nv; j++) {
            uint32_t a = (uint32_t)(i * nv + j), b = (uint32_t)(((i + 1) % nu) * nv + j),
                     c = (uint32_t)(((i + 1) % nu) * nv + (j + 1) % nv),
                     d = (uint32_t)(i * nv + (j + 1) % nv);
            ism_mesh_add_triangle(m, a, b, c);
            ism_mesh_add_triangle(m, a, c, d);
        }
}

void test_mesh_crossing_planes(ism_mesh *m, int n)
{
    ism_mesh_init(m);
    uint32_t *a = malloc(sizeof *a * (size_t)(n + 1) * (n + 1));
    uint32_t *b = malloc(sizeof *b * (size_t)(n + 1) * (n + 1));
    for (int j = 0; j <= n; j++)
        for (int i = 0; i <= n; i++)
            a[j * (n + 1) + i] = vert(m, -1 + 2.0 * i / n, -1 + 2.0 * j / n, 0, 0, 0, 1);
    for (int j = 0; j <= n; j++)
        for (int i = 0; i <= n; i++)
            b[j * (n + 1) + i] = j == n / 2 ? a[(n / 2) * (n + 1) + i]
                                            : vert(m, -1 + 2.0 * i / n, 0, -1 + 2.0 * j / n,
                                                   0, 1, 0);
    uint32_t *grids[2] = {a, b};
    for (int g = 0; g < 2; g++)
        for (int j = 0; j < n; j++)
            for (int i = 0; i < n; i++) {
                uint32_t *v = grids[g];
                uint32_t p = v[j * (n + 1) + i], q = v[j * (n + 1) + i + 1],
                         r = v[(j + 1) * (n + 1) + i + 1], s = v[(j + 1) * (n + 1) + i];
                ism_mesh_add_triangle(m, p, q, r);
                ism_mesh_add_triangle(m, p, r, s);
            }
    free(a);
    free(b);
}

void test_mesh_touching_tetrahedra(ism_mesh *m)
{
    ism_mesh_init(m);
    uint32_t o = vert(m, 0, 0, 0, 0, 0, 0); /* singular: no normal known */
    uint32_t t[2][3];
    for (int s = 0; s < 2; s++) {
        double d = s ? -1 : 1;
        t[s][0] = vert(m, d, 0, 0, (float)d, 0, 0);
        t[s][1] = vert(m, d, d, 0, 0, (float)d, 0);
        t[s][2] = vert(m, d, 0, d, 0, 0, (float)d);
    }
    for (int s = 0; s < 2; s++) {
        uint32_t a = t[s][0], b = t[s][1], c = t[s][2];
        ism_mesh_add_triangle(m, o, b, a);
        ism_mesh_add_triangle(m, o, c, b);
        ism_mesh_add_triangle(m, o, a, c);
        ism_mesh_add_triangle(m, a, b, c);
    }
}
