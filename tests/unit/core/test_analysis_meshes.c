/* test_analysis_meshes.c — builders of the hand-made meshes the analysis tests measure. */
#include "tests/unit/core/test_analysis_meshes.h"

#include <criterion/criterion.h>
#include <math.h>
#include <stdlib.h>

#define PI 3.14159265358979323846

uint32_t ta_vertex(ism_mesh *m, double x, double y, double z)
{
    double p[3] = {x, y, z};
    uint32_t v = ism_mesh_add_vertex(m, p, NULL);
    cr_assert_neq(v, UINT32_MAX);
    return v;
}

void ta_triangle(ism_mesh *m, uint32_t a, uint32_t b, uint32_t c)
{
    cr_assert(ism_mesh_add_triangle(m, a, b, c));
}

void ta_cube(ism_mesh *m)
{
    uint32_t base = (uint32_t)m->nverts;
    for (int i = 0; i < 8; i++)
        ta_vertex(m, i & 1, (i >> 1) & 1, (i >> 2) & 1);
    /* each face as two triangles, counter-clockwise seen from outside */
    static const int quads[6][4] = {
        {0, 2, 3, 1}, /* z = 0 */ {4, 5, 7, 6}, /* z = 1 */
        {0, 1, 5, 4}, /* y = 0 */ {2, 6, 7, 3}, /* y = 1 */
        {0, 4, 6, 2}, /* x = 0 */ {1, 3, 7, 5}, /* x = 1 */
    };
    for (int f = 0; f < 6; f++) {
        const int *q = quads[f];
        ta_triangle(m, base + q[0], base + q[1], base + q[2]);
        ta_triangle(m, base + q[0], base + q[2], base + q[3]);
    }
}

void ta_fan(ism_mesh *m, uint32_t apex, int n, double h)
{
    uint32_t ring = (uint32_t)m->nverts;
    for (int i = 0; i < n; i++)
        ta_vertex(m, cos(2 * PI * i / n), sin(2 * PI * i / n), h);
    for (int i = 0; i < n; i++)
        ta_triangle(m, apex, ring + i, ring + (i + 1) % n);
}

void ta_disc(ism_mesh *m, int n)
{
    uint32_t c = ta_vertex(m, 0, 0, 0);
    ta_fan(m, c, n, 0);
}

void ta_moebius(ism_mesh *m, int n)
{
    uint32_t top = (uint32_t)m->nverts, bottom = top + n;
    for (int side = 0; side < 2; side++)
        for (int i = 0; i < n; i++) {
            double t = 2 * PI * i / n, w = side ? -0.3 : 0.3;
            double rad = 1 + w * cos(t / 2);
            ta_vertex(m, rad * cos(t), rad * sin(t), w * sin(t / 2));
        }
    for (int i = 0; i < n; i++) {
        uint32_t t0 = top + i, b0 = bottom + i, t1, b1;
        if (i + 1 < n) {
            t1 = top + i + 1;
            b1 = bottom + i + 1;
        } else { /* the half twist: top meets bottom */
            t1 = bottom;
            b1 = top;
        }
        ta_triangle(m, t0, b0, b1);
        ta_triangle(m, t0, b1, t1);
    }
}

void ta_torus(ism_mesh *m, int nu, int nv, double R, double r)
{
    uint32_t base = (uint32_t)m->nverts;
    for (int i = 0; i < nu; i++)
        for (int j = 0; j < nv; j++) {
            double u = 2 * PI * i / nu, v = 2 * PI * j / nv;
            ta_vertex(m, (R + r * cos(v)) * cos(u), (R + r * cos(v)) * sin(u), r * sin(v));
        }
    for (int i = 0; i < nu; i++)
        for (int j = 0; j < nv; j++) {
            uint32_t a = base + i * nv + j, b = base + ((i + 1) % nu) * nv + j;
            uint32_t c = base + ((i + 1) % nu) * nv + (j + 1) % nv;
            uint32_t d = base + i * nv + (j + 1) % nv;
            ta_triangle(m, a, b, c);
            ta_triangle(m, a, c, d);
        }
}

static uint32_t welded_vertex(ism_mesh *m, const double p[3])
{
    for (size_t v = 0; v < m->nverts; v++) {
        const double *q = m->pos + 3 * v;
        if (q[0] == p[0] && q[1] == p[1] && q[2] == p[2])
            return (uint32_t)v;
    }
    return ta_vertex(m, p[0], p[1], p[2]);
}

void ta_plane_grid(ism_mesh *m, int a, int b, int k)
{
    uint32_t *id = malloc((size_t)(k + 1) * (k + 1) * sizeof *id);
    cr_assert_not_null(id);
    for (int i = 0; i <= k; i++)
        for (int j = 0; j <= k; j++) {
            double p[3] = {0, 0, 0};
            p[a] = -1 + 2.0 * i / k;
            p[b] = -1 + 2.0 * j / k;
            id[i * (k + 1) + j] = welded_vertex(m, p);
        }
    for (int i = 0; i < k; i++)
        for (int j = 0; j < k; j++) {
            uint32_t p00 = id[i * (k + 1) + j], p10 = id[(i + 1) * (k + 1) + j];
            uint32_t p11 = id[(i + 1) * (k + 1) + j + 1], p01 = id[i * (k + 1) + j + 1];
            ta_triangle(m, p00, p10, p11);
            ta_triangle(m, p00, p11, p01);
        }
    free(id);
}

/* Midpoint of edge (a, b) pushed out onto the sphere, created once per edge (an
 * open-addressing table keyed by the vertex pair). */
typedef struct mid_table {
    uint64_t *key;
    uint32_t *val;
    size_t cap;
} mid_table;

static uint32_t midpoint(ism_mesh *m, mid_table *t, uint32_t a, uint32_t b, double r)
{
    uint64_t k = a < b ? (uint64_t)a << 32 | b : (uint64_t)b << 32 | a;
    size_t i = (size_t)((k * 0x9E3779B97F4A7C15ull) >> 20) % t->cap;
    while (t->key[i] != UINT64_MAX && t->key[i] != k)
        i = (i + 1) % t->cap;
    if (t->key[i] == k)
        return t->val[i];
    const double *p = m->pos + 3 * a, *q = m->pos + 3 * b;
    double c[3] = {(p[0] + q[0]) / 2, (p[1] + q[1]) / 2, (p[2] + q[2]) / 2};
    double len = sqrt(c[0] * c[0] + c[1] * c[1] + c[2] * c[2]);
    t->key[i] = k;
    t->val[i] = ta_vertex(m, c[0] * r / len, c[1] * r / len, c[2] * r / len);
    return t->val[i];
}

void ta_icosphere(ism_mesh *m, int levels, double r)
{
    double g = (1 + sqrt(5)) / 2;
    static const int faces[20][3] = {
        {0, 11, 5}, {0, 5, 1}, {0, 1, 7}, {0, 7, 10}, {0, 10, 11}, {1, 5, 9}, {5, 11, 4},
        {11, 10, 2}, {10, 7, 6}, {7, 1, 8}, {3, 9, 4}, {3, 4, 2}, {3, 2, 6}, {3, 6, 8},
        {3, 8, 9}, {4, 9, 5}, {2, 4, 11}, {6, 2, 10}, {8, 6, 7}, {9, 8, 1}};
    double base[12][3] = {{-1, g, 0}, {1, g, 0}, {-1, -g, 0}, {1, -g, 0},
                          {0, -1, g}, {0, 1, g}, {0, -1, -g}, {0, 1, -g},
                          {g, 0, -1}, {g, 0, 1}, {-g, 0, -1}, {-g, 0, 1}};
    ism_mesh_init(m);
    double s = r / sqrt(1 + g * g);
    for (int i = 0; i < 12; i++)
        ta_vertex(m, base[i][0] * s, base[i][1] * s, base[i][2] * s);
    for (int f = 0; f < 20; f++)
        ta_triangle(m, faces[f][0], faces[f][1], faces[f][2]);
    for (int l = 0; l < levels; l++) {
        size_t nt = m->ntris;
        uint32_t *old = malloc(nt * 3 * sizeof *old);
        cr_assert_not_null(old);
        for (size_t i = 0; i < 3 * nt; i++)
            old[i] = m->tri[i];
        mid_table t = {.cap = 4 * 3 * nt};
        t.key = malloc(t.cap * sizeof *t.key);
        t.val = malloc(t.cap * sizeof *t.val);
        cr_assert(t.key && t.val);
        for (size_t i = 0; i < t.cap; i++)
            t.key[i] = UINT64_MAX;
        m->ntris = 0;
        for (size_t f = 0; f < nt; f++) {
            uint32_t a = old[3 * f], b = old[3 * f + 1], c = old[3 * f + 2];
            uint32_t ab = midpoint(m, &t, a, b, r), bc = midpoint(m, &t, b, c, r);
            uint32_t ca = midpoint(m, &t, c, a, r);
            ta_triangle(m, a, ab, ca);
            ta_triangle(m, b, bc, ab);
            ta_triangle(m, c, ca, bc);
            ta_triangle(m, ab, bc, ca);
        }
        free(old);
        free(t.key);
        free(t.val);
    }
}
