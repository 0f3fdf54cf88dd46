/* krawczyk.h — the Krawczyk test for ∇f = 0 on a box X with centre c:
 *
 *     K(X) = c − Y ∇f(c) + (I − Y H(X)) (X − c),   Y ≈ mid(H(X))⁻¹
 *
 * Every zero of ∇f in X lies in K(X); so K ∩ X = ∅ proves there is none, and K ⊂ int X
 * proves there is exactly one (and that every Hessian in H(X) is non-singular). All
 * arithmetic is outward rounded; Y is any real matrix (only its quality matters). */
#ifndef ISM_SING_KRAWCZYK_H
#define ISM_SING_KRAWCZYK_H

#include "core/eval/eval.h"

enum ism_krawczyk_answer {
    ISM_KRAWCZYK_UNKNOWN = 0, /* neither: subdivide, or a degenerate zero */
    ISM_KRAWCZYK_UNIQUE = 1,  /* exactly one zero of ∇f in X, inside K */
    ISM_KRAWCZYK_EMPTY = 2,   /* no zero of ∇f in X */
};

/* x: the box; c: a point of it; gc: an enclosure of ∇f(c); h: an enclosure of the Hessian
 * over x (xx xy xz yy yz zz). Writes K (may be NULL). */
int ism_krawczyk(const ism_interval x[3], const double c[3], const ism_interval gc[3],
                 const ism_interval h[6], ism_interval k[3]);

/* The same test for a 2-D system G(a, b) = 0 on the square [−r, r]² centred on (0, 0): gc an
 * enclosure of G(0, 0), j an enclosure of its (symmetric) Jacobian over the square (aa ab
 * bb), Y the inverse of j's midpoint. Used on the normal-plane gradient of a singular curve
 * (curve_cert.h). */
int ism_krawczyk2(double r, const ism_interval gc[2], const ism_interval j[3]);

#endif
