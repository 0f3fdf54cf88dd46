/* curve_cert.c — a singular curve's certificate, point by point (curve_cert.h): Krawczyk on
 * the gradient across the curve over a square of its normal plane, f and ∂f/∂t checked over
 * the same box. One interval-jet evaluation a point (over the box; its Hessian's midpoint gives
 * the frame) and one interval gradient at p (an enclosure of G(0, 0)); a second jet only when
 * the first square fails. */
#include "core/singular/curve_cert.h"
#include "core/singular/krawczyk.h"
#include "core/singular/point_cert.h"
#include "core/eval/interval_ops.h"
#include "core/util/sym3.h"
#include "core/util/vec3.h"


/* The first square tried is CCERT_FIRST × the largest allowed half-width: K contracts when
 * the square holds x* with room to spare, and the smallest square that works is the best
 * enclosure. The tracer leaves its points within ~1e-12 × diagonal of the curve (its Newton
 * tolerance), and 1e-3 × 0.5e-9 × diagonal holds that with room, so the first square nearly
 * always passes; a failure is retried once at the bound itself unless the Newton step left
 * at p is already beyond it. */
#define CCERT_FIRST 1e-3

/* An end at a certified point passes when the point lies within this many certificate
 * bounds (ISM_SING_CERT_REL × diagonal) of it: the point's own box (≤ 1 bound) plus the
 * tracer's placement of the end (~1e-10 × diagonal). Farther, the end is checked like any
 * other point. */
#define CCERT_END_BOUNDS 2.0

/* Σ_k e[k] x[k] over intervals x. */
static ism_interval dot_iv(const double e[3], const ism_interval x[3])
{
    ism_interval s = iv_mul_c(x[0], e[0]);
    s = iv_add(s, iv_mul_c(x[1], e[1]));
    return iv_add(s, iv_mul_c(x[2], e[2]));
}

/* Row k of the symmetric Hessian enclosure h (xx xy xz yy yz zz). */
static void hrow(const ism_interval h[6], int k, ism_interval row[3])
{
    static const int idx[3][3] = { { 0, 1, 2 }, { 1, 3, 4 }, { 2, 4, 5 } };
    for (int l = 0; l < 3; l++)
        row[l] = h[idx[k][l]];
}

/* eᵢᵀ H eⱼ over the enclosure h. */
static ism_interval quad(const ism_interval h[6], const double ei[3], const double ej[3])
{
    ism_interval he[3];
    for (int k = 0; k < 3; k++) {
        ism_interval row[3];
        hrow(h, k, row);
        he[k] = dot_iv(ej, row);
    }
    return dot_iv(ei, he);
}

static bool holds0(ism_interval x) { return x.lo <= 0.0 && x.hi >= 0.0; }

/* The jet over the cube p ± √2 r, which holds the square |a|, |b| ≤ r of any plane through
 * p (|a u_k + b v_k| ≤ r (|u_k| + |v_k|) ≤ √2 r for orthonormal u, v): its Hessian's
 * midpoint gives the frame before the frame is known. */
static void cube_jet(const ism_tape *t, ism_ivjet_ws *jw, const double p[3], double r,
                     ism_ivjet *j, uint64_t *evals)
{
    double h = up1(up1(r * 1.4142135623730951 * (1.0 + 0x1p-50)));
    ism_interval box[3];
    for (int k = 0; k < 3; k++)
        box[k] = iv(down1(p[k] - h), up1(p[k] + h));
    ism_eval_interval_jet(t, jw, box, NULL, NULL, j);
    (*evals)++;
}

/* The frame from a Hessian enclosure's midpoint: fr[0] the eigenvector of the smallest
 * |eigenvalue| (the tangent), fr[1], fr[2] the others; lam[0..1] their eigenvalues. */
static void frame(const ism_interval hv[6], double fr[3][3], double lam[2])
{
    double h[6], eig[3], vec[3][3];
    for (int k = 0; k < 6; k++)
        h[k] = 0.5 * hv[k].lo + 0.5 * hv[k].hi;
    ism_sym3_eigen(h, eig, vec);
    int null = 0;
    for (int e = 1; e < 3; e++)
        if (fabs(eig[e]) < fabs(eig[null]))
            null = e;
    for (int i = 0; i < 3; i++)
        for (int k = 0; k < 3; k++)
            fr[i][k] = vec[(null + i) % 3][k];
    lam[0] = eig[(null + 1) % 3];
    lam[1] = eig[(null + 2) % 3];
}

/* The test on the square of half-width r, given the jet over its cube: K ⊂ its interior,
 * and f, ∂f/∂t over the cube hold 0. */
static bool passes(const ism_ivjet *j, const double fr[3][3], const ism_interval gc[2], double r)
{
    const double *tan = fr[0], *u = fr[1], *v = fr[2];
    ism_interval jac[3] = { quad(j->h, u, u), quad(j->h, u, v), quad(j->h, v, v) };
    return ism_krawczyk2(r, gc, jac) == ISM_KRAWCZYK_UNIQUE && holds0(j->v) &&
           holds0(dot_iv(tan, j->d));
}

bool ism_curve_cert_point(const ism_tape *t, ism_ivjet_ws *jw, const double p[3], double rmax,
                          ism_ccert *out, uint64_t *evals)
{
    /* an enclosure of f and ∇f at p itself: G(0, 0) (a gradient costs less than a jet) */
    ism_interval pb[3] = { iv(p[0], p[0]), iv(p[1], p[1]), iv(p[2], p[2]) };
    ism_ivgrad at;
    ism_eval_interval_grad(t, jw, pb, NULL, NULL, &at);
    (*evals)++;
    double g[3];
    for (int k = 0; k < 3; k++)
        g[k] = 0.5 * at.d[k].lo + 0.5 * at.d[k].hi;
    *out = (ism_ccert){ .residual_f = fabs(0.5 * at.v.lo + 0.5 * at.v.hi),
                        .residual_grad = ism_norm3(g) };
    double r = CCERT_FIRST * rmax;
    for (;;) {
        ism_ivjet j;
        cube_jet(t, jw, p, r, &j, evals);
        double fr[3][3], lam[2];
        frame(j.h, fr, lam);
        ism_interval gc[2] = { dot_iv(fr[1], at.d), dot_iv(fr[2], at.d) };
        out->radius = r;
        if (passes(&j, fr, gc, r))
            return true;
        if (r >= rmax)
            return false;
        /* the Newton step left in the plane (G(0, 0) through the block's inverse) says
         * whether a larger square can hold x*: far beyond the bound, it cannot */
        double step = hypot(0.5 * (gc[0].lo + gc[0].hi) / lam[0],
                            0.5 * (gc[1].lo + gc[1].hi) / lam[1]);
        if (step > rmax)
            return false;
        r = rmax;
    }
}

/* Whether point i of c is an end at a certified point of l within reach. */
static bool end_at_certified(const ism_locus *l, const ism_sing_curve *c, size_t i,
                             double reach)
{
    if (c->closed || (i != 0 && i + 1 != c->n))
        return false;
    int j = c->end_point[i == 0 ? 0 : 1];
    if (j < 0 || (size_t)j >= l->npoints || !l->points[j].certified)
        return false;
    const double *q = l->points[j].p, *x = c->xyz + 3 * i;
    return ism_dist3(q, x) <= reach;
}

bool ism_sing_certify_curves(const ism_tape *f, const ism_locus_options *o, ism_locus *out,
                             ism_error *err)
{
    double rmax = ISM_SING_CERT_REL * ism_dist3(o->box, o->box + 3);
    for (size_t c = 0; c < out->ncurves; c++) {
        ism_sing_curve *cv = &out->curves[c];
        cv->certified = false;
        cv->uncertified_points = cv->n;
        cv->first_uncertified = -1;
        cv->first_residual_f = cv->first_residual_grad = cv->cert_radius = 0.0;
    }
    if (out->ncurves == 0)
        return true;
    ism_ivjet_ws *jw = ism_ivjet_ws_new(f);
    if (!jw)
        return ism_error_set(err, "singular curve certificates: out of memory");
    const char *during = "the certification of curves";
    for (size_t c = 0; c < out->ncurves && !ism_locus_out_of_time(o, out, during); c++) {
        ism_sing_curve *cv = &out->curves[c];
        cv->uncertified_points = 0;
        for (size_t i = 0; i < cv->n; i++) {
            ism_ccert pc;
            if (end_at_certified(out, cv, i, CCERT_END_BOUNDS * rmax))
                continue;
            if (ism_curve_cert_point(f, jw, cv->xyz + 3 * i, rmax, &pc, &out->evals_jet)) {
                cv->cert_radius = fmax(cv->cert_radius, pc.radius);
                continue;
            }
            if (cv->uncertified_points++ == 0) {
                cv->first_uncertified = (long)i;
                cv->first_residual_f = pc.residual_f;
                cv->first_residual_grad = pc.residual_grad;
            }
        }
        cv->certified = cv->n > 0 && cv->uncertified_points == 0;
    }
    ism_ivjet_ws_free(jw);
    return true;
}
