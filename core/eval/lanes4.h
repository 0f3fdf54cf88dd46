/* lanes4.h — four doubles as one value of GCC's vector extension, for the gradient
 * evaluators' always-inline steps: one AVX2 register in a function compiled for AVX2, a pair
 * of SSE2 ones in the x86-64 baseline; element by element the same IEEE operations as scalar
 * code, so a lane's bits are the scalar code's. Loads and stores through memcpy (no alignment
 * or aliasing assumption). */
#ifndef ISM_LANES4_H
#define ISM_LANES4_H

#pragma GCC diagnostic ignored "-Wpsabi" /* v4d is only passed between always_inline helpers:
                                             no call ever uses the AVX return convention */
typedef double v4d __attribute__((vector_size(4 * sizeof(double))));
typedef long long v4i __attribute__((vector_size(4 * sizeof(double))));

static inline __attribute__((always_inline)) v4d ld(const double *p)
{
    v4d v;
    __builtin_memcpy(&v, p, sizeof v);
    return v;
}

static inline __attribute__((always_inline)) void st(double *p, v4d v)
{
    __builtin_memcpy(p, &v, sizeof v);
}

#endif
