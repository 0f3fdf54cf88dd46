/* quality.c — the shape of the triangles (Farin: "the larger the smallest angle, the better
 * the triangle"): each triangle's smallest angle, their minimum, median, histogram and the
 * share under 10 degrees; their aspect ratios; degenerate triangles; and the area around each vertex (one third
 * of its triangles' areas), the weights of ∫K dA. The triangles are measured on a pool's
 * threads; what adds them up runs in triangle order after, so the figures are the same on
 * any number of threads. */
#include "core/analysis/quality.h"
#include "core/analysis/blocks.h"
#include "core/analysis/edges.h"
#include "core/analysis/select.h"
#include "core/util/parallel.h"
#include "core/util/vec3.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#define DEGENERATE_REL 1e-12
#define RAD_TO_DEG (180.0 / 3.14159265358979323846)

static void sub3(const double *a, const double *b, double *out)
{
    out[0] = a[0] - b[0];
    out[1] = a[1] - b[1];
    out[2] = a[2] - b[2];
}

static double cross_norm(const double *a, const double *b)
{
    double c[3];
    ism_cross3(a, b, c);
    return ism_norm3(c);
}

/* Twice the area of triangle t; *angle its smallest angle in degrees (the one opposite the
 * shortest side), or -1 when the triangle is degenerate; *aspect its aspect ratio. */
static double measure_triangle(const ism_mesh *m, size_t t, double *angle, double *aspect)
{
    const uint32_t *c = m->tri + 3 * t;
    *angle = -1;
    if (ism_an_tri_collapsed(m->tri, t))
        return 0;
    const double *p[3] = {m->pos + 3 * c[0], m->pos + 3 * c[1], m->pos + 3 * c[2]};
    double side[3][3], len2[3];
    for (int k = 0; k < 3; k++) { /* side k is opposite corner k */
        sub3(p[(k + 2) % 3], p[(k + 1) % 3], side[k]);
        len2[k] = ism_dot3(side[k], side[k]);
    }
    double twice_area = cross_norm(side[1], side[2]);
    int shortest = 0, longest = 0;
    for (int k = 1; k < 3; k++) {
        if (len2[k] < len2[shortest])
            shortest = k;
        if (len2[k] > len2[longest])
            longest = k;
    }
    if (!(twice_area > DEGENERATE_REL * len2[longest]))
        return twice_area;
    /* the angle at the corner opposite the shortest side, between the corner's two sides */
    double u[3], w[3];
    sub3(p[(shortest + 1) % 3], p[shortest], u);
    sub3(p[(shortest + 2) % 3], p[shortest], w);
    *angle = atan2(twice_area, ism_dot3(u, w)) * RAD_TO_DEG;
    double perimeter = sqrt(len2[0]) + sqrt(len2[1]) + sqrt(len2[2]);
    *aspect = sqrt(len2[longest]) * perimeter / (2 * sqrt(3.0) * twice_area);
    return twice_area;
}

static void aspect_statistics(ism_analysis *a, ism_pool *pool, float *aspect, size_t n)
{
    if (n == 0)
        return;
    double sum = 0;
    for (size_t i = 0; i < n; i++) {
        sum += aspect[i];
        a->aspect_max = fmax(a->aspect_max, aspect[i]);
    }
    a->aspect_mean = sum / (double)n;
    a->aspect_p99 = ism_an_select_float_on(pool, aspect, n, ism_an_p99_rank(n));
}

static void angle_statistics(ism_analysis *a, ism_pool *pool, float *good, size_t ngood)
{
    if (ngood == 0)
        return;
    size_t under_10 = 0;
    for (size_t i = 0; i < ngood; i++) {
        double d = good[i];
        under_10 += d < 10;
        int bin = (int)(d / (90.0 / ISM_ANGLE_BINS));
        a->angle_hist[bin < ISM_ANGLE_BINS ? bin : ISM_ANGLE_BINS - 1]++;
    }
    a->share_under_10 = (double)under_10 / (double)ngood;
    size_t mid = ngood / 2;
    if (ngood % 2 == 1) {
        a->median_angle = ism_an_select_float_on(pool, good, ngood, mid);
    } else {
        float lower;
        double upper = ism_an_select_float_pair_on(pool, good, ngood, mid, &lower);
        a->median_angle = 0.5 * ((double)lower + upper);
    }
}

/* Each triangle's measures, made on the threads: half its area, its smallest angle (-1:
 * degenerate) and its aspect ratio. */
typedef struct measures {
    const ism_mesh *m;
    double *area, *angle;
    float *ratio;
} measures;

static void measure_block(void *ctx, size_t blk, int thread)
{
    (void)thread;
    measures *w = ctx;
    size_t lo = blk * ISM_AN_TRI_BLOCK, hi = ism_block_end(blk, ISM_AN_TRI_BLOCK, w->m->ntris);
    for (size_t t = lo; t < hi; t++) {
        double ratio = 1;
        w->area[t] = 0.5 * measure_triangle(w->m, t, &w->angle[t], &ratio);
        w->ratio[t] = (float)ratio;
    }
}

bool ism_an_triangle_quality(const ism_mesh *m, ism_pool *pool, ism_analysis *a)
{
    size_t nt = m->ntris, nv = m->nverts, room = nt ? nt : 1;
    a->triangle_min_angle = malloc(room * sizeof *a->triangle_min_angle);
    a->vertex_area = calloc(nv ? nv : 1, sizeof *a->vertex_area);
    float *good = malloc(room * sizeof *good);
    float *aspect = malloc(room * sizeof *aspect);
    measures w = {m, malloc(room * sizeof(double)), malloc(room * sizeof(double)),
                  malloc(room * sizeof(float))};
    bool ok = a->triangle_min_angle && a->vertex_area && good && aspect && w.area && w.angle &&
              w.ratio;
    if (ok) {
        ism_pool_for(pool, ism_blocks(nt, ISM_AN_TRI_BLOCK), measure_block, &w, NULL);
        /* the sums in triangle order, as one thread makes them */
        size_t ngood = 0;
        a->min_angle = 0;
        for (size_t t = 0; t < nt; t++) {
            double angle = w.angle[t], area = w.area[t];
            a->area += area;
            if (!ism_an_tri_collapsed(m->tri, t))
                for (int k = 0; k < 3; k++)
                    a->vertex_area[m->tri[3 * t + k]] += area / 3;
            if (angle < 0) {
                a->degenerate_triangles++;
                a->triangle_min_angle[t] = 0;
            } else {
                a->triangle_min_angle[t] = (float)angle;
                if (ngood == 0 || angle < a->min_angle)
                    a->min_angle = angle;
                aspect[ngood] = w.ratio[t];
                good[ngood++] = (float)angle;
            }
        }
        angle_statistics(a, pool, good, ngood);
        aspect_statistics(a, pool, aspect, ngood);
    }
    free(good);
    free(aspect);
    free(w.area);
    free(w.angle);
    free(w.ratio);
    return ok;
}
