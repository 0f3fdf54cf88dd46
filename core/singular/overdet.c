/* overdet.c — left inverses of small dense matrices and Krawczyk's operator for regular
 * overdetermined systems (overdet.h). */
#include "core/singular/overdet.h"
#include "core/eval/interval_ops.h"

#include <math.h>

/* Rows are scaled to unit length, but none by more than 1 / (this × the longest row): a row
 * that carries no first-order information at the point (∇f's rows where H = 0, at a triple
 * point) is rounding noise whose relative width is large, and scaling it up would let that
 * noise into every row of P. Any P with P A = I is valid (A of full column rank): the floor
 * changes only how well K contracts, never what it proves. */
#define OD_ROW_FLOOR 1e-6

/* y = m⁻¹ (n × n) by Gauss–Jordan with partial pivoting; m is destroyed. False when singular
 * or not finite. */
static bool invert(int n, double m[][ISM_OD_MAXK], double y[][ISM_OD_MAXK])
{
    for (int i = 0; i < n; i++)
        for (int j = 0; j < n; j++)
            y[i][j] = i == j;
    for (int c = 0; c < n; c++) {
        int piv = c;
        for (int r = c + 1; r < n; r++)
            if (fabs(m[r][c]) > fabs(m[piv][c]))
                piv = r;
        if (!(fabs(m[piv][c]) > 0.0) || !isfinite(m[piv][c]))
            return false;
        for (int j = 0; j < n; j++) {
            double t = m[c][j]; m[c][j] = m[piv][j]; m[piv][j] = t;
            t = y[c][j]; y[c][j] = y[piv][j]; y[piv][j] = t;
        }
        double inv = 1.0 / m[c][c];
        for (int j = 0; j < n; j++)
            m[c][j] *= inv, y[c][j] *= inv;
        for (int r = 0; r < n; r++) {
            if (r == c || m[r][c] == 0.0)
                continue;
            double s = m[r][c];
            for (int j = 0; j < n; j++)
                m[r][j] -= s * m[c][j], y[r][j] -= s * y[c][j];
        }
    }
    for (int i = 0; i < n; i++)
        for (int j = 0; j < n; j++)
            if (!isfinite(y[i][j]))
                return false;
    return true;
}

/* ‖P W⁻¹‖ ‖W A‖ (max-row norms): the condition of the row-scaled matrix. */
static double condition(int m, int k, const double a[][ISM_OD_MAXK], const double p[][ISM_OD_MAXM],
                        const double w[])
{
    double np = 0.0, na = 0.0;
    for (int i = 0; i < k; i++) {
        double row = 0.0;
        for (int r = 0; r < m; r++)
            row += fabs(p[i][r]) / w[r];
        np = fmax(np, row);
    }
    for (int r = 0; r < m; r++) {
        double row = 0.0;
        for (int j = 0; j < k; j++)
            row += fabs(a[r][j]) * w[r];
        na = fmax(na, row);
    }
    return np * na;
}

bool ism_od_left_inverse(int m, int k, const double a[][ISM_OD_MAXK], double p[][ISM_OD_MAXM],
                         double *cond)
{
    double n[ISM_OD_MAXK][ISM_OD_MAXK], y[ISM_OD_MAXK][ISM_OD_MAXK], w[ISM_OD_MAXM];
    if (m == k) {
        for (int i = 0; i < k; i++)
            for (int j = 0; j < k; j++)
                n[i][j] = a[i][j];
        if (!invert(k, n, y))
            return false;
        for (int i = 0; i < k; i++)
            for (int j = 0; j < k; j++) {
                p[i][j] = y[i][j];
                w[i] = 1.0;
            }
        if (cond)
            *cond = condition(m, k, a, p, w);
        return true;
    }
    double longest = 0.0;
    for (int r = 0; r < m; r++) { /* row scales: every equation weighs the same */
        double s = 0.0;
        for (int j = 0; j < k; j++)
            s += a[r][j] * a[r][j];
        w[r] = sqrt(s);
        longest = fmax(longest, w[r]);
    }
    if (!(longest > 0.0) || !isfinite(longest))
        return false;
    for (int r = 0; r < m; r++)
        w[r] = 1.0 / fmax(w[r], OD_ROW_FLOOR * longest);
    for (int i = 0; i < k; i++)
        for (int j = 0; j < k; j++) {
            double s = 0.0;
            for (int r = 0; r < m; r++)
                s += a[r][i] * w[r] * w[r] * a[r][j];
            n[i][j] = s;
        }
    if (!invert(k, n, y))
        return false;
    for (int i = 0; i < k; i++)
        for (int r = 0; r < m; r++) {
            double s = 0.0;
            for (int j = 0; j < k; j++)
                s += y[i][j] * a[r][j];
            p[i][r] = s * w[r] * w[r];
            if (!isfinite(p[i][r]))
                return false;
        }
    if (cond)
        *cond = condition(m, k, a, p, w);
    return true;
}

bool ism_od_krawczyk(int m, int k, const ism_interval jz[][ISM_OD_MAXK], const ism_interval g[],
                     const double zc[], const ism_interval z[], ism_interval kout[])
{
    double a[ISM_OD_MAXM][ISM_OD_MAXK], p[ISM_OD_MAXK][ISM_OD_MAXM];
    for (int r = 0; r < m; r++)
        for (int j = 0; j < k; j++)
            a[r][j] = 0.5 * jz[r][j].lo + 0.5 * jz[r][j].hi;
    if (!ism_od_left_inverse(m, k, a, p, NULL))
        return false;
    bool inner = true;
    for (int i = 0; i < k; i++) {
        ism_interval acc = iv(zc[i], zc[i]);
        for (int r = 0; r < m; r++)
            acc = iv_sub(acc, iv_mul_c(g[r], p[i][r]));
        for (int j = 0; j < k; j++) {
            ism_interval e = iv(i == j ? 1.0 : 0.0, i == j ? 1.0 : 0.0);
            for (int r = 0; r < m; r++)
                e = iv_sub(e, iv_mul_c(jz[r][j], p[i][r]));
            acc = iv_add(acc, iv_mul(ism_iv_sane(e), iv_sub(z[j], iv(zc[j], zc[j]))));
        }
        acc = ism_iv_sane(acc);
        if (kout)
            kout[i] = acc;
        inner = inner && acc.lo > z[i].lo && acc.hi < z[i].hi;
    }
    return inner;
}
