/* min_norm.c — the minimum-norm Newton step (min_norm.h): the Gram matrix J Jᵀ, solved by
 * Cramer's rule (it is 2 × 2 or 3 × 3). */
#include "core/util/min_norm.h"
#include "core/util/vec3.h"

#include <string.h>

/* Solves the m × m system A y = r (m = 2 or 3; A a Gram matrix, so symmetric with a
 * determinant ≥ 0 but for rounding). False when singular to within rel. */
static bool solve_gram(int m, double a[3][3], const double r[3], double rel, double y[3])
{
    if (m == 2) {
        double det = a[0][0] * a[1][1] - a[0][1] * a[1][0];
        if (!(det > rel * a[0][0] * a[1][1]))
            return false;
        y[0] = (r[0] * a[1][1] - a[0][1] * r[1]) / det;
        y[1] = (a[0][0] * r[1] - a[1][0] * r[0]) / det;
        return true;
    }
    double c0 = a[1][1] * a[2][2] - a[1][2] * a[2][1];
    double c1 = a[1][2] * a[2][0] - a[1][0] * a[2][2];
    double c2 = a[1][0] * a[2][1] - a[1][1] * a[2][0];
    double det = a[0][0] * c0 + a[0][1] * c1 + a[0][2] * c2;
    if (!(det > rel * a[0][0] * a[1][1] * a[2][2]))
        return false;
    double b[3][3];
    for (int col = 0; col < 3; col++) {
        memcpy(b, a, sizeof b);
        for (int row = 0; row < 3; row++)
            b[row][col] = r[row];
        double d = b[0][0] * (b[1][1] * b[2][2] - b[1][2] * b[2][1]) -
                   b[0][1] * (b[1][0] * b[2][2] - b[1][2] * b[2][0]) +
                   b[0][2] * (b[1][0] * b[2][1] - b[1][1] * b[2][0]);
        y[col] = d / det;
    }
    return true;
}

bool ism_min_norm_step(int m, const double J[][3], const double r[], double rel,
                       double step[3])
{
    double a[3][3], rr[3] = {r[0], r[1], m > 2 ? r[2] : 0}, y[3];
    for (int i = 0; i < m; i++)
        for (int j = 0; j < m; j++)
            a[i][j] = ism_dot3(J[i], J[j]);
    if (!solve_gram(m, a, rr, rel, y))
        return false;
    for (int c = 0; c < 3; c++) {
        step[c] = 0;
        for (int i = 0; i < m; i++)
            step[c] -= J[i][c] * y[i];
    }
    return true;
}
