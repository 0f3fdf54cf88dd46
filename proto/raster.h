/* raster.h — a small software rasteriser for thumbnails: triangles in pixel coordinates with
 * a depth each corner, filled with a z-buffer and colours interpolated across (Gouraud). */
#ifndef ISM_RASTER_H
#define ISM_RASTER_H

#include <stdbool.h>

typedef struct ism_raster {
    int w, h;
    float *depth;   /* w*h, +inf where nothing was drawn */
    float *rgb;     /* 3 per pixel, in [0, 1] */
} ism_raster;

/* A w x h raster, all empty. False when out of memory (or w, h < 1). */
bool ism_raster_init(ism_raster *r, int w, int h);
void ism_raster_free(ism_raster *r);

/* Draws the triangle with corners p[k] = (x, y, depth) in pixels (x right, y down; pixel
 * (i, j) covers [i, i+1) x [j, j+1), its sample at the centre) and colours c[k]: every pixel
 * whose centre lies inside (either winding; centres on an edge count for one of the two
 * triangles sharing it) and whose depth is below what is there gets the interpolated depth
 * and colour. */
void ism_raster_triangle(ism_raster *r, const float p[3][3], const float c[3][3]);

/* Whether pixel (i, j) was drawn. */
bool ism_raster_covered(const ism_raster *r, int i, int j);

#endif
