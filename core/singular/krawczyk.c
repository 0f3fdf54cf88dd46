/* krawczyk.c — the Krawczyk operator on ∇f (krawczyk.h), with the preconditioner Y the
 * inverse of the Hessian enclosure's midpoint by cofactors; and its 2-D form on a square. */
#include "core/singular/krawczyk.h"
#include "core/eval/interval_ops.h"

#include <stdbool.h>

/* Index of entry (i, j) of a symmetric 3×3 matrix in xx xy xz yy yz zz order. */
static inline int sym(int i, int j)
{
    static const int idx[3][3] = { { 0, 1, 2 }, { 1, 3, 4 }, { 2, 4, 5 } };
    return idx[i][j];
}

/* Y = mid(h)⁻¹; false when the midpoint is not finite or singular. */
static bool mid_inverse(const ism_interval h[6], double y[3][3])
{
    double m[3][3];
    for (int i = 0; i < 3; i++)
        for (int j = 0; j < 3; j++) {
            ism_interval e = h[sym(i, j)];
            m[i][j] = 0.5 * e.lo + 0.5 * e.hi;
            if (!isfinite(m[i][j]))
                return false;
        }
    double c00 = m[1][1] * m[2][2] - m[1][2] * m[2][1];
    double c01 = m[1][2] * m[2][0] - m[1][0] * m[2][2];
    double c02 = m[1][0] * m[2][1] - m[1][1] * m[2][0];
    double det = m[0][0] * c00 + m[0][1] * c01 + m[0][2] * c02;
    if (!(det != 0.0) || !isfinite(det))
        return false;
    double inv = 1.0 / det;
    y[0][0] = c00 * inv;
    y[1][0] = c01 * inv;
    y[2][0] = c02 * inv;
    y[0][1] = (m[0][2] * m[2][1] - m[0][1] * m[2][2]) * inv;
    y[1][1] = (m[0][0] * m[2][2] - m[0][2] * m[2][0]) * inv;
    y[2][1] = (m[0][1] * m[2][0] - m[0][0] * m[2][1]) * inv;
    y[0][2] = (m[0][1] * m[1][2] - m[0][2] * m[1][1]) * inv;
    y[1][2] = (m[0][2] * m[1][0] - m[0][0] * m[1][2]) * inv;
    y[2][2] = (m[0][0] * m[1][1] - m[0][1] * m[1][0]) * inv;
    for (int i = 0; i < 3; i++)
        for (int j = 0; j < 3; j++)
            if (!isfinite(y[i][j]))
                return false;
    return true;
}

int ism_krawczyk(const ism_interval x[3], const double c[3], const ism_interval gc[3],
                 const ism_interval h[6], ism_interval k[3])
{
    double y[3][3];
    if (!mid_inverse(h, y))
        return ISM_KRAWCZYK_UNKNOWN;
    ism_interval dx[3];
    _Pragma("GCC unroll 3") for (int j = 0; j < 3; j++)
        dx[j] = iv_sub(x[j], iv(c[j], c[j]));
    bool inner = true, empty = false;
    _Pragma("GCC unroll 3") for (int i = 0; i < 3; i++) {
        ism_interval acc = iv(c[i], c[i]);
        _Pragma("GCC unroll 3") for (int m = 0; m < 3; m++)
            acc = iv_sub(acc, iv_mul_c(gc[m], y[i][m]));
        _Pragma("GCC unroll 3") for (int j = 0; j < 3; j++) {
            ism_interval e = iv(i == j ? 1.0 : 0.0, i == j ? 1.0 : 0.0);
            _Pragma("GCC unroll 3") for (int m = 0; m < 3; m++)
                e = iv_sub(e, iv_mul_c(h[sym(m, j)], y[i][m]));
            acc = iv_add(acc, iv_mul(ism_iv_sane(e), dx[j]));
        }
        acc = ism_iv_sane(acc);
        if (k)
            k[i] = acc;
        inner = inner && acc.lo > x[i].lo && acc.hi < x[i].hi;
        empty = empty || acc.hi < x[i].lo || acc.lo > x[i].hi;
    }
    return empty ? ISM_KRAWCZYK_EMPTY : inner ? ISM_KRAWCZYK_UNIQUE : ISM_KRAWCZYK_UNKNOWN;
}

int ism_krawczyk2(double r, const ism_interval gc[2], const ism_interval j[3])
{
    double m[3];
    for (int e = 0; e < 3; e++)
        m[e] = 0.5 * j[e].lo + 0.5 * j[e].hi;
    double det = m[0] * m[2] - m[1] * m[1];
    if (!(det != 0.0) || !isfinite(det))
        return ISM_KRAWCZYK_UNKNOWN;
    double y[2][2] = { { m[2] / det, -m[1] / det }, { -m[1] / det, m[0] / det } };
    static const int at[2][2] = { { 0, 1 }, { 1, 2 } };
    ism_interval dx = iv(-r, r);
    bool inner = true, empty = false;
    for (int i = 0; i < 2; i++) {
        if (!isfinite(y[i][0]) || !isfinite(y[i][1]))
            return ISM_KRAWCZYK_UNKNOWN;
        ism_interval acc = iv_neg(iv_add(iv_mul_c(gc[0], y[i][0]), iv_mul_c(gc[1], y[i][1])));
        for (int c = 0; c < 2; c++) {
            ism_interval e = iv(i == c ? 1.0 : 0.0, i == c ? 1.0 : 0.0);
            for (int k = 0; k < 2; k++)
                e = iv_sub(e, iv_mul_c(j[at[k][c]], y[i][k]));
            acc = iv_add(acc, iv_mul(ism_iv_sane(e), dx));
        }
        acc = ism_iv_sane(acc);
        inner = inner && acc.lo > -r && acc.hi < r;
        empty = empty || acc.hi < -r || acc.lo > r;
    }
    return empty ? ISM_KRAWCZYK_EMPTY : inner ? ISM_KRAWCZYK_UNIQUE : ISM_KRAWCZYK_UNKNOWN;
}
