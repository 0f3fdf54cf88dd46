/* vec3.h — the small vector helpers on double[3] that the polygoniser, the singular locus
 * and the curves share (dot product, length, normalising, distance), inline, each written
 * once (the same arithmetic, in the same order, wherever it is used). */
#ifndef ISM_VEC3_H
#define ISM_VEC3_H

#include <math.h>

static inline double ism_dot3(const double a[3], const double b[3])
{
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}

static inline double ism_norm3(const double a[3]) { return sqrt(ism_dot3(a, a)); }

/* Normalises a in place; returns its former length (a is left unchanged when it is 0). */
static inline double ism_normalise3(double a[3])
{
    double n = ism_norm3(a);
    if (n > 0 && isfinite(n))
        for (int k = 0; k < 3; k++)
            a[k] /= n;
    return n;
}

/* The squared distance |a − b|². */
static inline double ism_sqdist3(const double a[3], const double b[3])
{
    double d[3] = {a[0] - b[0], a[1] - b[1], a[2] - b[2]};
    return ism_dot3(d, d);
}

static inline double ism_dist3(const double a[3], const double b[3])
{
    return sqrt(ism_sqdist3(a, b));
}

/* The squared distance from p to the segment a–b (to a when a = b). */
static inline double ism_sqdist_segment3(const double p[3], const double a[3], const double b[3])
{
    double ab[3], ap[3], t = 0, l2 = 0;
    for (int k = 0; k < 3; k++) {
        ab[k] = b[k] - a[k];
        ap[k] = p[k] - a[k];
        l2 += ab[k] * ab[k];
        t += ab[k] * ap[k];
    }
    t = l2 > 0 ? fmin(1.0, fmax(0.0, t / l2)) : 0.0;
    double d2 = 0;
    for (int k = 0; k < 3; k++) {
        double d = ap[k] - t * ab[k];
        d2 += d * d;
    }
    return d2;
}

#endif
