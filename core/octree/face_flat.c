/* face_flat.c — polygons lying in a node's face (see face_flat.h): which face, and the
 * surface point above their centroid on the node's side. */
#include "core/octree/face_flat.h"
#include "core/octree/edge_roots.h"

#include <math.h>
#include <string.h>

/* Samples of f on the way from the centroid across the node: the first sign change is
 * bracketed within 1/LIFT_SAMPLES of the node, and regula falsi takes it from there. A
 * piece thinner than the node is caught by the first sample already. */
#define LIFT_SAMPLES 8

static bool on_plane(const double node[6], int face, const double p[3])
{
    int axis = face / 2;
    return p[axis] == node[3 * (face % 2) + axis];
}

int ism_face_plane(const double node[6], const ism_fpoint *p, size_t n)
{
    for (int face = 0; face < 6 && n > 0; face++) {
        size_t i = 0;
        while (i < n && on_plane(node, face, p[i].p))
            i++;
        if (i == n)
            return face;
    }
    return -1;
}

void ism_face_masks(const double node[6], const ism_fpoint *p, size_t n, uint8_t *mask)
{
    for (size_t i = 0; i < n; i++) {
        const double *q = p[i].p;
        unsigned m = 0; /* on_plane of faces 2a (lower) and 2a + 1 (upper) */
        for (int a = 0; a < 3; a++)
            m |= (unsigned)(q[a] == node[a]) << 2 * a |
                 (unsigned)(q[a] == node[3 + a]) << (2 * a + 1);
        mask[i] = (uint8_t)m;
    }
}

/* The first zero of f on the way from `from` along `axis` to the coordinate `to` (reached
 * exactly), strictly past `from`. */
static bool first_root(ism_sampler *s, const double from[3], int axis, double to,
                       ism_fpoint *out)
{
    double a[3] = {from[0], from[1], from[2]}, start = from[axis];
    double fa = ism_sample_f(s, a);
    if (fa == 0 || !isfinite(fa))
        return false;
    for (int j = 1; j <= LIFT_SAMPLES; j++) {
        double b[3] = {a[0], a[1], a[2]};
        b[axis] = j == LIFT_SAMPLES ? to : start + (to - start) * j / LIFT_SAMPLES;
        double fb = ism_sample_f(s, b);
        if (!isfinite(fb))
            return false;
        if (fb == 0 || (fb < 0) != (fa < 0)) {
            double t = fb == 0 ? 1 : ism_regula_falsi(s, a, b, fa, fb);
            for (int k = 0; k < 3; k++)
                out->p[k] = a[k] + t * (b[k] - a[k]);
            out->p[axis] = a[axis] + t * (b[axis] - a[axis]);
            if (out->p[axis] == start)
                return false; /* no height: nothing to lift */
            ism_sample_grad(s, out->p, out->g);
            return true;
        }
        memcpy(a, b, sizeof a);
        fa = fb;
    }
    return false;
}

bool ism_lift_point(ism_sampler *s, const ism_fpoint *p, size_t n, const double node[6],
                    int face, ism_fpoint *top)
{
    int axis = face / 2;
    double c[3] = {0, 0, 0};
    for (size_t i = 0; i < n; i++)
        for (int k = 0; k < 3; k++)
            c[k] += p[i].p[k] / (double)n;
    c[axis] = node[3 * (face % 2) + axis]; /* exactly on the face */
    if (!first_root(s, c, axis, node[3 * (1 - face % 2) + axis], top))
        return false;
    top->flags = ISM_FP_INTERIOR;
    return true;
}

bool ism_lift_chord(ism_sampler *s, const ism_fpoint *a, const ism_fpoint *b, int axis,
                    double to, ism_fpoint *mid)
{
    double c[3];
    for (int k = 0; k < 3; k++)
        c[k] = 0.5 * (a->p[k] + b->p[k]);
    c[axis] = a->p[axis]; /* exactly on the tile's side */
    if (!first_root(s, c, axis, to, mid))
        return false;
    mid->flags = 0;
    return true;
}
