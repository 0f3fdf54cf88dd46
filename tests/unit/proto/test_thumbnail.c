/* test_thumbnail.c — the thumbnail's parts: the rasteriser covers exactly the pixels whose
 * centres a triangle holds (either winding, no gap or double cover along a shared edge, the
 * nearer triangle wins), the deflate stream equals zlib's own fixed-Huffman output on known
 * inputs, the PNG has its signature, header and chunk CRCs, and a sphere's picture is a
 * centred disc whose share of the frame is the projected sphere's. */
#include <criterion/criterion.h>
#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "proto/png.h"
#include "proto/raster.h"
#include "proto/thumbnail.h"

static const float GREY[3][3] = {{.5f, .5f, .5f}, {.5f, .5f, .5f}, {.5f, .5f, .5f}};

/* The triangle (1,1) (9.3,1) (1,9.3) holds the centre (i+.5, j+.5) iff i, j >= 1 and
 * i + j <= 9 (no centre lies on an edge). */
static void check_right_triangle(bool flip)
{
    ism_raster r;
    cr_assert(ism_raster_init(&r, 12, 12));
    float p[3][3] = {{1, 1, 2}, {9.3f, 1, 2}, {1, 9.3f, 2}};
    if (flip) {
        float t[3];
        memcpy(t, p[1], sizeof t);
        memcpy(p[1], p[2], sizeof t);
        memcpy(p[2], t, sizeof t);
    }
    ism_raster_triangle(&r, p, GREY);
    int covered = 0;
    for (int j = 0; j < 12; j++)
        for (int i = 0; i < 12; i++) {
            bool want = i >= 1 && j >= 1 && i + j <= 9;
            cr_expect_eq(ism_raster_covered(&r, i, j), want, "pixel %d %d (flip %d)", i, j, flip);
            covered += want;
        }
    cr_expect_eq(covered, 36); /* 8 + 7 + ... + 1 */
    ism_raster_free(&r);
}

Test(thumbnail, raster_covers_the_pixels_whose_centres_are_inside)
{
    check_right_triangle(false);
    check_right_triangle(true);
}

/* A square split along its diagonal, which passes through 8 pixel centres: drawn one at a
 * time, every pixel belongs to exactly one of the two triangles (no gap, no double cover). */
Test(thumbnail, shared_edge_no_gap_no_double_cover)
{
    float a[3][3] = {{0, 0, 5}, {8, 8, 5}, {8, 0, 5}};   /* upper right half */
    float b[3][3] = {{0, 0, 1}, {0, 8, 1}, {8, 8, 1}};   /* lower left half */
    ism_raster ra, rb;
    cr_assert(ism_raster_init(&ra, 8, 8) && ism_raster_init(&rb, 8, 8));
    ism_raster_triangle(&ra, a, GREY);
    ism_raster_triangle(&rb, b, GREY);
    int in_a = 0;
    for (int j = 0; j < 8; j++)
        for (int i = 0; i < 8; i++) {
            bool ca = ism_raster_covered(&ra, i, j), cb = ism_raster_covered(&rb, i, j);
            cr_expect(ca != cb, "pixel %d %d: in a %d, in b %d", i, j, ca, cb);
            if (i != j)
                cr_expect_eq(ca, i > j, "pixel %d %d off the diagonal", i, j);
            in_a += ca;
        }
    cr_expect(in_a == 28 || in_a == 36, "the diagonal split between both: %d", in_a);
    ism_raster_free(&ra);
    ism_raster_free(&rb);
}

Test(thumbnail, nearer_triangle_wins_whatever_the_order)
{
    ism_raster r;
    cr_assert(ism_raster_init(&r, 4, 4));
    const float red[3][3] = {{1, 0, 0}, {1, 0, 0}, {1, 0, 0}};
    const float blue[3][3] = {{0, 0, 1}, {0, 0, 1}, {0, 0, 1}};
    float near[3][3] = {{-1, -1, 1}, {9, -1, 1}, {-1, 9, 1}};
    float far[3][3] = {{-1, -1, 3}, {9, -1, 3}, {-1, 9, 3}};
    ism_raster_triangle(&r, near, red);
    ism_raster_triangle(&r, far, blue);
    cr_expect(r.rgb[0] > .5f && r.rgb[2] < .5f);
    cr_expect_float_eq(r.depth[0], 1.f, 1e-6);
    ism_raster_free(&r);
}

/* Reference bytes. "a": Python's zlib.compressobj(1, DEFLATED, 15, 8, Z_FIXED) gives the same
 * (a literal has one encoding). "aaaaaaaaaa": by hand from RFC 1951's fixed codes — literal
 * 'a' (8 bits), then <length 9: code 263, dist 1: code 0>, end of block — and zlib.decompress
 * of these bytes gives the input back (zlib itself picks two literals and length 8: 11 bytes). */
Test(thumbnail, deflate_matches_zlib_fixed_codes)
{
    static const struct { const char *in; unsigned char out[16]; size_t n; } cases[] = {
        {"a", {0x78, 0x01, 0x4b, 0x04, 0x00, 0x00, 0x62, 0x00, 0x62}, 9},
        {"aaaaaaaaaa", {0x78, 0x01, 0x4b, 0x84, 0x03, 0x00, 0x14, 0xe1, 0x03, 0xcb}, 10},
    };
    for (size_t k = 0; k < 2; k++) {
        unsigned char *z;
        size_t n;
        cr_assert(ism_zlib_compress((const unsigned char *)cases[k].in, strlen(cases[k].in), &z, &n));
        cr_expect_eq(n, cases[k].n, "%s: %zu bytes", cases[k].in, n);
        cr_expect(n == cases[k].n && !memcmp(z, cases[k].out, n), "bytes of '%s'", cases[k].in);
        free(z);
    }
}

static uint32_t be32(const unsigned char *p)
{
    return (uint32_t)p[0] << 24 | (uint32_t)p[1] << 16 | (uint32_t)p[2] << 8 | p[3];
}

/* CRC-32 by the polynomial's definition, bit at a time (independent of png.c's loop form). */
static uint32_t crc_ref(const unsigned char *p, size_t n)
{
    uint32_t c = 0xffffffffu;
    for (size_t i = 0; i < n; i++)
        for (int b = 0; b < 8; b++) {
            uint32_t bit = ((p[i] >> b) & 1u) ^ (c & 1u);
            c >>= 1;
            if (bit)
                c ^= 0xedb88320u;
        }
    return c ^ 0xffffffffu;
}

/* A unit sphere as an octahedron refined 4 times and pushed onto the sphere. */
static void sphere(ism_mesh *m)
{
    ism_mesh_init(m);
    static const double v[6][3] = {{1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}, {0, 0, -1}};
    static const int f[8][3] = {{0, 2, 4}, {2, 1, 4}, {1, 3, 4}, {3, 0, 4},
                                {2, 0, 5}, {1, 2, 5}, {3, 1, 5}, {0, 3, 5}};
    enum { N = 16 }; /* each face cut into N^2 triangles */
    for (int t = 0; t < 8; t++) {
        uint32_t base = (uint32_t)m->nverts;
        for (int i = 0; i <= N; i++)
            for (int j = 0; j <= N - i; j++) {
                double p[3];
                for (int k = 0; k < 3; k++)
                    p[k] = (v[f[t][0]][k] * (N - i - j) + v[f[t][1]][k] * i + v[f[t][2]][k] * j) / N;
                double n = sqrt(p[0] * p[0] + p[1] * p[1] + p[2] * p[2]);
                float nf[3];
                for (int k = 0; k < 3; k++) {
                    p[k] /= n;
                    nf[k] = (float)p[k];
                }
                ism_mesh_add_vertex(m, p, nf);
            }
        /* index of (i, j): rows of shrinking length */
#define IDX(i, j) (base + (uint32_t)((i) * (N + 1) - (i) * ((i) - 1) / 2 + (j)))
        for (int i = 0; i < N; i++)
            for (int j = 0; j < N - i; j++) {
                ism_mesh_add_triangle(m, IDX(i, j), IDX(i + 1, j), IDX(i, j + 1));
                if (j + 1 < N - i)
                    ism_mesh_add_triangle(m, IDX(i + 1, j), IDX(i + 1, j + 1), IDX(i, j + 1));
            }
#undef IDX
    }
}

Test(thumbnail, png_structure_and_crcs)
{
    ism_mesh m;
    sphere(&m);
    const double box[6] = {-1.5, -1.5, -1.5, 1.5, 1.5, 1.5};
    unsigned char *png;
    size_t len;
    cr_assert(ism_thumbnail_png(&m, box, &png, &len));
    static const unsigned char sig[8] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};
    cr_assert(len > 8 + 25 + 12 + 12);
    cr_expect(!memcmp(png, sig, 8));
    cr_expect(!memcmp(png + 12, "IHDR", 4));
    cr_expect_eq(be32(png + 16), ISM_THUMB_W);
    cr_expect_eq(be32(png + 20), ISM_THUMB_H);
    cr_expect_eq(png[24], 8);
    cr_expect_eq(png[25], 6);
    size_t at = 8;
    int chunks = 0;
    while (at + 12 <= len) {
        uint32_t n = be32(png + at);
        cr_assert(at + 12 + n <= len);
        cr_expect_eq(be32(png + at + 8 + n), crc_ref(png + at + 4, n + 4), "chunk %d", chunks);
        at += 12 + n;
        chunks++;
    }
    cr_expect_eq(at, len);
    cr_expect_eq(chunks, 3);
    cr_expect(!memcmp(png + len - 8, "IEND", 4));
    free(png);
    ism_mesh_free(&m);
}

/* The sphere's picture: the camera's cone holds the bounding sphere of the mesh's bounding
 * box (radius sqrt 3, times the margin) with the 35-degree vertical field of view; the unit
 * sphere seen from distance D = 1.08 sqrt(3) / sin(17.5 deg) subtends an angle asin(1/D), a
 * disc of radius f tan(asin(1/D)) pixels, f = 60 / tan(17.5 deg). Its area over the frame is
 * the foreground share (alpha-weighted), within 3% (the mesh is a polyhedron inside the
 * sphere). The disc is centred and shaded (not one flat colour). */
Test(thumbnail, sphere_is_a_centred_disc_of_the_projected_size)
{
    ism_mesh m;
    sphere(&m);
    const double box[6] = {-1.5, -1.5, -1.5, 1.5, 1.5, 1.5};
    unsigned char *px = ism_thumbnail_rgba(&m, box, ISM_THUMB_W, ISM_THUMB_H);
    cr_assert_not_null(px);
    double half = 17.5 * M_PI / 180, D = 1.08 * sqrt(3) / sin(half);
    double radius = (ISM_THUMB_H / 2.0) / tan(half) * tan(asin(1 / D));
    double want = M_PI * radius * radius, got = 0, mx = 0, my = 0;
    int lo = 255, hi = 0;
    for (int y = 0; y < ISM_THUMB_H; y++)
        for (int x = 0; x < ISM_THUMB_W; x++) {
            const unsigned char *p = px + 4 * (y * ISM_THUMB_W + x);
            double a = p[3] / 255.0;
            got += a;
            mx += a * (x + .5);
            my += a * (y + .5);
            if (p[3] == 255) {
                lo = p[0] < lo ? p[0] : lo;
                hi = p[0] > hi ? p[0] : hi;
            }
        }
    cr_expect(fabs(got - want) < 0.03 * want, "area %g px, projected sphere %g", got, want);
    cr_expect(fabs(mx / got - ISM_THUMB_W / 2.0) < 0.5 && fabs(my / got - ISM_THUMB_H / 2.0) < 0.5,
              "centroid %g %g", mx / got, my / got);
    cr_expect(hi - lo > 60, "shading range %d..%d", lo, hi);
    free(px);
    ism_mesh_free(&m);
}
