/* lanes4.h — four doubles as one value of GCC's vector extension, for the evaluators'
 * always-inline steps: one AVX2 register in a function compiled for AVX2, a pair of SSE2 ones
 * in the x86-64 baseline; element by element the same IEEE operations as scalar code, so a
 * lane's bits are the scalar code's. Loads and stores through memcpy (no alignment or aliasing
 * assumption).
 *
 * Rule for includers: a v4d is passed and returned only between INLINE (always-inline)
 * helpers, never across a real call, so the AVX calling convention GCC warns about (-Wpsabi:
 * "the ABI for passing parameters with 32-byte alignment has changed") never applies; the
 * warning is off for every file that includes this header. */
#ifndef ISM_LANES4_H
#define ISM_LANES4_H

#pragma GCC diagnostic ignored "-Wpsabi"

#include <math.h>
#if defined(__x86_64__)
#include <emmintrin.h>
#endif

/* The evaluators' helpers: inlined into each caller, so that one compiled for AVX2 keeps its
 * v4d values in AVX2 registers. */
#define INLINE static inline __attribute__((always_inline))

typedef double v4d __attribute__((vector_size(4 * sizeof(double))));
typedef long long v4i __attribute__((vector_size(4 * sizeof(double))));

INLINE v4d v4_ld(const double *p)
{
    v4d v;
    __builtin_memcpy(&v, p, sizeof v);
    return v;
}

INLINE void v4_st(double *p, v4d v)
{
    __builtin_memcpy(p, &v, sizeof v);
}

/* a where m is set, else b (m's lanes all ones or all zeros, as a comparison gives) */
INLINE v4d v4_pick(v4i m, v4d a, v4d b)
{
    return (v4d)(((v4i)a & m) | ((v4i)b & ~m));
}

/* |x| lane by lane: the sign bit cleared, as fabs does (NaN stays NaN) */
INLINE v4d v4_abs(v4d x)
{
    const long long mag = 0x7fffffffffffffffLL;
    return (v4d)((v4i)x & (v4i){ mag, mag, mag, mag });
}

/* sqrt lane by lane, correctly rounded as sqrt is: SSE2's sqrtpd on each half on x86-64,
 * which takes no errno path (a negative lane gives NaN, as sqrt's value does). */
INLINE v4d v4_sqrt(v4d x)
{
#if defined(__x86_64__)
    __m128d lo = _mm_sqrt_pd((__m128d){ x[0], x[1] }), hi = _mm_sqrt_pd((__m128d){ x[2], x[3] });
    return (v4d){ lo[0], lo[1], hi[0], hi[1] };
#else
    return (v4d){ sqrt(x[0]), sqrt(x[1]), sqrt(x[2]), sqrt(x[3]) };
#endif
}

/* c where m is set, else +0.0 (all-zero bits) */
INLINE v4d v4_keep(v4d c, v4i m)
{
    return (v4d)((v4i)c & m);
}

/* The chain rule's partial g' a', +0 where g' is 0 (±0) even where a' is not finite: the one
 * rule of the gradient evaluators, one point (eval_gradient.c's dual_chain) and batched
 * (eval_gradient_batch.c's k_chain), which must agree bit for bit. A NaN g' passes through
 * (NaN != 0). */
INLINE v4d v4_chain(v4d g1, v4d a)
{
    return v4_keep(g1 * a, (v4i)(g1 != 0.0));
}

#endif
