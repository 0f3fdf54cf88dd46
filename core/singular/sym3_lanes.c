/* sym3_lanes.c — the Jacobi sweeps of ism_sym3_eigen on four matrices at once (sym3_lanes.h).
 * A lane whose sweeps have ended (its off-diagonal part negligible) or whose rotation would
 * find its entry already 0 keeps its values through a mask, as the scalar loop's break and
 * rotate's early return leave them; the other lanes take the scalar operations lane by lane
 * (lanes4.h: the same IEEE operations; sqrt correctly rounded either way). The sort, the
 * non-finite check and the step itself are sym3.c's own, per matrix. Compiled for the x86-64
 * baseline and for AVX2 (avx2_clone.h). */
#include "core/singular/sym3_lanes.h"
#include "core/eval/avx2_clone.h"
#include "core/eval/lanes4.h"
#include "core/util/sym3.h"

#include <math.h>
#include <string.h>

/* sym3.c's rotate on the lanes set in live (and whose a[p][q] is not 0). */
INLINE void rotate4(v4d a[3][3], v4d v[3][3], int p, int q, v4i live)
{
    v4i m = live & (v4i)(a[p][q] != 0.0);
    if (!(m[0] | m[1] | m[2] | m[3]))
        return;
    v4d one = { 1.0, 1.0, 1.0, 1.0 };
    v4d theta = (a[q][q] - a[p][p]) / (2.0 * a[p][q]);
    v4d t = v4_pick((v4i)(theta >= 0.0), one, -one) /
            (v4_abs(theta) + v4_sqrt(theta * theta + 1.0));
    v4d c = 1.0 / v4_sqrt(t * t + 1.0), s = t * c;
    _Pragma("GCC unroll 3") for (int k = 0; k < 3; k++) {
        v4d akp = a[k][p], akq = a[k][q];
        a[k][p] = v4_pick(m, c * akp - s * akq, akp);
        a[k][q] = v4_pick(m, s * akp + c * akq, akq);
    }
    _Pragma("GCC unroll 3") for (int k = 0; k < 3; k++) {
        v4d apk = a[p][k], aqk = a[q][k];
        a[p][k] = v4_pick(m, c * apk - s * aqk, apk);
        a[q][k] = v4_pick(m, s * apk + c * aqk, aqk);
    }
    v4d zero = { 0.0, 0.0, 0.0, 0.0 };
    a[p][q] = v4_pick(m, zero, a[p][q]);
    a[q][p] = v4_pick(m, zero, a[q][p]);
    _Pragma("GCC unroll 3") for (int k = 0; k < 3; k++) {
        v4d vkp = v[k][p], vkq = v[k][q];
        v[k][p] = v4_pick(m, c * vkp - s * vkq, vkp);
        v[k][q] = v4_pick(m, s * vkp + c * vkq, vkq);
    }
}

/* The sweeps of four matrices h[0..4) into as[l], vs[l] (lane l's a and v of ism_sym3_eigen
 * after its loop). */
ISM_AVX2_TWICE(void, sweeps4, (const double (*h)[6], double as[4][3][3], double vs[4][3][3]),
               (h, as, vs),
    v4d a[3][3], v[3][3];
    static const int at[3][3] = { { 0, 1, 2 }, { 1, 3, 4 }, { 2, 4, 5 } };
    for (int i = 0; i < 3; i++)
        for (int j = 0; j < 3; j++) {
            a[i][j] = (v4d){ h[0][at[i][j]], h[1][at[i][j]], h[2][at[i][j]], h[3][at[i][j]] };
            double e = i == j ? 1.0 : 0.0;
            v[i][j] = (v4d){ e, e, e, e };
        }
    v4i live = { -1, -1, -1, -1 };
    for (int sweep = 0; sweep < ISM_SYM3_MAX_SWEEPS; sweep++) {
        v4d off = v4_abs(a[0][1]) + v4_abs(a[0][2]) + v4_abs(a[1][2]);
        v4d diag = v4_abs(a[0][0]) + v4_abs(a[1][1]) + v4_abs(a[2][2]);
        live &= (v4i)(off > ISM_SYM3_OFF_TINY) & ~(v4i)(off <= ISM_SYM3_OFF_REL * diag);
        if (!(live[0] | live[1] | live[2] | live[3]))
            break;
        rotate4(a, v, 0, 1, live);
        rotate4(a, v, 0, 2, live);
        rotate4(a, v, 1, 2, live);
    }
    for (int l = 0; l < 4; l++)
        for (int i = 0; i < 3; i++)
            for (int j = 0; j < 3; j++) {
                as[l][i][j] = a[i][j][l];
                vs[l][i][j] = v[i][j][l];
            }
)

void ism_sym3_pinv_lanes(const double (*g)[3], const double (*h)[6], const double *rel,
                         const double *trust, double (*step)[3], bool *ok, size_t n)
{
    for (size_t b = 0; b < n; b += 4) {
        size_t m = n - b < 4 ? n - b : 4;
        double hb[4][6] = { { 0 } }, as[4][3][3], vs[4][3][3];
        memcpy(hb, h + b, m * sizeof hb[0]); /* missing lanes: the zero matrix, no sweep */
        sweeps4((const double (*)[6])hb, as, vs);
        for (size_t l = 0; l < m; l++) {
            double eig[3], vec[3][3];
            ism_sym3_sorted(h[b + l], (const double (*)[3])as[l], (const double (*)[3])vs[l],
                            eig, vec);
            ok[b + l] = ism_sym3_pinv_of(g[b + l], eig, (const double (*)[3])vec, rel[b + l],
                                         trust[b + l], step[b + l]);
        }
    }
}
