/* overdet.c — left inverses of small dense matrices and Krawczyk's operator for regular
 * overdetermined systems (overdet.h). */
#include "core/singular/overdet.h"
#include "core/eval/interval_ops.h"

#include <math.h>

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

bool ism_od_left_inverse(int m, int k, const double a[][ISM_OD_MAXK], double p[][ISM_OD_MAXM])
{
    double n[ISM_OD_MAXK][ISM_OD_MAXK], y[ISM_OD_MAXK][ISM_OD_MAXK], w[ISM_OD_MAXM];
    if (m == k) {
        for (int i = 0; i < k; i++)
            for (int j = 0; j < k; j++)
                n[i][j] = a[i][j];
        if (!invert(k, n, y))
            return false;
        for (int i = 0; i < k; i++)
            for (int j = 0; j < k; j++)
                p[i][j] = y[i][j];
        return true;
    }
    for (int r = 0; r < m; r++) { /* row scales: every equation weighs the same */
        double s = 0.0;
        for (int j = 0; j < k; j++)
            s += a[r][j] * a[r][j];
        w[r] = s > 0.0 ? 1.0 / sqrt(s) : 0.0;
    }
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
    return true;
}

bool ism_od_krawczyk(int m, int k, const ism_interval jz[][ISM_OD_MAXK], const ism_interval g[],
                     const double zc[], const ism_interval z[], ism_interval kout[])
{
    double a[ISM_OD_MAXM][ISM_OD_MAXK], p[ISM_OD_MAXK][ISM_OD_MAXM];
    for (int r = 0; r < m; r++)
        for (int j = 0; j < k; j++)
            a[r][j] = 0.5 * jz[r][j].lo + 0.5 * jz[r][j].hi;
    if (!ism_od_left_inverse(m, k, a, p))
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
