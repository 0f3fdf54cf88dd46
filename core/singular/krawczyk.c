/* krawczyk.c — the Krawczyk operator on ∇f (krawczyk.h), with the preconditioner Y the
 * inverse of the Hessian enclosure's midpoint by cofactors; and its 2-D form on a square. */
#include "core/singular/krawczyk.h"
#include "core/eval/interval_ops.h"

#include <math.h>
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

/* Relative slack of undecided's plain-double estimates: far above their rounding (a few
 * ulps of the magnitudes summed, ~1e-15), far below any margin that matters. */
#define KRAWCZYK_SLACK 1e-9

/* Whether every row of K(X) is sure to be neither inside X nor apart from it, from plain
 * doubles: K's answer is then UNKNOWN, and its interval pass is spared. Row i of K holds
 * [a − W/2, a + W/2] with a = c_i − Σ_m y_im mid(gc_m) and
 * W/2 = Σ_m |y_im| rad(gc_m) + Σ_j r_j Σ_m |y_im| rad(h_mj), r_j the smaller distance from c_j
 * to X_j's ends: the term (I − Y H) (X − c) holds e_ij [−r_j, r_j], whose half-width is
 * mag(e_ij) r_j ≥ rad(e_ij) r_j, and the outward-rounded K holds the exact one. So W ≥ w(X_i)
 * rules out "inside", and [a ± W/2] meeting X_i rules out "apart". Each comparison keeps
 * KRAWCZYK_SLACK of its sides; anything non-finite answers false (the full pass decides).
 * On the singular search's cells along a curve (the cross-cap's axis: the Hessian singular
 * along it, Y large) every row is undecided: 1,065 of 1,065 calls. */
static bool undecided(const ism_interval x[3], const double c[3], const ism_interval gc[3],
                      const ism_interval h[6], const double y[3][3])
{
    double r[3], gm[3], gr[3];
    for (int j = 0; j < 3; j++) {
        r[j] = fmin(c[j] - x[j].lo, x[j].hi - c[j]) * (1.0 - KRAWCZYK_SLACK);
        gm[j] = 0.5 * gc[j].lo + 0.5 * gc[j].hi;
        gr[j] = 0.5 * gc[j].hi - 0.5 * gc[j].lo;
        if (!(r[j] > 0.0))
            return false;
    }
    for (int i = 0; i < 3; i++) {
        double a = c[i], size = fabs(c[i]), half = 0.0;
        for (int m = 0; m < 3; m++) {
            a -= y[i][m] * gm[m];
            size += fabs(y[i][m] * gm[m]);
            half += fabs(y[i][m]) * gr[m];
        }
        for (int j = 0; j < 3; j++) {
            double rad = 0.0;
            for (int m = 0; m < 3; m++) {
                ism_interval e = h[sym(m, j)];
                rad += fabs(y[i][m]) * (0.5 * e.hi - 0.5 * e.lo);
            }
            half += rad * r[j];
        }
        half *= 1.0 - KRAWCZYK_SLACK;
        double err = KRAWCZYK_SLACK * (size + half + fabs(x[i].lo) + fabs(x[i].hi));
        bool wide = 2.0 * half >= (x[i].hi - x[i].lo) * (1.0 + KRAWCZYK_SLACK);
        bool meets = a - half + err <= x[i].hi && a + half - err >= x[i].lo;
        if (!(wide && meets))
            return false;
    }
    return true;
}

int ism_krawczyk(const ism_interval x[3], const double c[3], const ism_interval gc[3],
                 const ism_interval h[6], ism_interval k[3])
{
    double y[3][3];
    if (!mid_inverse(h, y))
        return ISM_KRAWCZYK_UNKNOWN;
    if (!k && undecided(x, c, gc, h, y))
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
