/* thumbnail.c — the picture of thumbnail.h: a perspective camera on the viewer's default
 * direction whose cone holds the mesh's bounding sphere, per-vertex Lambert shading (a
 * headlight plus ambient), faces turned away from the eye in the inside tint, drawn at
 * SUPERSAMPLE x the size by raster.h and averaged down (anti-aliased edges, partial alpha). */
#include "proto/thumbnail.h"
#include "core/util/vec3.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "proto/png.h"
#include "proto/raster.h"

#define SUPERSAMPLE 3            /* samples per pixel side: smooth silhouettes at 160 px */
#define MAX_SIDE 1024            /* bounded memory: (1024 * 3)^2 samples * 16 B = 150 MB */
#define FOV_DEG 35.0             /* the viewer's camera (web/js/viewer.js) */
#define MARGIN 1.08              /* the bounding sphere fills this much less than the view */
#define AMBIENT 0.38             /* the viewer's hemisphere light, roughly */
#define DIFFUSE 0.72             /* the headlight */

/* The viewer's colours (web/js/viewer.js): SURFACE_RGB 0xb9c6d8 and INSIDE_TINT. */
static const float SURFACE[3] = {0xb9 / 255.f, 0xc6 / 255.f, 0xd8 / 255.f};
static const float INSIDE_TINT[3] = {1.12f, 0.82f, 0.55f};
/* The viewer's DEFAULT_DIRECTION (eye from target), and its headlight in camera space. */
static const double VIEW_DIR[3] = {1.5, -2.1, 1.25};
static const double HEADLIGHT[3] = {0.35, 0.55, 1};

typedef struct camera {
    double eye[3], right[3], up[3], back[3]; /* back: from the target toward the eye */
    double focal;                            /* pixels per unit of x/z */
    double cx, cy;
    double light[3];                         /* toward the light, world */
} camera;

static double dot(const double *a, const double *b)
{
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}

static void normalise(double *v)
{
    double n = sqrt(dot(v, v));
    for (int k = 0; k < 3; k++)
        v[k] = n > 0 ? v[k] / n : 0;
}

/* The bounding box of the vertices used by triangles (box when there are none). */
static void bounds(const ism_mesh *m, const double box[6], double lo[3], double hi[3])
{
    for (int k = 0; k < 3; k++) {
        lo[k] = INFINITY;
        hi[k] = -INFINITY;
    }
    for (size_t t = 0; t < 3 * m->ntris; t++) {
        const double *p = m->pos + 3 * (size_t)m->tri[t];
        for (int k = 0; k < 3; k++) {
            lo[k] = fmin(lo[k], p[k]);
            hi[k] = fmax(hi[k], p[k]);
        }
    }
    if (!m->ntris)
        for (int k = 0; k < 3; k++) {
            lo[k] = box[k];
            hi[k] = box[k + 3];
        }
}

static void camera_fit(const ism_mesh *m, const double box[6], int w, int h, camera *c)
{
    double lo[3], hi[3], centre[3], radius = 0;
    bounds(m, box, lo, hi);
    for (int k = 0; k < 3; k++) {
        centre[k] = (lo[k] + hi[k]) / 2;
        radius += (hi[k] - lo[k]) * (hi[k] - lo[k]) / 4;
    }
    radius = sqrt(radius) * MARGIN;
    if (!(radius > 0))
        radius = 1;
    double half_v = FOV_DEG * M_PI / 360, half_h = atan(tan(half_v) * w / h);
    double dist = radius / sin(fmin(half_v, half_h));
    memcpy(c->back, VIEW_DIR, sizeof c->back);
    normalise(c->back);
    static const double z_up[3] = {0, 0, 1};
    ism_cross3(z_up, c->back, c->right);
    normalise(c->right);
    ism_cross3(c->back, c->right, c->up);
    for (int k = 0; k < 3; k++) {
        c->eye[k] = centre[k] + dist * c->back[k];
        c->light[k] = HEADLIGHT[0] * c->right[k] + HEADLIGHT[1] * c->up[k] + HEADLIGHT[2] * c->back[k];
    }
    normalise(c->light);
    c->focal = (h / 2.0) / tan(half_v);
    c->cx = w / 2.0;
    c->cy = h / 2.0;
}

/* Pixel x, y and depth of world point p. */
static void project(const camera *c, const double *p, float out[3])
{
    double d[3] = {p[0] - c->eye[0], p[1] - c->eye[1], p[2] - c->eye[2]};
    double z = -dot(d, c->back); /* distance in front of the eye */
    if (z < 1e-9)
        z = 1e-9;
    out[0] = (float)(c->cx + c->focal * dot(d, c->right) / z);
    out[1] = (float)(c->cy - c->focal * dot(d, c->up) / z);
    out[2] = (float)z;
}

/* Corner colour: the vertex normal (the face's where it has none) turned to the eye's side,
 * Lambert-lit; inside (facing away from the eye) tinted. */
static void shade(const camera *c, const ism_mesh *m, uint32_t v, const double *face_n,
                  bool inside, float out[3])
{
    double n[3];
    const float *vn = m->normal ? m->normal + 3 * (size_t)v : NULL;
    if (vn && (vn[0] != 0 || vn[1] != 0 || vn[2] != 0))
        for (int k = 0; k < 3; k++)
            n[k] = vn[k];
    else
        memcpy(n, face_n, sizeof n);
    if (inside)
        for (int k = 0; k < 3; k++)
            n[k] = -n[k];
    double lambert = fmax(0, dot(n, c->light));
    float lit = (float)(AMBIENT + DIFFUSE * lambert);
    for (int k = 0; k < 3; k++) {
        float v3 = SURFACE[k] * lit * (inside ? INSIDE_TINT[k] : 1);
        out[k] = v3 > 1 ? 1 : v3;
    }
}

static void draw_triangle(ism_raster *r, const camera *c, const ism_mesh *m, size_t t)
{
    const uint32_t *tv = m->tri + 3 * t;
    const double *a = m->pos + 3 * (size_t)tv[0], *b = m->pos + 3 * (size_t)tv[1],
                 *d = m->pos + 3 * (size_t)tv[2];
    double e1[3], e2[3], n[3], to_eye[3];
    for (int k = 0; k < 3; k++) {
        e1[k] = b[k] - a[k];
        e2[k] = d[k] - a[k];
        to_eye[k] = c->eye[k] - a[k];
    }
    ism_cross3(e1, e2, n);
    normalise(n);
    bool inside = dot(n, to_eye) < 0; /* the eye sees the side grad f points away from */
    float p[3][3], col[3][3];
    for (int k = 0; k < 3; k++) {
        project(c, m->pos + 3 * (size_t)tv[k], p[k]);
        shade(c, m, tv[k], n, inside, col[k]);
    }
    ism_raster_triangle(r, p, col);
}

/* Averages s x s samples into each RGBA pixel: alpha the covered share, colour their mean. */
static void downsample(const ism_raster *r, int s, int w, int h, unsigned char *rgba)
{
    for (int y = 0; y < h; y++)
        for (int x = 0; x < w; x++) {
            float sum[3] = {0, 0, 0};
            int hits = 0;
            for (int j = 0; j < s; j++)
                for (int i = 0; i < s; i++) {
                    long q = (long)(y * s + j) * r->w + (x * s + i);
                    if (!ism_raster_covered(r, x * s + i, y * s + j))
                        continue;
                    hits++;
                    for (int k = 0; k < 3; k++)
                        sum[k] += r->rgb[3 * q + k];
                }
            unsigned char *o = rgba + 4 * ((size_t)y * (size_t)w + (size_t)x);
            for (int k = 0; k < 3; k++)
                o[k] = hits ? (unsigned char)lrintf(255 * sum[k] / (float)hits) : 0;
            o[3] = (unsigned char)lrintf(255.f * (float)hits / (float)(s * s));
        }
}

unsigned char *ism_thumbnail_rgba(const ism_mesh *m, const double box[6], int w, int h)
{
    if (w < 1 || h < 1 || w > MAX_SIDE || h > MAX_SIDE)
        return NULL;
    int s = SUPERSAMPLE;
    ism_raster r;
    unsigned char *rgba = malloc(4 * (size_t)w * (size_t)h);
    if (!rgba || !ism_raster_init(&r, w * s, h * s)) {
        free(rgba);
        return NULL;
    }
    camera c;
    camera_fit(m, box, w * s, h * s, &c);
    for (size_t t = 0; t < m->ntris; t++)
        draw_triangle(&r, &c, m, t);
    downsample(&r, s, w, h, rgba);
    ism_raster_free(&r);
    return rgba;
}

bool ism_thumbnail_png(const ism_mesh *m, const double box[6], unsigned char **png, size_t *len)
{
    unsigned char *rgba = ism_thumbnail_rgba(m, box, ISM_THUMB_W, ISM_THUMB_H);
    bool ok = rgba && ism_png_rgba(rgba, ISM_THUMB_W, ISM_THUMB_H, png, len);
    free(rgba);
    return ok;
}
