/* select.c — the k-th smallest of an array in expected linear time (quickselect with a
 * median-of-three pivot and a three-way partition, so runs of equal values cost nothing),
 * for medians of angles and gradient norms. Deterministic: no random pivots. Callers pass
 * finite values only. */
#include "core/analysis/select.h"

#define DEFINE_SELECT(name, T)                                                  \
    T name(T *v, size_t n, size_t k)                                            \
    {                                                                           \
        size_t lo = 0, hi = n - 1;                                              \
        while (lo < hi) {                                                       \
            T a = v[lo], b = v[lo + (hi - lo) / 2], c = v[hi];                  \
            T pivot = a < b ? (b < c ? b : (a < c ? c : a))                     \
                            : (a < c ? a : (b < c ? c : b));                    \
            size_t lt = lo, i = lo, gt = hi;                                    \
            while (i <= gt) {                                                   \
                T x = v[i];                                                     \
                if (x < pivot) {                                                \
                    v[i++] = v[lt];                                             \
                    v[lt++] = x;                                                \
                } else if (x > pivot) {                                         \
                    v[i] = v[gt];                                               \
                    v[gt--] = x;                                                \
                } else {                                                        \
                    i++;                                                        \
                }                                                               \
            }                                                                   \
            if (k < lt)                                                         \
                hi = lt - 1;                                                    \
            else if (k > gt)                                                    \
                lo = gt + 1;                                                    \
            else                                                                \
                return pivot;                                                   \
        }                                                                       \
        return v[k];                                                            \
    }

DEFINE_SELECT(ism_an_select_double, double)
DEFINE_SELECT(ism_an_select_float, float)
