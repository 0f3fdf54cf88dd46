/* miranda.c — Poincaré–Miranda on a cube in the Hessian's eigenframe (miranda.h). */
#include "core/singular/miranda.h"
#include "core/eval/interval_ops.h"
#include "core/util/sym3.h"

#include <math.h>

/* Pieces per face side: the Taylor form over a piece of half-width h = ρ/PIECES adds
 * ~|T| h² to F̃_N, where at a contact |T| ~ ρ × f's quartic scale (plus the product
 * rule's cancelling terms, also ~h); the signal there is ~ρ³ × the quartic's: 8 pieces
 * leave a wide margin at touching spheres. */
#define MIRANDA_PIECES 8
/* Cube half-widths grow by this factor between tries. */
#define MIRANDA_GROWTH 10.0

/* Row and column of entry e of a symmetric 3×3 matrix in xx xy xz yy yz zz order. */
static const int SYM[6][2] = { { 0, 0 }, { 0, 1 }, { 0, 2 }, { 1, 1 }, { 1, 2 }, { 2, 2 } };

/* F̃_i over one face piece: centre c, half-width h along R_j and R_k, by the Taylor form
 * F̃_i(c) + Σ_d t_d R_i H(c) R_dᵀ + ½ Σ_de t_d t_e T(hull)[R_i, R_d, R_e]. */
static ism_interval piece(ism_jet4_ws *w, const double R[3][3], int i, int j, int k,
                          const double c[3], double h, uint64_t *evals)
{
    ism_interval pc[3], hull[3];
    for (int a = 0; a < 3; a++) {
        double reach = h * (fabs(R[j][a]) + fabs(R[k][a]));
        pc[a] = iv(c[a], c[a]);
        hull[a] = iv(down1(c[a] - reach), up1(c[a] + reach));
    }
    ism_jet4 jc, jh;
    ism_jet4_eval(w, pc, &jc, evals);
    ism_jet4_eval(w, hull, &jh, evals);
    ism_interval s = iv(0.0, 0.0), t = iv(-h, h), tt = iv_mul(t, t);
    for (int a = 0; a < 3; a++)
        s = iv_add(s, iv_mul_c(jc.d[a], R[i][a]));
    const int dirs[2] = { j, k };
    for (int d = 0; d < 2; d++) {
        ism_interval rhr = iv(0.0, 0.0); /* R_i H(c) R_dᵀ */
        for (int a = 0; a < 3; a++)
            for (int b = 0; b < 3; b++)
                rhr = iv_add(rhr, iv_mul_c(jc.h[a][b], R[i][a] * R[dirs[d]][b]));
        s = iv_add(s, iv_mul(rhr, t));
        for (int e = 0; e < 2; e++) {
            ism_interval trr = iv(0.0, 0.0); /* T(hull)[R_i, R_d, R_e] */
            for (int a = 0; a < 3; a++)
                for (int b = 0; b < 3; b++)
                    for (int g = 0; g < 3; g++)
                        trr = iv_add(trr, iv_mul_c(jh.t[a][b][g],
                                                   R[i][a] * R[dirs[d]][b] * R[dirs[e]][g]));
            s = iv_add(s, iv_mul_c(iv_mul(trr, tt), 0.5));
        }
    }
    return ism_iv_sane(s);
}

/* +1 / −1 when F̃_i is strictly of that sign on the whole face s_i = side·ρ, else 0. */
static int face_sign(ism_jet4_ws *w, const double R[3][3], const double p[3], int i,
                     double side, double rho, uint64_t *evals)
{
    int j = (i + 1) % 3, k = (i + 2) % 3, sign = 0;
    double h = rho / MIRANDA_PIECES;
    for (int a = 0; a < MIRANDA_PIECES; a++)
        for (int b = 0; b < MIRANDA_PIECES; b++) {
            double u = -rho + (2 * a + 1) * h, v = -rho + (2 * b + 1) * h, c[3];
            for (int m = 0; m < 3; m++)
                c[m] = p[m] + side * rho * R[i][m] + u * R[j][m] + v * R[k][m];
            ism_interval s = piece(w, R, i, j, k, c, h, evals);
            int here = s.lo > 0.0 ? 1 : s.hi < 0.0 ? -1 : 0;
            if (here == 0 || (sign != 0 && here != sign))
                return 0;
            sign = here;
        }
    return sign;
}

bool ism_miranda_zero(ism_jet4_ws *w, const double p[3], double rmin, double rmax,
                      double *radius, uint64_t *evals)
{
    ism_interval pc[3] = { iv(p[0], p[0]), iv(p[1], p[1]), iv(p[2], p[2]) };
    ism_jet4 j;
    ism_jet4_eval(w, pc, &j, evals);
    double h[6], eig[3], R[3][3];
    for (int e = 0; e < 6; e++)
        h[e] = 0.5 * j.h[SYM[e][0]][SYM[e][1]].lo + 0.5 * j.h[SYM[e][0]][SYM[e][1]].hi;
    ism_sym3_eigen(h, eig, R);
    if (!isfinite(eig[0]) || !isfinite(eig[2]))
        return false;
    for (double rho = rmin; rho <= rmax * (1.0 + 1e-12); rho *= MIRANDA_GROWTH) {
        bool ok = true;
        for (int i = 0; ok && i < 3; i++) {
            int hi = face_sign(w, R, p, i, 1.0, rho, evals);
            ok = hi != 0 && face_sign(w, R, p, i, -1.0, rho, evals) == -hi;
        }
        if (ok) {
            *radius = sqrt(3.0) * rho;
            return true;
        }
    }
    return false;
}
