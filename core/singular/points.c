/* points.c — candidates of the search to certified, typed singular points (points.h). */
#include "core/singular/points.h"
#include "core/singular/clusters.h"
#include "core/singular/curve_jet.h"
#include "core/singular/newton.h"
#include "core/singular/point_cert.h"
#include "core/singular/search.h"
#include "core/eval/interval_jet.h"
#include "core/eval/interval_ops.h"
#include "core/util/clock.h"
#include "core/util/sym3.h"
#include "core/util/vec3.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* A cluster is one point when the projections of its boxes lie within this many finest
 * cells of each other (a curve's or sheet's projections spread along it). */
#define POINT_SPREAD_CELLS 1.0
/* Newton towards a point: steps at most (degenerate zeros converge linearly, by 1/2 to
 * 4/5 a step), and the step (× box diagonal) that ends it — a few ulps of the position. */
#define POINT_NEWTON_ITERS 200
#define POINT_NEWTON_TOL 1e-15
/* f is sampled this far (× finest cell) each way along the Hessian's null direction to tell
 * a cusp (sign change) from an isolated or degenerate point. */
#define TYPE_PROBE_CELLS 0.25
/* Newton steps across the range plane at each probe (quadratic there: a few suffice). */
#define TYPE_ACROSS_STEPS 4
/* Uncertified candidates closer than this (× finest cell) to another point are the same. */
#define MERGE_CELLS 1.0
/* Two rank-3 projections (Newton converged onto a non-degenerate zero of ∇f) closer than
 * this (× finest cell) are the same start; farther apart they are different zeros, however
 * close: at a coarse depth several critical points share a cell (kummer-4-nodes at depth 3
 * in ±2.2 shifted 0.37 cell, cell 0.55: its 4 nodes 0.47 apart and 0.51 from the critical
 * points off the surface; MERGE_CELLS skipped 3 of the 4). Rank-2 starts (along a curve of
 * zeros) stay MERGE_CELLS apart. */
#define SAME_START_CELLS 1e-6
/* Rank-3 projections tried as starts inside one extended cluster (a node on or near a
 * curve); beyond this the cluster is left to the curve stage as it is. */
#define EXTENDED_STARTS_MAX 64
/* Rank-3 boxes of one extended cluster searched again below the search cell
 * (below_cell_starts): a bound on the work, far above the few such boxes nodes leave at
 * a coarse depth (kummer-4-nodes, depth 3, box shifted 0.37 cell: 114). */
#define BELOW_CELL_BOXES_MAX 256
/* Levels below the search cell of that local search: cells 1/8 of the search cell, finer
 * than the nodes of one cell lie apart in any case seen (Kummer's 4 nodes, all in one cell
 * 0.75 wide at depth 3, are 0.47 apart). */
#define BELOW_CELL_DEPTH 3
/* Candidate boxes one local search may keep (all 8³ of them fit). */
#define BELOW_CELL_SUB_BOXES_MAX 512
/* Rank-2 projections of one extended cluster probed for a cusp (cusp_probe), at
 * least MERGE_CELLS apart: a curve of zeros gives one probe a cell of its length; beyond
 * this many cells of curve in one cluster no further cusp is looked for there. */
#define CUSP_PROBES_MAX 512
/* The probe's difference step (× finest cell): far above rounding of the Hessian, small
 * enough that a curve's bending (second order in the step) keeps its cubic term near 0. */
#define CUSP_PROBE_CELLS 0.01
/* nᵀ D³f[n] n at least this fraction of |D³f[n]|: a cusp's is of the size of the rest
 * (x² + z² − y³: all of it), a curve's is 0 up to the difference's error. */
#define CUSP_CUBIC_REL 1e-2
/* The step along the null direction that tells a point of a curve of zeros of ∇f (on_curve),
 * × finest cell: well inside the smallest whisker loop a cluster can hide (a loop of radius
 * ~ a cell), far above the Newton tolerance. */
#define CURVE_PROBE_CELLS 0.05
/* The rank-1 probe's landing tolerance, relative to |H| × step (|H| × step² for f): a curve
 * of zeros gives rounding there; two spheres of radius R touching give (d/R)²/2 — over it
 * for every d above 1.4e-5 R, so with the smallest step at CURVE_STRICT_MIN_CELLS no contact
 * of sheets a cell or more across passes. Loops below ~4 × that step read as a contact. */
#define CURVE_STRICT_REL 1e-10
#define CURVE_STRICT_MIN_CELLS 1e-3
/* Newton iterations across the curve at a probe (quadratic: a few; slack for a start
 * off the curve by the probe's second-order term). */
#define CURVE_PROBE_NEWTON 30
/* A critical point proved off the surface inside a point cluster is searched for a closed
 * curve of zeros around it (descend) only when the quadratic model of f reaches 0 within
 * this many finest cells of it: a loop the cluster could hide. */
#define DESCEND_REACH_CELLS 1.0
/* ... and a point Newton finds from there counts only when |f| there is below this fraction
 * of |f| at the critical point (it is not the same off-surface point seen again). */
#define DESCEND_F_DROP 1e-3

/* A small loop is left to the curve stage only when its Hessian across clears the seed's
 * rank test by this factor: at the test's edge the tracer's first step loses it (r = 5e-4
 * in ±1: a two-point curve with lost ends), while a point standing for the loop is honest. */
#define LOOP_SEED_MARGIN 2.0

/* Box-to-point distance checks explaining boxes by published points (points × boxes): a
 * bound on the work, far above any real case (16 nodes × a few thousand boxes). */
#define EXPLAIN_WORK_MAX 1e8

enum { NOT_FOUND = 0, FOUND = 1, OFF_SURFACE = 2 };

typedef struct cand {
    ism_sing_point pt;
    uint32_t cluster; /* its cluster, or UINT32_MAX */
    size_t box;       /* its ISM_LBOX_UNIQUE box, or SIZE_MAX */
    size_t order;     /* discovery order (ties of the quality sort) */
} cand;

typedef struct ctx {
    const ism_tape *t;
    const ism_locus_options *o;
    const double *box;  /* the search box: points outside it are not reported */
    ism_eval_ws *ws;
    ism_pcert pc;       /* certificates (point_cert.h) */
    double cell, diag;
    ism_locus *out;
    cand *c;
    size_t nc, capc;
} ctx;

/* The lowest (or, for an indefinite pair, the critical) value of f across the plane of
 * H's two range directions e[0], e[1] through q: a few Newton steps in that plane. */
static double across_value(ctx *x, const double q0[3], double e[2][3])
{
    double q[3] = { q0[0], q0[1], q0[2] }, g[3], h[6];
    static const int S[3][3] = { { 0, 1, 2 }, { 1, 3, 4 }, { 2, 4, 5 } };
    for (int it = 0; it < TYPE_ACROSS_STEPS; it++) {
        ism_eval_hessian(x->t, x->ws, q[0], q[1], q[2], g, h);
        x->out->evals_jet++;
        double r[2], m[2][2];
        for (int a = 0; a < 2; a++) {
            r[a] = e[a][0] * g[0] + e[a][1] * g[1] + e[a][2] * g[2];
            for (int b = 0; b < 2; b++) {
                double v = 0.0;
                for (int i = 0; i < 3; i++)
                    for (int j = 0; j < 3; j++)
                        v += e[a][i] * h[S[i][j]] * e[b][j];
                m[a][b] = v;
            }
        }
        double det = m[0][0] * m[1][1] - m[0][1] * m[1][0];
        if (!(det != 0.0) || !isfinite(det))
            break;
        double s0 = -(m[1][1] * r[0] - m[0][1] * r[1]) / det;
        double s1 = -(m[0][0] * r[1] - m[1][0] * r[0]) / det;
        for (int k = 0; k < 3; k++)
            q[k] += s0 * e[0][k] + s1 * e[1][k];
    }
    return ism_eval_point(x->t, x->ws, q[0], q[1], q[2]);
}

/* The type from the Hessian's eigen-decomposition at p (see points.h). For rank 2, f is
 * followed a little way each side along the null direction, taking at each side the value
 * across the range plane: a sign change is a cusp (x² + z² − y³); the sign of a definite
 * pair on both sides an isolated point (x² + z² + y⁴); anything else (the horn cyclide's
 * touching horns, 384u² + 40uy² + y⁴, dips below 0 across) is degenerate. */
static int point_type(ctx *x, const double p[3], const double eig[3], double vec[3][3])
{
    int rank = ism_sing_rank(eig, x->out->hessian_scale);
    if (rank == 3)
        return (eig[0] > 0.0) == (eig[2] > 0.0) ? ISM_SING_ISOLATED : ISM_SING_NODE;
    if (rank < 2)
        return ISM_SING_DEGENERATE;
    int null = 0; /* the eigenvalue nearest 0 */
    for (int i = 1; i < 3; i++)
        if (fabs(eig[i]) < fabs(eig[null]))
            null = i;
    int a = (null + 1) % 3, b = (null + 2) % 3;
    double e[2][3];
    memcpy(e[0], vec[a], sizeof e[0]);
    memcpy(e[1], vec[b], sizeof e[1]);
    double d = TYPE_PROBE_CELLS * x->cell, s[2];
    for (int m = 0; m < 2; m++) {
        double q[3];
        for (int k = 0; k < 3; k++)
            q[k] = p[k] + (m ? -d : d) * vec[null][k];
        s[m] = across_value(x, q, e);
    }
    if ((s[0] > 0.0 && s[1] < 0.0) || (s[0] < 0.0 && s[1] > 0.0))
        return ISM_SING_CUSP;
    bool up = eig[a] > 0.0;
    bool definite = up == (eig[b] > 0.0);
    bool same = s[0] != 0.0 && s[1] != 0.0 && (s[0] > 0.0) == up && (s[1] > 0.0) == up;
    return definite && same ? ISM_SING_ISOLATED : ISM_SING_DEGENERATE;
}

/* The eigenvector of the smallest |eigenvalue|. */
static const double *null_vector(const double eig[3], double vec[3][3])
{
    int null = 0;
    for (int i = 1; i < 3; i++)
        if (fabs(eig[i]) < fabs(eig[null]))
            null = i;
    return vec[null];
}

/* Whether the rank-2 projection q may be a cusp rather than a point of a curve of zeros of
 * ∇f: f's cubic term along the Hessian's null direction n, nᵀ D³f[n] n, is not 0 there (on a
 * curve with tangent n it is exactly 0, f vanishing along the curve). D³f[n] by a central
 * difference of the Hessian over ±CUSP_PROBE_CELLS along n — a filter only: deflation
 * decides. */
static bool cusp_probe(ctx *x, const double q[3])
{
    double g[3], h[6], hp[6], hm[6], eig[3], vec[3][3];
    ism_eval_hessian(x->t, x->ws, q[0], q[1], q[2], g, h);
    ism_sym3_eigen(h, eig, vec);
    const double *n = null_vector(eig, vec);
    double d = CUSP_PROBE_CELLS * x->cell;
    ism_eval_hessian(x->t, x->ws, q[0] + d * n[0], q[1] + d * n[1], q[2] + d * n[2], g, hp);
    ism_eval_hessian(x->t, x->ws, q[0] - d * n[0], q[1] - d * n[1], q[2] - d * n[2], g, hm);
    x->out->evals_jet += 3;
    static const int S[3][3] = { { 0, 1, 2 }, { 1, 3, 4 }, { 2, 4, 5 } };
    double nn = 0.0, norm = 0.0; /* nᵀ D³f[n] n and the Frobenius norm of D³f[n], × 2d */
    for (int i = 0; i < 3; i++)
        for (int j = 0; j < 3; j++) {
            double t = hp[S[i][j]] - hm[S[i][j]];
            nn += n[i] * t * n[j];
            norm += t * t;
        }
    return isfinite(nn) && fabs(nn) > CUSP_CUBIC_REL * sqrt(norm);
}

/* f's residuals and the Hessian's eigen-decomposition at pt->p. */
static void measure(ctx *x, ism_sing_point *pt, double vec[3][3])
{
    double g[3], h[6];
    pt->residual_f = fabs(ism_eval_hessian(x->t, x->ws, pt->p[0], pt->p[1], pt->p[2], g, h));
    x->out->evals_jet++;
    pt->residual_grad = sqrt(g[0] * g[0] + g[1] * g[1] + g[2] * g[2]);
    ism_sym3_eigen(h, pt->eig, vec);
}

/* An enclosure of f over the cube p ± h: the natural interval, intersected with the
 * second-order Taylor form f(p) + ∇f(p)·D + ½ Dᵀ H(B) D (D = B − p; f(p) and ∇f(p) enclosed
 * at the point, H over the cube) — at a critical point of f ∇f(p) ≈ 0 and only the Hessian
 * term widens it. Linked tori at depth 5 (cell 0.14): on each torus's circle of critical
 * points inside it, f = −0.36, yet the natural interval over the cell holds 0, and 4 to 14
 * uncertified "degenerate points" were reported there (the Taylor form: −0.36 ± 0.1). */
static ism_interval f_near(ctx *x, const double p[3], double h)
{
    ism_interval b[3], at[3], d[3];
    for (int k = 0; k < 3; k++) {
        b[k] = iv(down1(p[k] - h), up1(p[k] + h));
        at[k] = iv(p[k], p[k]);
        d[k] = iv_sub(b[k], at[k]);
    }
    ism_interval f = ism_eval_interval(x->t, x->ws, b[0], b[1], b[2]);
    ism_ivjet jp, jb;
    ism_eval_interval_jet(x->t, x->pc.jw, at, NULL, NULL, &jp);
    ism_eval_interval_jet(x->t, x->pc.jw, b, NULL, NULL, &jb);
    x->out->evals_interval += 3;
    static const int S[3][3] = { { 0, 1, 2 }, { 1, 3, 4 }, { 2, 4, 5 } };
    ism_interval t = jp.v;
    for (int i = 0; i < 3; i++) {
        t = iv_add(t, iv_mul(jp.d[i], d[i]));
        t = iv_add(t, iv_mul_c(iv_mul(jb.h[S[i][i]], iv_square(d[i])), 0.5));
        for (int j = i + 1; j < 3; j++)
            t = iv_add(t, iv_mul(jb.h[S[i][j]], iv_mul(d[i], d[j])));
    }
    if (!(t.lo <= t.hi)) /* NaN: no information */
        return f;
    return iv(fmax(f.lo, t.lo), fmin(f.hi, t.hi));
}

/* Newton from start within [lo, hi], certificate by the Hessian's rank (point_cert.h),
 * off-surface check, type. */
static int resolve(ctx *x, const double start[3], const double lo[3], const double hi[3],
                   double trust, double half_width, ism_sing_point *pt)
{
    memset(pt, 0, sizeof *pt);
    memcpy(pt->p, start, sizeof pt->p);
    ism_newton_opts no = { ISM_SING_PINV_REL_POINT, trust, POINT_NEWTON_TOL * x->diag,
                           POINT_NEWTON_ITERS, lo, hi, false };
    ism_sing_newton(x->t, x->ws, pt->p, &no, &x->out->evals_jet);
    for (int k = 0; k < 3; k++)
        if (!(pt->p[k] >= x->box[k] && pt->p[k] <= x->box[k + 3]))
            return NOT_FOUND; /* a neighbour's point seen through a boundary cell */
    double vec[3][3];
    measure(x, pt, vec);
    int rank = ism_sing_rank(pt->eig, x->out->hessian_scale);
    ism_interval f;
    double before[3] = { pt->p[0], pt->p[1], pt->p[2] };
    if (ism_pcert_point(&x->pc, pt, rank, null_vector(pt->eig, vec), x->cell, &f)
        && memcmp(before, pt->p, sizeof before) != 0)
        measure(x, pt, vec); /* a defining system refined the position */
    if (pt->certified && !(f.lo <= 0.0 && f.hi >= 0.0))
        return OFF_SURFACE;
    if (!pt->certified) {
        f = f_near(x, pt->p, 0.5 * x->cell);
        if (!(f.lo <= 0.0 && f.hi >= 0.0))
            return OFF_SURFACE;
        pt->radius = half_width;
    }
    pt->type = point_type(x, pt->p, pt->eig, vec);
    pt->cones = -1;
    return FOUND;
}

static bool add_cand(ctx *x, const ism_sing_point *pt, uint32_t cluster, size_t box)
{
    if (x->nc == x->capc) {
        size_t c = x->capc ? 2 * x->capc : 16;
        cand *p = realloc(x->c, c * sizeof *p);
        if (!p)
            return false;
        x->c = p;
        x->capc = c;
    }
    x->c[x->nc] = (cand){ *pt, cluster, box, x->nc };
    x->nc++;
    return true;
}

/* Whether both probes at distance d along the unit null direction n of pt land on ∇f = 0:
 * a start d along n each way, Newton across in the plane normal to n (E), and there |∇f| ≤
 * glim and |f| ≤ flim. */
static bool probes_land(ctx *x, const ism_sing_point *pt, const double n[3], double E[2][3],
                        double d, double glim, double flim)
{
    ism_cjet j = { x->t, x->ws, POINT_NEWTON_TOL * x->diag, 0 };
    bool ok = true;
    for (int side = 0; side < 2 && ok; side++) {
        double start[3], q[3], g[3], h[6];
        for (int k = 0; k < 3; k++)
            start[k] = pt->p[k] + (side ? -d : d) * n[k];
        ok = ism_cjet_correct(&j, start, E, E, d, CURVE_PROBE_NEWTON, q, NULL);
        if (ok) {
            double fq = ism_eval_hessian(x->t, x->ws, q[0], q[1], q[2], g, h);
            j.evals++;
            ok = sqrt(g[0] * g[0] + g[1] * g[1] + g[2] * g[2]) <= glim && fabs(fq) <= flim;
        }
    }
    x->out->evals_jet += j.evals;
    return ok;
}

/* Whether the uncertified point pt of Hessian rank 1 or 2 lies on a curve of zeros of ∇f (a
 * whisker circle smaller than a cell, whose boxes cluster like a point's). Rank 2: a step of
 * CURVE_PROBE_CELLS along the Hessian's null direction each way lands on ∇f = 0 again (the
 * curve tracer's test, ISM_CURVE_GRAD_REL) and on f = 0 within the same relative size; at an
 * isolated rank-2 point the null component of ∇f grows off the point (by ~t² at a cusp, t³
 * at an A3 point: those are certified before this is asked). Rank 1 (a loop whose Hessian
 * across is below the rank threshold, or two sheets touching, where ∇f is only cubic along
 * the null plane and passes that test): the landing must hold |∇f| ≤ CURVE_STRICT_REL ×
 * |H| × d and |f| ≤ that × d at some step d from CURVE_PROBE_CELLS down by 4 to
 * CURVE_STRICT_MIN_CELLS — a loop passes once d is well inside it, a contact never. */
static bool on_curve(ctx *x, const ism_sing_point *pt, int rank)
{
    double g[3], h[6], eig[3], vec[3][3];
    ism_eval_hessian(x->t, x->ws, pt->p[0], pt->p[1], pt->p[2], g, h);
    x->out->evals_jet++;
    ism_sym3_eigen(h, eig, vec);
    const double *n = null_vector(eig, vec);
    double E[2][3], big = fmax(fabs(eig[0]), fabs(eig[2]));
    ism_across_least3(n, E);
    double d = CURVE_PROBE_CELLS * x->cell;
    if (rank == 2) {
        double lim = ISM_CURVE_GRAD_REL * fmax(x->out->hessian_scale, big) * x->diag;
        return probes_land(x, pt, n, E, d, lim, lim * x->diag);
    }
    for (; d >= CURVE_STRICT_MIN_CELLS * x->cell; d *= 0.25)
        if (probes_land(x, pt, n, E, d, CURVE_STRICT_REL * big * d, CURVE_STRICT_REL * big * d * d))
            return true;
    return false;
}

/* Whether the rank-2 projection q, whose cubic term along the null direction n is 0
 * (cusp_probe false), is no point of a curve of zeros of ∇f: an isolated zero where f is
 * quartic or higher along n (an A3 point) — the horn cyclide's (a, 0, 0), f ≈ 384(u² + z²)
 * + 40u y² + y⁴ (u = x − a). At depth 3 in its box (cell 4) that point's cells join one
 * cluster with the tube's and with critical points off the surface; its projections,
 * (10, ±0.0009, 0), were taken for a curve's, no start was tried, and the curve stage
 * traced a two-point whisker with lost ends. A step of CURVE_PROBE_CELLS along n each way
 * and Newton across land on ∇f = 0 to rounding (CURVE_STRICT_REL × |H| × step) on a curve of
 * zeros; at an A3 point the null component left there is cubic in the step (0.17 d³ on the
 * horn, 1.7e-4 at depth 4 — under on_curve's rank-2 bound, 1e-9 × the box's Hessian scale
 * × diagonal = 6e-4, which took it for a curve). A curve taken for a point here costs one
 * Newton and a certificate that fails: only certified points are kept. */
static bool isolated_rank2(ctx *x, const double q[3])
{
    double g[3], h[6], eig[3], vec[3][3], E[2][3];
    ism_eval_hessian(x->t, x->ws, q[0], q[1], q[2], g, h);
    x->out->evals_jet++;
    ism_sym3_eigen(h, eig, vec);
    const double *n = null_vector(eig, vec);
    ism_across_least3(n, E);
    ism_sing_point pt = { .cones = -1 };
    memcpy(pt.p, q, sizeof pt.p);
    double d = CURVE_PROBE_CELLS * x->cell, big = fmax(fabs(eig[0]), fabs(eig[2]));
    return !probes_land(x, &pt, n, E, d, CURVE_STRICT_REL * big * d,
                        CURVE_STRICT_REL * big * d * d);
}

/* Bounds of a cluster's boxes and of its boxes' projections. */
typedef struct cluster_info {
    double lo[3], hi[3];   /* boxes */
    double qlo[3], qhi[3]; /* projections */
    size_t first_projected, projected;
    uint8_t fate;          /* 0 left alone, 1 explained (USED), 2 removed */
} cluster_info;

static void gather(const ism_locus *l, const uint32_t *label, cluster_info *ci, size_t nclusters)
{
    for (size_t c = 0; c < nclusters; c++) {
        ci[c] = (cluster_info){ .first_projected = SIZE_MAX };
        for (int k = 0; k < 3; k++) {
            ci[c].lo[k] = ci[c].qlo[k] = INFINITY;
            ci[c].hi[k] = ci[c].qhi[k] = -INFINITY;
        }
    }
    for (size_t i = 0; i < l->nboxes; i++) {
        const ism_lbox *b = &l->boxes[i];
        cluster_info *c = &ci[label[i]];
        for (int k = 0; k < 3; k++) {
            c->lo[k] = fmin(c->lo[k], b->lo[k]);
            c->hi[k] = fmax(c->hi[k], b->hi[k]);
        }
        if (!(b->flags & ISM_LBOX_PROJECTED))
            continue;
        if (c->projected++ == 0)
            c->first_projected = i;
        for (int k = 0; k < 3; k++) {
            c->qlo[k] = fmin(c->qlo[k], b->q[k]);
            c->qhi[k] = fmax(c->qhi[k], b->q[k]);
        }
    }
}

static bool is_point_cluster(const ctx *x, const cluster_info *c)
{
    if (!c->projected)
        return false;
    for (int k = 0; k < 3; k++)
        if (c->qhi[k] - c->qlo[k] > POINT_SPREAD_CELLS * x->cell)
            return false;
    return true;
}

/* A critical point c proved off the surface in a point cluster may be the centre of a closed
 * curve of zeros of ∇f on f = 0 that the cluster's cells cannot show ((x² + y² − r²)² + z²
 * with r below a cell: f = r⁴ at the centre, every box's projection lands there, and the
 * loop was dropped with it). f falls to 0 from c along an eigenvector of the Hessian whose
 * eigenvalue λ has the sign opposite to f(c), at about t = √(2|f(c)|/|λ|) (the quadratic
 * model); Newton from there, both ways along each such direction, lands on the curve when
 * there is one. A landing point on a curve of zeros (on_curve) is returned as it is, with
 * *loop set (no point certificate applies to a point of a curve: a defining system would
 * move it to a least-squares point off the loop); else resolve's verdict from there when it
 * is FOUND; else OFF_SURFACE (*pt untouched). */
static int descend(ctx *x, const double c[3], const double lo[3], const double hi[3],
                   double half, ism_sing_point *pt, bool *loop)
{
    double g[3], h[6], eig[3], vec[3][3];
    double fc = ism_eval_hessian(x->t, x->ws, c[0], c[1], c[2], g, h);
    x->out->evals_jet++;
    ism_sym3_eigen(h, eig, vec);
    for (int i = 0; i < 3; i++) {
        if (!(fc * eig[i] < 0.0))
            continue;
        double t = sqrt(2.0 * fabs(fc) / fabs(eig[i]));
        if (!(t <= DESCEND_REACH_CELLS * x->cell))
            continue;
        for (int side = 0; side < 2; side++) {
            ism_sing_point q = { .cones = -1, .radius = half };
            for (int k = 0; k < 3; k++)
                q.p[k] = c[k] + (side ? -t : t) * vec[i][k];
            ism_newton_opts no = { ISM_SING_PINV_REL_POINT, x->cell, POINT_NEWTON_TOL * x->diag,
                                   POINT_NEWTON_ITERS, lo, hi, false };
            ism_sing_newton(x->t, x->ws, q.p, &no, &x->out->evals_jet);
            double qv[3][3];
            measure(x, &q, qv);
            if (!(q.residual_f <= DESCEND_F_DROP * fabs(fc)))
                continue; /* back at c, or elsewhere off the surface */
            int rank = ism_sing_rank(q.eig, x->out->hessian_scale);
            if ((rank == 1 || rank == 2) && on_curve(x, &q, rank)) {
                *pt = q;
                *loop = true;
                return FOUND;
            }
            if (resolve(x, q.p, lo, hi, x->cell, half, &q) == FOUND) {
                *pt = q;
                return FOUND;
            }
        }
    }
    return OFF_SURFACE;
}

/* The uncertified point pt of a point cluster lies on a closed curve of zeros (on_curve):
 * when the curve stage can start there (ism_cjet_seed_ok), the cluster's first projected box
 * becomes its seed (q on the curve, rank 2) and NOT_FOUND is returned; else the loop is too
 * small to trace (the Hessian across it below LOOP_SEED_MARGIN × the rank threshold: r < 7e-4
 * for (x² + y² − r²)² + z², whose Hessian across is diag(8r², 2)) and pt stands for it, its radius the farthest corner of the
 * cluster's boxes (the search keeps every cell the loop meets). */
static int small_loop(ctx *x, const cluster_info *c, ism_sing_point *pt)
{
    ism_cjet j = { x->t, x->ws, POINT_NEWTON_TOL * x->diag, 0 };
    ism_cpoint s;
    ism_cjet_frame(&j, pt->p, NULL, &s);
    x->out->evals_jet += j.evals;
    if (ism_cjet_seed_ok(&s, x->out->hessian_scale, x->diag, LOOP_SEED_MARGIN)) {
        ism_lbox *b = &x->out->boxes[c->first_projected];
        memcpy(b->q, pt->p, sizeof b->q);
        b->rank = 2;
        return NOT_FOUND; /* left to the curve stage */
    }
    double r2 = 0.0;
    for (int k = 0; k < 3; k++) {
        double d = fmax(pt->p[k] - c->lo[k], c->hi[k] - pt->p[k]);
        r2 += d * d;
    }
    pt->radius = sqrt(r2);
    pt->type = ISM_SING_DEGENERATE;
    pt->uncertified_why = ISM_UNCERT_LOOP;
    pt->exists_radius = 0.0;
    return FOUND;
}

/* A Krawczyk box of the search: Newton inside it (grown by half), certify. */
static bool from_unique_box(ctx *x, size_t i, uint8_t *box_fate)
{
    const ism_lbox *b = &x->out->boxes[i];
    double lo[3], hi[3], w = 0.0;
    for (int k = 0; k < 3; k++) {
        double half = 0.5 * (b->hi[k] - b->lo[k]);
        lo[k] = b->lo[k] - half;
        hi[k] = b->hi[k] + half;
        w = fmax(w, 2.0 * half);
    }
    ism_sing_point pt;
    int r = resolve(x, b->q, lo, hi, w, 0.5 * w, &pt);
    box_fate[i] = r == FOUND ? 1 : r == OFF_SURFACE ? 2 : 0;
    return r != FOUND || add_cand(x, &pt, UINT32_MAX, i);
}

/* Newton from start within [lo, hi]; a certified point on the surface whose Hessian has
 * rank min_rank or more is a candidate. *off (may be NULL) is set when the point reached is a
 * critical point proved off the surface. False only when out of memory. */
static bool certified_from(ctx *x, const double start[3], const double lo[3],
                           const double hi[3], double half, int min_rank, bool *off)
{
    ism_sing_point pt;
    int r = resolve(x, start, lo, hi, x->cell, half, &pt);
    if (off && r == OFF_SURFACE)
        *off = true;
    return !(r == FOUND && pt.certified && ism_sing_rank(pt.eig, x->out->hessian_scale) >= min_rank)
           || add_cand(x, &pt, UINT32_MAX, SIZE_MAX);
}

/* One box of a cluster searched again as a box of its own, BELOW_CELL_DEPTH levels below
 * the search cell (search.h): Newton from every sub-cell projected (with a Hessian of rank
 * min_rank or more there) or proved to hold one zero of ∇f, within lo..hi; only certified
 * points of that rank are kept. A sub-search cut short (budget, deadline) marks the locus
 * incomplete. False only when out of memory. */
static bool search_below(ctx *x, const ism_lbox *b, const double lo[3], const double hi[3],
                         double half, int min_rank)
{
    ism_locus_options so = *x->o;
    memcpy(so.box, b->lo, sizeof so.box[0] * 3);
    memcpy(so.box + 3, b->hi, sizeof so.box[0] * 3);
    so.max_depth = BELOW_CELL_DEPTH;
    so.max_boxes = BELOW_CELL_SUB_BOXES_MAX;
    so.threads = 1;
    ism_locus sub;
    ism_locus_init(&sub);
    ism_error err;
    bool ok = ism_sing_search(x->t, &so, &sub, &err);
    x->out->evals_interval += sub.evals_interval;
    x->out->evals_jet += sub.evals_jet;
    x->out->centre_dropped += sub.centre_dropped;
    x->out->grads_batched += sub.grads_batched;
    x->out->grads_batch_read += sub.grads_batch_read;
    x->out->centres_batched += sub.centres_batched;
    x->out->centres_batch_read += sub.centres_batch_read;
    for (size_t j = 0; ok && j < sub.nboxes; j++)
        if ((sub.boxes[j].flags & ISM_LBOX_UNIQUE)
            || ((sub.boxes[j].flags & ISM_LBOX_PROJECTED) && sub.boxes[j].rank >= min_rank))
            ok = certified_from(x, sub.boxes[j].q, lo, hi, half, min_rank, NULL);
    if (ok && sub.incomplete && !x->out->incomplete) {
        x->out->incomplete = true;
        snprintf(x->out->incomplete_why, sizeof x->out->incomplete_why,
                 "singular points, a search below the cell: %.40s", sub.incomplete_why);
    }
    ism_locus_free(&sub);
    return ok;
}

/* Newton from b's centre converged inside b itself. A projection the search accepted in the
 * cell grown by half (ISM_LBOX_PROJECTED) may lie outside the cell: a rank-3 one there is a
 * critical point Newton was drawn to from the cell — the heart at depth 3 in its box moved by
 * (√2 − 1, −(√5 − 1)/4, 1/e) cell: the cusp (0, 0, 1)'s cell projected onto the critical point
 * (0, 0.441, 0.810) off the surface, 0.18 beyond the cell, and the cusp was lost. Such a cell
 * is searched below as an unprojected one; a rank-2 projection outside (a curve's point) is
 * the curve stage's. */
static bool projected_inside(const ism_lbox *b)
{
    if (!(b->flags & ISM_LBOX_PROJECTED))
        return false;
    if (b->rank < 3)
        return true;
    for (int k = 0; k < 3; k++)
        if (b->q[k] < b->lo[k] || b->q[k] > b->hi[k])
            return false;
    return true;
}

/* Which boxes of a cluster below_cell_starts searches again. */
enum { BELOW_RANK3 = 0,       /* rank 3, not a Krawczyk box (an extended cluster) */
       BELOW_UNPROJECTED = 1, /* Newton from the centre left the cell (a point cluster):
                                 not projected, or projected outside onto a rank-3 point
                                 (projected_inside) */
       BELOW_UNPROJECTED_ISOLATED = 2 /* the same in an extended cluster, for points of
                                         Hessian rank 2 or 3 only (cusps, A3 points, nodes,
                                         isolated points): points of rank 0 or 1 there are
                                         the ends of its curves (pinch, triple points),
                                         which the curve stage finds and types */ };

/* The boxes of cluster id that `which` selects, each searched below the cell (search_below),
 * at most BELOW_CELL_BOXES_MAX of them. BELOW_RANK3, in an extended cluster: each may hold
 * points its projection did not reach — Newton from the centre left the cell
 * (kummer-4-nodes at depth 3 in ±3, cell 0.75, projects only onto its 8 critical points off
 * the surface, and its 4 nodes' cells stay unprojected), or landed on one of several points
 * in the cell (the same box shifted (0.37, −0.23, 0.41) cell puts 3 nodes in one cell,
 * projected onto one). Only in clusters whose every projection has rank 3 (points, not a
 * curve's or sheet's cells: there it would triple the stage's work on steiner-roman,
 * cross-cap and heart at depth 7 for nothing found). BELOW_UNPROJECTED, in a point cluster
 * whose projections all landed on one critical point off the surface: the cluster would be
 * dropped whole with it, and its unprojected boxes with it — isolated-point at depth 3 in
 * its box shifted 0.37 cell (cells 0.33 × 0.2 × 0.2): the origin's cell joins the cells
 * between it and the sphere, whose projections reach only the saddle at (0.377, 0, 0) off
 * the surface, and Newton from the origin's cell centre left it; the isolated point was
 * lost. BELOW_UNPROJECTED_ISOLATED: an extended cluster one of whose starts reached a
 * critical point off the surface (from_cluster). */
static bool below_cell_starts(ctx *x, uint32_t id, const uint32_t *label, const double lo[3],
                               const double hi[3], double half, int which)
{
    const ism_locus *l = x->out;
    for (size_t i = 0; which == BELOW_RANK3 && i < l->nboxes; i++)
        if (label[i] == id && (l->boxes[i].flags & ISM_LBOX_PROJECTED) && l->boxes[i].rank < 3)
            return true; /* a curve's or sheet's cluster: left to those stages as it is */
    size_t boxes = 0;
    for (size_t i = 0; i < l->nboxes && boxes < BELOW_CELL_BOXES_MAX; i++) {
        const ism_lbox *b = &l->boxes[i];
        bool want = which == BELOW_RANK3 ? b->rank == 3 : !projected_inside(b);
        if (label[i] != id || (b->flags & ISM_LBOX_UNIQUE) || !want)
            continue;
        boxes++;
        if (!search_below(x, b, lo, hi, half, which == BELOW_UNPROJECTED_ISOLATED ? 2 : 0))
            return false;
    }
    return true;
}

/* An isolated cluster: Newton from its first projection, within the cluster grown by a
 * cell. Rank-3 projections of an extended cluster, and rank-2 ones whose cubic term along
 * the null direction is not 0 (cusps): only certified points are kept. When one of those
 * starts reaches a critical point proved off the surface, the cluster's cells are coarse
 * enough to join the surface with critical structure off it, and Newton from a cell's centre
 * may have been drawn there from a point in the cell: its unprojected boxes are searched
 * below the cell for points of rank 2 or 3 (BELOW_UNPROJECTED_ISOLATED). The heart at depth 3 (cell
 * 0.375): one cluster for the whole surface with the lobes' critical points (±0.53, 0, 0.65)
 * and (±0.79, 0, 0.96) off it; Newton from the four cells round the cusp (0, 0, 1) went
 * towards them, and the cusp was lost. Finer, those cells are excluded by F (heart, depths
 * 6-7: no off-surface start, no extra work). */
static bool from_cluster(ctx *x, const cluster_info *c, uint32_t id, const uint32_t *label,
                         uint8_t *fate)
{
    const ism_locus *l = x->out;
    double lo[3], hi[3], half = 0.0;
    for (int k = 0; k < 3; k++) {
        lo[k] = c->lo[k] - x->cell;
        hi[k] = c->hi[k] + x->cell;
        half = fmax(half, 0.5 * (c->hi[k] - c->lo[k]));
    }
    if (is_point_cluster(x, c)) {
        ism_sing_point pt;
        int r = resolve(x, l->boxes[c->first_projected].q, lo, hi, x->cell, half, &pt);
        bool loop = false;
        if (r == OFF_SURFACE) {
            r = descend(x, pt.p, lo, hi, half, &pt, &loop);
            if (r == OFF_SURFACE
                && !below_cell_starts(x, id, label, lo, hi, half, BELOW_UNPROJECTED))
                return false;
        } else if (r == FOUND && !pt.certified) {
            int rank = ism_sing_rank(pt.eig, l->hessian_scale);
            loop = (rank == 1 || rank == 2) && on_curve(x, &pt, rank);
        }
        if (r == FOUND && loop)
            r = small_loop(x, c, &pt); /* a small closed curve */
        *fate = r == FOUND ? 1 : r == OFF_SURFACE ? 2 : 0;
        return r != FOUND || add_cand(x, &pt, id, SIZE_MAX);
    }
    size_t tried = 0, probed = 0;
    bool off = false; /* a start reached a critical point off the surface */
    double starts[EXTENDED_STARTS_MAX][3], probes[CUSP_PROBES_MAX][3];
    for (size_t i = c->first_projected; i < l->nboxes && tried < EXTENDED_STARTS_MAX; i++) {
        const ism_lbox *b = &l->boxes[i];
        if (label[i] != id || !(b->flags & ISM_LBOX_PROJECTED) || b->rank < 2)
            continue;
        bool seen = false;
        if (b->rank == 2) { /* a cusp or A3 point among the points of a curve */
            /* the probes are all taken: no rank-2 box is probed, seen or not (the scan of
             * all 512 for each later box was 17M instructions of the Klein bottle's 3,410M
             * at E 0.00327: 2,074 of its 3,110 rank-2 boxes came after the probes ran out) */
            if (probed == CUSP_PROBES_MAX)
                continue;
            /* latest first: boxes come in key order, so along a curve the probe that covers
             * a box is one of the last few (coordinate-planes: 372 probes, 1,520 boxes) */
            for (size_t s = probed; s-- > 0 && !seen;)
                seen = ism_dist3(probes[s], b->q) <= MERGE_CELLS * x->cell;
            if (seen)
                continue;
            memcpy(probes[probed++], b->q, sizeof probes[0]);
            if (!cusp_probe(x, b->q) && !isolated_rank2(x, b->q))
                continue;
        }
        double same = (b->rank == 3 ? SAME_START_CELLS : MERGE_CELLS) * x->cell;
        for (size_t s = 0; s < tried && !seen; s++)
            seen = ism_dist3(starts[s], b->q) <= same;
        if (seen)
            continue;
        memcpy(starts[tried++], b->q, sizeof starts[0]);
        if (!certified_from(x, b->q, lo, hi, half, 0, &off))
            return false;
    }
    return below_cell_starts(x, id, label, lo, hi, half, BELOW_RANK3)
           && (!off || below_cell_starts(x, id, label, lo, hi, half, BELOW_UNPROJECTED_ISOLATED))
           && !x->pc.oom;
}

static bool same_point(const ctx *x, const ism_sing_point *a, const ism_sing_point *b)
{
    if (a->certified && b->certified) {
        for (int k = 0; k < 3; k++)
            if (fabs(a->p[k] - b->p[k]) > a->radius + b->radius)
                return false;
        return true;
    }
    return ism_dist3(a->p, b->p) <= MERGE_CELLS * x->cell;
}

/* Best first: certified, then the smaller gradient residual, then the earlier. */
static int by_quality(const void *pa, const void *pb)
{
    const cand *a = pa, *b = pb;
    if (a->pt.certified != b->pt.certified)
        return a->pt.certified ? -1 : 1;
    if (a->pt.residual_grad != b->pt.residual_grad)
        return a->pt.residual_grad < b->pt.residual_grad ? -1 : 1;
    return a->order < b->order ? -1 : a->order > b->order;
}

static int by_position(const void *pa, const void *pb)
{
    const ism_sing_point *a = pa, *b = pb;
    for (int k = 2; k >= 0; k--)
        if (a->p[k] != b->p[k])
            return a->p[k] < b->p[k] ? -1 : 1;
    return 0;
}

/* Merges duplicates and appends the survivors to out->points in position order. */
static bool publish(ctx *x)
{
    cand *sorted = malloc((x->nc ? x->nc : 1) * sizeof *sorted);
    ism_sing_point *keep = malloc((x->nc ? x->nc : 1) * sizeof *keep);
    if (!sorted || !keep) {
        free(sorted);
        free(keep);
        return false;
    }
    if (x->nc)
        memcpy(sorted, x->c, x->nc * sizeof *sorted);
    qsort(sorted, x->nc, sizeof *sorted, by_quality);
    size_t nk = 0;
    for (size_t i = 0; i < x->nc; i++) {
        bool dup = false;
        for (size_t j = 0; j < nk && !dup; j++)
            dup = same_point(x, &sorted[i].pt, &keep[j]);
        if (!dup)
            keep[nk++] = sorted[i].pt;
    }
    qsort(keep, nk, sizeof *keep, by_position);
    bool ok = true;
    for (size_t i = 0; ok && i < nk; i++)
        ok = ism_locus_add_point(x->out, &keep[i]);
    free(sorted);
    free(keep);
    return ok;
}

/* Boxes of clusters that are not one point but whose projections landed on published points
 * (a cluster holding two nodes' halos at a coarse depth) are explained by those points: each
 * such box, and the whole cluster when all its projections are explained. */
static void explain_by_points(const ctx *x, const uint32_t *label, size_t nclusters,
                              uint8_t *cluster_fate, uint8_t *box_fate)
{
    const ism_locus *l = x->out;
    if (!l->npoints || (double)l->npoints * (double)l->nboxes > EXPLAIN_WORK_MAX)
        return;
    uint8_t *all = malloc(nclusters ? nclusters : 1);
    if (!all)
        return;
    memset(all, 1, nclusters ? nclusters : 1);
    for (size_t i = 0; i < l->nboxes; i++) {
        const ism_lbox *b = &l->boxes[i];
        if (!(b->flags & ISM_LBOX_PROJECTED) || cluster_fate[label[i]] || box_fate[i])
            continue;
        bool near = false;
        for (size_t j = 0; j < l->npoints && !near; j++)
            near = ism_dist3(b->q, l->points[j].p) <= MERGE_CELLS * x->cell;
        if (near)
            box_fate[i] = 1;
        else
            all[label[i]] = 0;
    }
    for (size_t c = 0; c < nclusters; c++)
        if (!cluster_fate[c] && all[c])
            cluster_fate[c] = 1;
    free(all);
}

/* Flags explained boxes USED and removes boxes explained by off-surface critical points. */
static void settle_boxes(ism_locus *l, const uint32_t *label, const uint8_t *cluster_fate,
                         const uint8_t *box_fate)
{
    size_t n = 0;
    for (size_t i = 0; i < l->nboxes; i++) {
        uint8_t fate = box_fate[i] ? box_fate[i] : cluster_fate[label[i]];
        if (fate == 2)
            continue;
        l->boxes[n] = l->boxes[i];
        if (fate == 1)
            l->boxes[n].flags |= ISM_LBOX_USED;
        n++;
    }
    l->nboxes = n;
}

static bool run(ctx *x, const ism_locus_options *o)
{
    ism_locus *l = x->out;
    size_t n = l->nboxes;
    uint32_t *label = malloc((n ? n : 1) * sizeof *label);
    uint8_t *box_fate = calloc(n ? n : 1, 1);
    size_t nclusters = label ? ism_sing_clusters(o, l->boxes, n, label) : (size_t)-1;
    cluster_info *ci = nclusters != (size_t)-1 ? malloc((nclusters ? nclusters : 1) * sizeof *ci) : NULL;
    uint8_t *fate = ci ? calloc(nclusters ? nclusters : 1, 1) : NULL;
    bool ok = label && box_fate && fate;
    if (ok)
        gather(l, label, ci, nclusters);
    const char *during = "the singular-point certification";
    for (size_t i = 0; ok && i < n && !ism_locus_out_of_time(o, l, during); i++)
        if (l->boxes[i].flags & ISM_LBOX_UNIQUE)
            ok = from_unique_box(x, i, box_fate);
    for (size_t c = 0; ok && c < nclusters && !ism_locus_out_of_time(o, l, during); c++)
        if (ci[c].projected)
            ok = from_cluster(x, &ci[c], (uint32_t)c, label, &fate[c]);
    ok = ok && publish(x);
    if (ok) {
        explain_by_points(x, label, nclusters, fate, box_fate);
        settle_boxes(l, label, fate, box_fate);
    }
    free(label);
    free(box_fate);
    free(ci);
    free(fate);
    return ok;
}

bool ism_sing_points(const ism_tape *f, const ism_locus_options *o, ism_locus *out,
                     ism_error *err)
{
    double t0 = ism_now_ms();
    ctx x = { .t = f, .o = o, .box = o->box, .out = out };
    double cells = ldexp(1.0, o->max_depth);
    for (int k = 0; k < 3; k++)
        x.cell = fmax(x.cell, (o->box[k + 3] - o->box[k]) / cells);
    x.diag = ism_box_diagonal(o->box);
    x.ws = ism_eval_ws_new(f);
    bool ok = ism_pcert_init(&x.pc, f, x.diag, out->hessian_scale, &out->evals_jet) && x.ws && run(&x, o)
              && !x.pc.oom;
    ism_eval_ws_free(x.ws);
    ism_pcert_free(&x.pc);
    free(x.c);
    out->time_ms += ism_now_ms() - t0;
    if (!ok)
        return ism_error_set(err, "singular points: out of memory");
    return true;
}
