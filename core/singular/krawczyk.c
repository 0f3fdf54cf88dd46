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

/* Relative slack of row_sure's plain-double estimates: far above their rounding (a few
 * ulps of the magnitudes summed, ~1e-15), far below any margin that matters. */
#define KRAWCZYK_SLACK 1e-9

/* Whether some row of the interval matrix h holds 0 in each entry: then h holds a singular
 * matrix, and K ⊂ int X (which proves every matrix of h non-singular) cannot hold. */
static bool holds_singular(const ism_interval h[6])
{
    for (int i = 0; i < 3; i++) {
        bool zero = true;
        for (int j = 0; j < 3 && zero; j++)
            zero = h[sym(i, j)].lo <= 0.0 && h[sym(i, j)].hi >= 0.0;
        if (zero)
            return true;
    }
    return false;
}

/* What plain doubles tell of a row of K (row_sure). */
enum { ROW_MEETS = 1, /* sure not to be apart from X */
       ROW_WIDE = 2 /* sure not to be inside X */ };

/* The plain-double view of K: Y, c, and per axis the half-width r_j (the smaller distance
 * from c_j to X_j's ends) and gc's midpoint and radius; |Y| and the radii of H's entries,
 * taken once for the three rows, the same values row_sure took per row before (Klein at E
 * 0.0141, the search's 1,945 calls: 2.62M -> 2.33M instructions). */
typedef struct k_view {
    const double (*y)[3];
    const double *c;
    double ya[3][3];          /* |Y| */
    double r[3], gm[3], gr[3];
    double hr[6];             /* rad(h_e), xx xy xz yy yz zz */
    bool ok;                  /* every r_j > 0 */
} k_view;

static void view_of(k_view *v, const ism_interval x[3], const double c[3],
                    const ism_interval gc[3], const ism_interval h[6], const double y[3][3])
{
    v->y = y;
    v->c = c;
    v->ok = true;
    for (int j = 0; j < 3; j++) {
        v->r[j] = fmin(c[j] - x[j].lo, x[j].hi - c[j]) * (1.0 - KRAWCZYK_SLACK);
        v->gm[j] = 0.5 * gc[j].lo + 0.5 * gc[j].hi;
        v->gr[j] = 0.5 * gc[j].hi - 0.5 * gc[j].lo;
        v->ok = v->ok && v->r[j] > 0.0;
        for (int m = 0; m < 3; m++)
            v->ya[j][m] = fabs(y[j][m]);
    }
    for (int e = 0; e < 6; e++)
        v->hr[e] = 0.5 * h[e].hi - 0.5 * h[e].lo;
}

/* What row i of K is sure to be, from plain doubles (ROW_* bits; 0: nothing sure). The row
 * holds [a − W/2, a + W/2] with a = c_i − Σ_m y_im mid(gc_m) and
 * W/2 = Σ_m |y_im| rad(gc_m) + Σ_j r_j Σ_m |y_im| rad(h_mj): the term (I − Y H) (X − c) holds
 * e_ij [−r_j, r_j], whose half-width is mag(e_ij) r_j ≥ rad(e_ij) r_j, and the outward-rounded
 * row holds the exact one. So W ≥ w(X_i) rules out "inside", and [a ± W/2] meeting X_i rules
 * out "apart". Each comparison keeps KRAWCZYK_SLACK of its sides; anything non-finite is
 * sure of nothing. */
static int row_sure(const k_view *v, int i, const ism_interval x[3])
{
    if (!v->ok)
        return 0;
    double a = v->c[i], size = fabs(v->c[i]), half = 0.0;
    for (int m = 0; m < 3; m++) {
        a -= v->y[i][m] * v->gm[m];
        size += fabs(v->y[i][m] * v->gm[m]);
        half += v->ya[i][m] * v->gr[m];
    }
    for (int j = 0; j < 3; j++) {
        double rad = 0.0;
        for (int m = 0; m < 3; m++)
            rad += v->ya[i][m] * v->hr[sym(m, j)];
        half += rad * v->r[j];
    }
    half *= 1.0 - KRAWCZYK_SLACK;
    double err = KRAWCZYK_SLACK * (size + half + fabs(x[i].lo) + fabs(x[i].hi));
    if (!(a - half + err <= x[i].hi && a + half - err >= x[i].lo))
        return 0;
    return ROW_MEETS | (2.0 * half >= (x[i].hi - x[i].lo) * (1.0 + KRAWCZYK_SLACK) ? ROW_WIDE : 0);
}

/* Row i of K, outward rounded (dx = X − c). */
static ism_interval k_row(int i, const double c[3], const ism_interval gc[3],
                          const ism_interval h[6], const double y[3][3],
                          const ism_interval dx[3])
{
    ism_interval acc = iv(c[i], c[i]);
    _Pragma("GCC unroll 3") for (int m = 0; m < 3; m++)
        acc = iv_sub(acc, iv_mul_c(gc[m], y[i][m]));
    _Pragma("GCC unroll 3") for (int j = 0; j < 3; j++) {
        ism_interval e = iv(i == j ? 1.0 : 0.0, i == j ? 1.0 : 0.0);
        _Pragma("GCC unroll 3") for (int m = 0; m < 3; m++)
            e = iv_sub(e, iv_mul_c(h[sym(m, j)], y[i][m]));
        acc = iv_add(acc, iv_mul(ism_iv_sane(e), dx[j]));
    }
    return ism_iv_sane(acc);
}

/* K's answer is EMPTY when a row is apart from X, else UNIQUE when every row is inside it,
 * else UNKNOWN. Without K wanted, a row is computed in intervals only when plain doubles
 * (row_sure) leave its part of that answer open: a row sure to meet X cannot make it EMPTY,
 * and one row sure not to be inside (or a singular matrix in h) rules UNIQUE out. The
 * singular search's cells along a curve (H singular along it) need no row at all on the
 * cross-cap (Y large: every row wide), one on the Whitney umbrella's axis (H's z row holds
 * 0; the x row of K touches X's face exactly, which only the interval row can tell). */
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
    if (k) {
        for (int i = 0; i < 3; i++) {
            ism_interval acc = k[i] = k_row(i, c, gc, h, y, dx);
            inner = inner && acc.lo > x[i].lo && acc.hi < x[i].hi;
            empty = empty || acc.hi < x[i].lo || acc.lo > x[i].hi;
        }
        return empty ? ISM_KRAWCZYK_EMPTY : inner ? ISM_KRAWCZYK_UNIQUE : ISM_KRAWCZYK_UNKNOWN;
    }
    k_view v;
    view_of(&v, x, c, gc, h, y);
    bool not_inside = holds_singular(h), open[3] = { false, false, false };
    for (int i = 0; i < 3; i++) {
        int sure = row_sure(&v, i, x);
        if (sure & ROW_MEETS) {
            not_inside = not_inside || (sure & ROW_WIDE);
            open[i] = !(sure & ROW_WIDE);
            continue;
        }
        ism_interval acc = k_row(i, c, gc, h, y, dx);
        if (acc.hi < x[i].lo || acc.lo > x[i].hi)
            return ISM_KRAWCZYK_EMPTY;
        not_inside = not_inside || !(acc.lo > x[i].lo && acc.hi < x[i].hi);
    }
    for (int i = 0; i < 3 && !not_inside; i++)
        if (open[i]) {
            ism_interval acc = k_row(i, c, gc, h, y, dx);
            not_inside = !(acc.lo > x[i].lo && acc.hi < x[i].hi);
        }
    return not_inside ? ISM_KRAWCZYK_UNKNOWN : ISM_KRAWCZYK_UNIQUE;
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
