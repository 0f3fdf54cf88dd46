/* point_cert.c — one singular point's certificate by its Hessian's rank (point_cert.h). */
#include "core/singular/point_cert.h"
#include "core/singular/deflate.h"
#include "core/singular/krawczyk.h"
#include "core/singular/miranda.h"
#include "core/singular/search.h"
#include "core/singular/typecert.h"
#include "core/eval/interval_ops.h"
#include "core/util/sym3.h"

#include <string.h>

/* Certificate boxes are tried from CERT_FIRST × the largest allowed half-width, growing by
 * CERT_GROWTH: the smallest box that works is the best enclosure. */
#define CERT_FIRST 1e-6
#define CERT_GROWTH 10.0
/* The largest cube (× diagonal) the existence proof of a contact tries: a contact is located
 * to ~1e-5 of f's scale in double precision; beyond 1e-3 the proof says little more than
 * the candidate cluster. */
#define MIRANDA_RMAX_REL 1e-3

bool ism_pcert_init(ism_pcert *c, const ism_tape *t, double diag, double hscale,
                    uint64_t *evals)
{
    *c = (ism_pcert){ .t = t, .diag = diag, .hscale = hscale, .evals = evals };
    c->jw = ism_ivjet_ws_new(t);
    return c->jw != NULL;
}

void ism_pcert_free(ism_pcert *c)
{
    ism_ivjet_ws_free(c->jw);
    ism_jet4_ws_free(c->j3);
    ism_jet4_ws_free(c->j4);
}

/* *w made at first use (order 3 or 4); false (oom set) when out of memory. */
static bool jets(ism_pcert *c, ism_jet4_ws **w, int order)
{
    if (!*w && !(*w = ism_jet4_ws_new(c->t, order)))
        c->oom = true;
    return *w != NULL;
}

/* Krawczyk on p ± r for growing r up to the allowed half-width. */
static bool krawczyk(ism_pcert *c, ism_sing_point *pt, ism_interval *fbox)
{
    double rmax = ISM_SING_CERT_REL * c->diag;
    const double *p = pt->p;
    ism_interval b0[3] = { iv(p[0], p[0]), iv(p[1], p[1]), iv(p[2], p[2]) };
    ism_ivgrad gc;
    ism_eval_interval_grad(c->t, c->jw, b0, NULL, NULL, &gc);
    for (double r = CERT_FIRST * rmax; r <= rmax * (1.0 + 1e-12); r *= CERT_GROWTH) {
        ism_interval b[3];
        for (int k = 0; k < 3; k++)
            b[k] = iv(down1(p[k] - r), up1(p[k] + r));
        ism_ivjet j;
        ism_eval_interval_jet(c->t, c->jw, b, NULL, NULL, &j);
        (*c->evals)++;
        if (ism_krawczyk(b, p, gc.d, j.h, NULL) == ISM_KRAWCZYK_UNIQUE) {
            pt->radius = r;
            pt->certificate = ISM_CERT_KRAWCZYK;
            *fbox = j.v;
            return true;
        }
    }
    return false;
}

/* The deflation certificate of a rank-2 point along its null vector; false with the reason
 * set (ISM_UNCERT_CUBIC when the cubic term vanishes: the A3 system is tried next). */
static bool deflation(ism_pcert *c, ism_sing_point *pt, const double n[3], ism_interval *fbox)
{
    if (!jets(c, &c->j3, 3))
        return false;
    double rmax = ISM_SING_CERT_REL * c->diag;
    ism_deflate_result r;
    int a = ism_deflate_certify(c->j3, pt->p, n, CERT_FIRST * rmax, rmax, CERT_GROWTH, &r,
                                c->evals);
    if (a != ISM_DEFLATE_CERTIFIED) {
        pt->uncertified_why = a == ISM_DEFLATE_SINGULAR ? ISM_UNCERT_CUBIC : ISM_UNCERT_CONTRACT;
        return false;
    }
    pt->radius = r.radius;
    pt->certificate = ISM_CERT_DEFLATION;
    pt->perturbation = r.eps;
    *fbox = r.f;
    return true;
}

/* A defining system (typecert.h); the reason when singular is the system's own. */
static bool defining_system(ism_pcert *c, ism_sing_point *pt, int system, double reach,
                            ism_interval *fbox)
{
    static const int why_singular[ISM_TC_SYSTEMS] = { ISM_UNCERT_RANK0, ISM_UNCERT_CONTACT,
                                                      ISM_UNCERT_CUBIC };
    ism_jet4_ws **w = system == ISM_TC_A3 ? &c->j4 : &c->j3; /* D⁴f only for A3 */
    if (!jets(c, w, system == ISM_TC_A3 ? 4 : 3))
        return false;
    ism_typecert_result r;
    int a = ism_typecert(*w, system, pt->p, reach, ISM_SING_CERT_REL * c->diag, c->diag,
                         c->hscale, &r, c->evals);
    if (a != ISM_TC_CERTIFIED) {
        pt->uncertified_why = a == ISM_TC_SINGULAR ? why_singular[system] : ISM_UNCERT_CONTRACT;
        return false;
    }
    memcpy(pt->p, r.p, sizeof pt->p);
    pt->radius = r.radius;
    pt->certificate = ISM_CERT_RANK0 + system;
    pt->perturbation = r.residual;
    pt->uncertified_why = ISM_UNCERT_NONE;
    *fbox = r.f;
    return true;
}

bool ism_pcert_point(ism_pcert *c, ism_sing_point *pt, int rank, const double null_vec[3],
                     double reach, ism_interval *fbox)
{
    pt->certificate = ISM_CERT_NONE;
    pt->uncertified_why = ISM_UNCERT_NONE;
    pt->perturbation = 0.0;
    bool ok = krawczyk(c, pt, fbox);
    if (!ok && rank == 2) {
        ok = deflation(c, pt, null_vec, fbox);
        if (!ok && pt->uncertified_why == ISM_UNCERT_CUBIC)
            ok = defining_system(c, pt, ISM_TC_A3, reach, fbox);
    } else if (!ok && rank < 2) {
        ok = defining_system(c, pt, rank == 1 ? ISM_TC_RANK1 : ISM_TC_RANK0, reach, fbox);
    } else if (!ok) {
        pt->uncertified_why = ISM_UNCERT_CONTRACT;
    }
    pt->certified = ok;
    pt->exists_radius = 0.0;
    if (pt->uncertified_why != ISM_UNCERT_CONTACT)
        return ok;
    if (jets(c, &c->j3, 3) && !ism_miranda_zero(c->j3, pt->p, ISM_SING_CERT_REL * c->diag,
                               MIRANDA_RMAX_REL * c->diag, &pt->exists_radius, c->evals))
        pt->exists_radius = 0.0;
    return ok;
}

/* How far (× finest cell) a curve point's defining system may move it: the tracer placed it
 * within 1e-10 × diagonal, so any farther solution is another point. */
#define CURVE_POINT_REACH_CELLS 0.1

/* Hessian eigen-decomposition and residuals at pt->p. */
static void measure(const ism_tape *f, ism_eval_ws *ws, ism_sing_point *pt, double vec[3][3],
                    uint64_t *evals)
{
    double g[3], h[6];
    pt->residual_f = fabs(ism_eval_hessian(f, ws, pt->p[0], pt->p[1], pt->p[2], g, h));
    (*evals)++;
    pt->residual_grad = sqrt(g[0] * g[0] + g[1] * g[1] + g[2] * g[2]);
    ism_sym3_eigen(h, pt->eig, vec);
}

bool ism_sing_certify_curve_points(const ism_tape *f, const ism_locus_options *o,
                                   ism_locus *out, ism_error *err)
{
    double d2 = 0.0, cell = 0.0;
    for (int k = 0; k < 3; k++) {
        double ext = o->box[k + 3] - o->box[k];
        d2 += ext * ext;
        cell = fmax(cell, ext / ldexp(1.0, o->max_depth));
    }
    ism_pcert c;
    ism_eval_ws *ws = ism_eval_ws_new(f);
    bool ok = ism_pcert_init(&c, f, sqrt(d2), out->hessian_scale, &out->evals_jet) && ws;
    const char *during = "the certification of curve points";
    for (size_t i = 0; ok && i < out->npoints && !ism_locus_out_of_time(o, out, during); i++) {
        ism_sing_point *pt = &out->points[i];
        if (pt->certified || pt->uncertified_why != ISM_UNCERT_NONE)
            continue;
        double vec[3][3], keep[3];
        memcpy(keep, pt->p, sizeof keep);
        measure(f, ws, pt, vec, &out->evals_jet);
        int rank = ism_sing_rank(pt->eig, out->hessian_scale), null = 0;
        for (int e = 1; e < 3; e++)
            if (fabs(pt->eig[e]) < fabs(pt->eig[null]))
                null = e;
        double radius = pt->radius;
        ism_interval fbox;
        if (ism_pcert_point(&c, pt, rank, vec[null], CURVE_POINT_REACH_CELLS * cell, &fbox)
            && !(fbox.lo <= 0.0 && fbox.hi >= 0.0)) {
            /* proved, but off f = 0: not the curve's point after all */
            *pt = (ism_sing_point){ .p = { keep[0], keep[1], keep[2] }, .radius = radius,
                                    .type = pt->type, .cones = pt->cones,
                                    .uncertified_why = ISM_UNCERT_CONTRACT };
        }
        measure(f, ws, pt, vec, &out->evals_jet);
        ok = !c.oom;
    }
    ism_eval_ws_free(ws);
    ism_pcert_free(&c);
    if (!ok)
        return ism_error_set(err, "singular curve points: out of memory");
    return true;
}
