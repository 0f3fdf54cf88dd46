/* raster.c — the rasteriser of raster.h: edge functions over the triangle's bounding box,
 * barycentric interpolation of depth and colour, a top-left rule for shared edges. */
#include "proto/raster.h"

#include <math.h>
#include <stdlib.h>

bool ism_raster_init(ism_raster *r, int w, int h)
{
    r->w = w;
    r->h = h;
    r->depth = w > 0 && h > 0 ? malloc(sizeof *r->depth * (size_t)w * (size_t)h) : NULL;
    r->rgb = r->depth ? calloc((size_t)w * (size_t)h * 3, sizeof *r->rgb) : NULL;
    if (!r->rgb) {
        free(r->depth);
        r->depth = NULL;
        return false;
    }
    for (long i = 0; i < (long)w * h; i++)
        r->depth[i] = INFINITY;
    return true;
}

void ism_raster_free(ism_raster *r)
{
    free(r->depth);
    free(r->rgb);
    r->depth = r->rgb = NULL;
}

bool ism_raster_covered(const ism_raster *r, int i, int j)
{
    return i >= 0 && j >= 0 && i < r->w && j < r->h && isfinite(r->depth[(long)j * r->w + i]);
}

/* Twice the signed area of (a, b, q): positive when q is left of a->b (y down). */
static double edge(const float *a, const float *b, double qx, double qy)
{
    return ((double)b[0] - a[0]) * (qy - a[1]) - ((double)b[1] - a[1]) * (qx - a[0]);
}

/* Top-left rule, for a counter-clockwise (positive-area) triangle: a centre exactly on an
 * edge belongs to the triangle when the edge is a top or a left one. */
static bool owns_edge(const float *a, const float *b)
{
    double dx = (double)b[0] - a[0], dy = (double)b[1] - a[1];
    return dy < 0 || (dy == 0 && dx > 0);
}

static int clampi(double v, int lo, int hi)
{
    return v < lo ? lo : v > hi ? hi : (int)v;
}

void ism_raster_triangle(ism_raster *r, const float p[3][3], const float c[3][3])
{
    double area = edge(p[0], p[1], p[2][0], p[2][1]);
    if (!(fabs(area) > 0))
        return; /* degenerate or not finite */
    int o[3] = {0, 1, 2};
    if (area < 0) { /* the other winding: swap two corners */
        o[1] = 2;
        o[2] = 1;
        area = -area;
    }
    const float *a = p[o[0]], *b = p[o[1]], *d = p[o[2]];
    double lo_x = fmin(a[0], fmin(b[0], d[0])), hi_x = fmax(a[0], fmax(b[0], d[0]));
    double lo_y = fmin(a[1], fmin(b[1], d[1])), hi_y = fmax(a[1], fmax(b[1], d[1]));
    int x0 = clampi(floor(lo_x - 0.5), 0, r->w - 1), x1 = clampi(ceil(hi_x - 0.5), 0, r->w - 1);
    int y0 = clampi(floor(lo_y - 0.5), 0, r->h - 1), y1 = clampi(ceil(hi_y - 0.5), 0, r->h - 1);
    bool own0 = owns_edge(b, d), own1 = owns_edge(d, a), own2 = owns_edge(a, b);
    for (int y = y0; y <= y1; y++)
        for (int x = x0; x <= x1; x++) {
            double qx = x + 0.5, qy = y + 0.5;
            double w0 = edge(b, d, qx, qy), w1 = edge(d, a, qx, qy), w2 = edge(a, b, qx, qy);
            if (w0 < 0 || w1 < 0 || w2 < 0 || (w0 == 0 && !own0) || (w1 == 0 && !own1) ||
                (w2 == 0 && !own2))
                continue;
            w0 /= area;
            w1 /= area;
            w2 /= area;
            float z = (float)(w0 * a[2] + w1 * b[2] + w2 * d[2]);
            long i = (long)y * r->w + x;
            if (!(z < r->depth[i]))
                continue;
            r->depth[i] = z;
            for (int k = 0; k < 3; k++)
                r->rgb[3 * i + k] =
                    (float)(w0 * c[o[0]][k] + w1 * c[o[1]][k] + w2 * c[o[2]][k]);
        }
}
