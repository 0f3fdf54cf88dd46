/* sym3.c — cyclic Jacobi for symmetric 3×3 matrices (see sym3.h). Each rotation zeroes one
 * off-diagonal entry; sweeps repeat until the off-diagonal part is negligible against the
 * diagonal. Convergence is quadratic, so a handful of sweeps always suffice. Then the
 * pseudo-inverse Newton step on ∇f = 0 over its eigen-directions (ism_sym3_pinv_step). */
#include "core/util/sym3.h"
#include "core/util/vec3.h"

#include <math.h>
#include <string.h>

/* Inlined into the sweep with constant p, q (its three calls) and its loops unrolled by
 * pragma (gcc -O2 keeps them rolled), so the indexing folds away; the same operations in the
 * same order. The singular search's Newton steps spend most of their pseudo-inverse here. */
static inline __attribute__((always_inline)) void rotate(double a[3][3], double v[3][3], int p,
                                                         int q)
{
    if (a[p][q] == 0.0)
        return;
    double theta = (a[q][q] - a[p][p]) / (2.0 * a[p][q]);
    double t = (theta >= 0 ? 1.0 : -1.0) / (fabs(theta) + sqrt(theta * theta + 1.0));
    double c = 1.0 / sqrt(t * t + 1.0), s = t * c;
    _Pragma("GCC unroll 3") for (int k = 0; k < 3; k++) { /* columns p, q of a */
        double akp = a[k][p], akq = a[k][q];
        a[k][p] = c * akp - s * akq;
        a[k][q] = s * akp + c * akq;
    }
    _Pragma("GCC unroll 3") for (int k = 0; k < 3; k++) { /* rows p, q of a */
        double apk = a[p][k], aqk = a[q][k];
        a[p][k] = c * apk - s * aqk;
        a[q][k] = s * apk + c * aqk;
    }
    a[p][q] = a[q][p] = 0.0;
    _Pragma("GCC unroll 3") for (int k = 0; k < 3; k++) { /* v's columns are the eigenvectors */
        double vkp = v[k][p], vkq = v[k][q];
        v[k][p] = c * vkp - s * vkq;
        v[k][q] = s * vkp + c * vkq;
    }
}

void ism_sym3_sorted(const double h[6], const double a[3][3], const double v[3][3],
                     double eig[3], double vec[3][3])
{
    int order[3] = {0, 1, 2};
    for (int i = 0; i < 3; i++) /* three-element insertion sort by eigenvalue */
        for (int j = i; j > 0 && a[order[j]][order[j]] < a[order[j - 1]][order[j - 1]]; j--) {
            int t = order[j];
            order[j] = order[j - 1];
            order[j - 1] = t;
        }
    for (int i = 0; i < 3; i++) {
        eig[i] = a[order[i]][order[i]];
        if (vec)
            for (int k = 0; k < 3; k++)
                vec[i][k] = v[k][order[i]];
    }
    for (int i = 0; i < 6; i++)
        if (!isfinite(h[i])) {
            eig[0] = eig[1] = eig[2] = NAN;
            break;
        }
}

void ism_sym3_eigen(const double h[6], double eig[3], double vec[3][3])
{
    double a[3][3] = {{h[0], h[1], h[2]}, {h[1], h[3], h[4]}, {h[2], h[4], h[5]}};
    double v[3][3] = {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
    for (int sweep = 0; sweep < ISM_SYM3_MAX_SWEEPS; sweep++) {
        double off = fabs(a[0][1]) + fabs(a[0][2]) + fabs(a[1][2]);
        double diag = fabs(a[0][0]) + fabs(a[1][1]) + fabs(a[2][2]);
        if (!(off > ISM_SYM3_OFF_TINY) || off <= ISM_SYM3_OFF_REL * diag)
            break;
        rotate(a, v, 0, 1);
        rotate(a, v, 0, 2);
        rotate(a, v, 1, 2);
    }
    ism_sym3_sorted(h, (const double (*)[3])a, (const double (*)[3])v, eig, vec);
}

int ism_sym3_rank(const double eig[3], double rel)
{
    double m = fmax(fabs(eig[0]), fmax(fabs(eig[1]), fabs(eig[2])));
    int r = 0;
    for (int i = 0; i < 3; i++)
        r += m > 0 && fabs(eig[i]) > rel * m;
    return r;
}

/* Loops over the three directions are unrolled by pragma here and in search.c's interval
 * tests (gcc -O2 keeps them rolled: the singular stage runs this step for every Newton
 * iterate). This step lived in core/singular/newton.c until the octree's critical-radius
 * test shared it. Inlined into both callers below. */
static inline __attribute__((always_inline)) bool pinv_of(const double g[3],
                                                          const double eig[3],
                                                          const double vec[3][3], double rel,
                                                          double trust, double step[3])
{
    double big = fmax(fabs(eig[0]), fmax(fabs(eig[1]), fabs(eig[2])));
    if (!(big > 0.0) || !isfinite(big))
        return false;
    /* directions by decreasing |λ| */
    int order[3] = { 0, 1, 2 };
    _Pragma("GCC unroll 3") for (int i = 0; i < 3; i++)
        for (int j = i + 1; j < 3; j++)
            if (fabs(eig[order[j]]) > fabs(eig[order[i]])) {
                int t = order[i];
                order[i] = order[j];
                order[j] = t;
            }
    double part[3][3] = { { 0 } }; /* part[i]: the step along the i-th largest direction */
    int kept = 0;
    _Pragma("GCC unroll 3") for (int r = 0; r < 3; r++) {
        int i = order[r];
        if (!(fabs(eig[i]) > rel * big))
            break;
        double c = -(vec[i][0] * g[0] + vec[i][1] * g[1] + vec[i][2] * g[2]) / eig[i];
        _Pragma("GCC unroll 3") for (int k = 0; k < 3; k++)
            part[r][k] = c * vec[i][k];
        kept++;
    }
    for (; kept > 0; kept--) {
        _Pragma("GCC unroll 3") for (int k = 0; k < 3; k++)
            step[k] = part[0][k] + (kept > 1 ? part[1][k] : 0.0) + (kept > 2 ? part[2][k] : 0.0);
        if (!(ism_norm3(step) > trust))
            break;
    }
    if (kept == 0)
        _Pragma("GCC unroll 3") for (int k = 0; k < 3; k++)
            step[k] = part[0][k];
    return isfinite(step[0]) && isfinite(step[1]) && isfinite(step[2]);
}

bool ism_sym3_pinv_step(const double g[3], const double h[6], double rel, double trust,
                        double step[3])
{
    double eig[3], vec[3][3];
    ism_sym3_eigen(h, eig, vec);
    return pinv_of(g, eig, (const double (*)[3])vec, rel, trust, step);
}

bool ism_sym3_pinv_of(const double g[3], const double eig[3], const double vec[3][3],
                      double rel, double trust, double step[3])
{
    return pinv_of(g, eig, vec, rel, trust, step);
}
