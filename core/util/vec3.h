/* vec3.h — the small vector helpers on double[3] that the polygoniser, the singular locus,
 * the curves and the analysis share (dot and cross products, length, normalising, distance,
 * a triangle's normal and area, the distance to a box, a box's diagonal, frames across a
 * direction, the Fibonacci sphere's directions), inline, each written once (the same arithmetic, in the same
 * order, wherever it is used). */
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

/* The diagonal of a box [lo x, lo y, lo z, hi x, hi y, hi z]: the scale of max_error's default
 * and limits (proto/request.c), of the curves' and the locus check's tolerances. */
static inline double ism_box_diagonal(const double box[6]) { return ism_dist3(box, box + 3); }

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

/* c = a × b (c is neither a nor b). */
static inline void ism_cross3(const double a[3], const double b[3], double c[3])
{
    c[0] = a[1] * b[2] - a[2] * b[1];
    c[1] = a[2] * b[0] - a[0] * b[2];
    c[2] = a[0] * b[1] - a[1] * b[0];
}

/* n = (b − a) × (c − a): triangle a b c's normal as it is wound (right hand), twice its area
 * long (n is none of a, b, c). */
static inline void ism_tri_cross3(const double a[3], const double b[3], const double c[3],
                                  double n[3])
{
    double u[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]};
    double w[3] = {c[0] - a[0], c[1] - a[1], c[2] - a[2]};
    ism_cross3(u, w, n);
}

/* The area of triangle a b c, |(b − a) × (c − a)| / 2. */
static inline double ism_tri_area3(const double a[3], const double b[3], const double c[3])
{
    double n[3];
    ism_tri_cross3(a, b, c, n);
    return 0.5 * ism_norm3(n);
}

/* The squared distance from p to the closed box lo..hi (lo ≤ hi), 0 inside: per axis the
 * larger of lo − p and p − hi when positive. Comparisons, not libm's fmax: a node test asks it
 * of every ball (dual_balls.c: fmax calls were 166M instructions of Barth's 5.0G run); for
 * finite input the same value as any other order of those maxima. */
static inline double ism_sqdist_box3(const double p[3], const double lo[3], const double hi[3])
{
    double d2 = 0;
    for (int a = 0; a < 3; a++) {
        double below = lo[a] - p[a], above = p[a] - hi[a];
        double e = below > above ? below : above;
        e = e > 0 ? e : 0;
        d2 += e * e;
    }
    return d2;
}

/* Two unit directions across the unit vector u, (u, e[0], e[1]) orthonormal and right-handed:
 * e[0] is the x axis made normal to u — the y axis when u is within 53° of x (|u_x| ≥ 0.6,
 * then |u_y| ≤ 0.8: the axis kept is never nearer than 37° to u) — and e[1] = u × e[0]. */
static inline void ism_across3(const double u[3], double e[2][3])
{
    double w[3] = {fabs(u[0]) < 0.6 ? 1 : 0, fabs(u[0]) < 0.6 ? 0 : 1, 0};
    double c = ism_dot3(w, u);
    for (int a = 0; a < 3; a++)
        e[0][a] = w[a] - c * u[a];
    ism_normalise3(e[0]);
    ism_cross3(u, e[0], e[1]);
}

/* The same by another construction: e[0] = u × a / |u × a| with a the coordinate axis least
 * along u (the first of equals), e[1] = u × e[0]; (e[0], e[1], u) right-handed. Its frame is
 * not ism_across3's, and what its callers compute in it (the triangulation's plane, the
 * tangential Hessian, a singular curve's normal plane) is the same to the last bit only in
 * the frame they have always had. */
static inline void ism_across_least3(const double u[3], double e[2][3])
{
    int a = 0;
    for (int k = 1; k < 3; k++)
        if (fabs(u[k]) < fabs(u[a]))
            a = k;
    double axis[3] = {0, 0, 0};
    axis[a] = 1;
    ism_cross3(u, axis, e[0]);
    ism_normalise3(e[0]);
    ism_cross3(u, e[0], e[1]);
}

/* The golden angle π(3 − √5): the Fibonacci sphere's turn from one point to the next. */
#define ISM_GOLDEN_ANGLE 2.39996322972865332

/* Direction i (0 ≤ i < n) of the Fibonacci sphere: heights z = 1 − (2i + 1)/n evenly spaced,
 * each turned by the golden angle from the last; the n directions spread evenly over the unit
 * sphere, about √(4π / n) apart. */
static inline void ism_fibonacci_dir(int i, int n, double v[3])
{
    double z = 1 - (2 * i + 1.0) / n, rho = sqrt(1 - z * z);
    v[0] = rho * cos(i * ISM_GOLDEN_ANGLE);
    v[1] = rho * sin(i * ISM_GOLDEN_ANGLE);
    v[2] = z;
}

#endif
