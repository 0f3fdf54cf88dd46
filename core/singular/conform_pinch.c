/* conform_pinch.c — a tube's rim and rings beside a pinch point, in the chart of the umbrella
 * there. Near a pinch point the surface is, to first order, Whitney's umbrella x² = y² z: the
 * double curve along z > 0 (the tangent c), the two sheets x = ±y √z lying apart along the
 * Hessian's one eigenvector of non-zero eigenvalue (n: rank 1 at a pinch point), folded into
 * each other round the line x = z = 0 (e = c × n) with radius y² / 2 — under a cell within a
 * few cells of the point. Its smooth chart is (y, v) with v = x / y, the sheet's own
 * parameter: v < 0 on one sheet, v > 0 on the other, and a tube's rim round the curve's end
 * runs monotone in v from one sheet round the fold onto the other:
 *
 *      z (c)  ╲   ╱  sheets x = ±y√z       rim vertex q (frame coordinates h, xn, xe):
 *       │      ╲ ╱                         s = rho · xn / xe, the parameter the rim runs
 *   ────●───────●────── fold (e)           along; ring point at fraction t: (t xn, t xe)
 *     pinch    ╱ ╲   the rim's cap          at height h, moved along c onto f = 0
 *
 * Rim: along the curve the feet say which way the rim runs (conform_ears.c); round the
 * curve's end they all lie at the pinch, and the polygoniser's vertices beside the fold step
 * back and forth across it. Each run of rim vertices whose feet lie within
 * CF_PINCH_REACH_RHO tube radii of a pinch point is read in the chart (s, and the distance to
 * the tangent line) and its backward steps are clipped as ears (cf_clip_ears).
 *
 * Rings (every loop's, also one along several curves, zipped by its rim's feet: each of
 * Steiner's four loops passes three pinch points): elsewhere a ring point is
 * foot + t (q − foot) moved onto f = 0 along ∇f. On the cap
 * that is P + t (q − P) (the foot is the pinch point), below the fold's vertex at the smaller
 * section (z = −x² on a cross-cap), where ∇f points along the curve on the fold and across
 * it on the sheets: Newton slid the ring points onto the fold from either sheet, out of their
 * order round it, and every ladder quad between two swapped points turned over (cross-cap,
 * depth 7, lattice box: all 32 turned-over edges, on rings 1.8 and 3.8 cells out, running
 * +, −, +, − across the fold). Here the foot is taken on the tangent line (past the end for
 * the cap) and the ring point moves along the tangent only: its place across the curve — its
 * order round the rim — stays the rim vertex's scaled by t; on the umbrella itself
 * (t x, t y, z) lies on x² = y² z when (x, y, z) does. The zip then reads each ring vertex's
 * parameter from where it went (cf_pinch_param). Below a rim edge that crosses the fold the
 * rings of its nearer end are scaled from the edge's point on the fold instead, and stay on
 * it (cf_pinch_rim_points, below). */
#include "core/singular/conform_internal.h"
#include "core/util/vec3.h"

#include "core/util/sym3.h"

#include <math.h>
#include <stdlib.h>

/* The tangent at the pinch is the chord to the curve point this many tube radii along it: the
 * direction across the width the chart is used over (the presets' double segments are
 * straight; a curved one bends little across a tube's width). */
#define PINCH_TANGENT_RHO 1.0
/* Newton steps along the tangent (the section is near-linear in it: a few suffice, as for
 * cf_project). */
#define PINCH_STEPS 8

void cf_pinch_ends(cf_ctx *c, const cf_polyline *pl, size_t npl, double rho, cf_pinch *out)
{
    for (size_t k = 0; k < npl; k++)
        for (int e = 0; e < 2; e++) {
            cf_pinch *ch = &out[2 * k + e];
            ch->on = false;
            if (pl[k].closed || pl[k].n < 2 || !pl[k].pinch[e])
                continue;
            /* the end point and the first curve point PINCH_TANGENT_RHO rho or more from it */
            size_t end = e ? pl[k].n - 1 : 0, j = end;
            for (size_t i = 1; i < pl[k].n; i++) {
                j = e ? pl[k].n - 1 - i : i;
                if (fabs(pl[k].s[j] - pl[k].s[end]) >= PINCH_TANGENT_RHO * rho)
                    break;
            }
            const double *p = pl[k].p + 3 * end, *q = pl[k].p + 3 * j;
            double d[3] = {q[0] - p[0], q[1] - p[1], q[2] - p[2]}, len = ism_norm3(d);
            /* the sheets' direction apart: the Hessian's eigenvector of the largest |λ| (its
             * rank is 1 at a pinch point), made normal to the tangent */
            double g[3], h[6], eig[3], vec[3][3];
            ism_eval_hessian(c->f, c->ws, p[0], p[1], p[2], g, h);
            ism_sym3_eigen(h, eig, vec);
            int big = fabs(eig[0]) > fabs(eig[2]) ? 0 : 2;
            if (!(len > 0) || !isfinite(eig[big]) || eig[big] == 0)
                continue;
            for (int i = 0; i < 3; i++) {
                ch->p[i] = p[i];
                ch->c[i] = d[i] / len;
                ch->n[i] = vec[big][i];
            }
            double nc = ism_dot3(ch->n, ch->c);
            for (int i = 0; i < 3; i++)
                ch->n[i] -= nc * ch->c[i];
            if (!(ism_normalise3(ch->n) > 0))
                continue;
            ism_cross3(ch->c, ch->n, ch->e);
            ch->end = e;
            ch->on = true;
        }
}

double cf_pinch_param(const cf_pinch *ch, const cf_polyline *pl, const double q[3])
{
    double h = (q[0] - ch->p[0]) * ch->c[0] + (q[1] - ch->p[1]) * ch->c[1] +
               (q[2] - ch->p[2]) * ch->c[2];
    h = fmin(fmax(h, 0.0), pl->length);
    return ch->end ? pl->length - h : h;
}

const cf_pinch *cf_pinch_near(const cf_pinch *ends, const cf_polyline *pl, int k, double s,
                              double reach)
{
    for (int e = 0; e < 2; e++) {
        const cf_pinch *ch = &ends[2 * (size_t)k + e];
        if (ch->on && (e ? pl[k].length - s : s) <= reach)
            return ch;
    }
    return NULL;
}

/* The point's coordinates in the chart's frame: along the tangent, the sheets' normal, the
 * fold. */
static void frame(const cf_pinch *ch, const double q[3], double *h, double *xn, double *xe)
{
    double d[3] = {q[0] - ch->p[0], q[1] - ch->p[1], q[2] - ch->p[2]};
    *h = ism_dot3(d, ch->c);
    *xn = ism_dot3(d, ch->n);
    *xe = ism_dot3(d, ch->e);
}

void cf_pinch_ring_point(cf_ctx *c, const cf_pinch *ch, const double q[3], double t,
                         double out[3])
{
    double h, xn, xe, foot[3], p[3];
    frame(ch, q, &h, &xn, &xe);
    for (int k = 0; k < 3; k++) {
        foot[k] = ch->p[k] + h * ch->c[k];
        p[k] = foot[k] + t * (q[k] - foot[k]);
        out[k] = p[k];
    }
    /* the section moves by (1 − t²) of the fold's depth below the rim (z = −x² on a
     * cross-cap): at most the ring's distance to the rim */
    double max_move = ism_dist3(q, foot), z = 0;
    cf_poll(c, 1);
    for (int it = 0; it < PINCH_STEPS; it++) {
        double x[3] = {p[0] + z * ch->c[0], p[1] + z * ch->c[1], p[2] + z * ch->c[2]}, g[3];
        double fv = ism_eval_gradient(c->f, c->ws, x[0], x[1], x[2], g);
        double gc = ism_dot3(g, ch->c);
        if (fv == 0)
            break;
        z = fabs(gc) > 0 && isfinite(fv) ? z - fv / gc : NAN;
        if (!(fabs(z) <= max_move)) { /* no root of the section nearby: as elsewhere */
            cf_project(c, out, 0.5 * t * ism_dist3(q, foot));
            return;
        }
    }
    for (int k = 0; k < 3; k++)
        out[k] = p[k] + z * ch->c[k];
}

/* Runs of at least this many loop vertices in one pinch chart are smoothed (cf_clip_ears
 * reads a direction over DIR_WINDOW edges each side and never clips an open run's ends). */
#define PINCH_RUN_MIN 8

int cf_pinch_ears(cf_ctx *c, const cf_pinch *ends, const cf_polyline *pl, cf_loop *l,
                  double *u, double *foot, int *cid, double reach, double rho)
{
    size_t n = l->n;
    if (n < PINCH_RUN_MIN)
        return 0;
    const cf_pinch **ch = malloc(n * sizeof *ch);
    uint32_t *v = malloc(n * sizeof *v);
    double *s = malloc(n * sizeof *s), *ft = malloc(3 * n * sizeof *ft);
    size_t *src = malloc(n * sizeof *src);
    bool *keep = malloc(n * sizeof *keep);
    int clipped = 0;
    if (!ch || !v || !s || !ft || !src || !keep) {
        clipped = -1;
        goto done;
    }
    for (size_t i = 0; i < n; i++) {
        ch[i] = cf_pinch_near(ends, pl, cid[i], u[i], reach);
        keep[i] = true;
    }
    /* a closed loop is read from a change of chart (none: one run all round, closed) */
    size_t start = 0;
    bool whole = false;
    if (l->closed) {
        while (start < n && ch[start] == ch[(start + n - 1) % n])
            start++;
        whole = start == n;
        start = whole ? 0 : start;
    }
    cf_polyline flat = {0}; /* an open parameter line: steps are differences of s */
    for (size_t a = 0; a < n;) {
        size_t i0 = (start + a) % n;
        const cf_pinch *cur = ch[i0];
        size_t len = 0;
        while (a + len < n && cur && ch[(start + a + len) % n] == cur)
            len++;
        if (!cur || len < PINCH_RUN_MIN) {
            a += len ? len : 1;
            continue;
        }
        /* the run in the chart: s = rho × (along n) / (along the fold), the sheet's own
         * parameter (x / y on x² = y² z), monotone along a rim that goes round the pinch;
         * the distance to the tangent line beside it */
        for (size_t j = 0; j < len; j++) {
            size_t i = (i0 + j) % n;
            const double *q = c->m->pos + 3 * (size_t)l->v[i];
            double h, xn, xe;
            frame(cur, q, &h, &xn, &xe);
            v[j] = l->v[i];
            src[j] = i;
            s[j] = fabs(xe) > 0 ? rho * xn / xe : (xn >= 0 ? 1 : -1) * INFINITY;
            for (int k = 0; k < 3; k++)
                ft[3 * j + k] = cur->p[k] + h * cur->c[k];
        }
        bool finite = true;
        for (size_t j = 0; j < len; j++)
            finite = finite && isfinite(s[j]);
        a += len;
        if (!finite)
            continue;
        /* the chart's unit, its mean step in s: round the pinch the rim moves mostly along
         * the tangent and the fold, so its steps in s are a fraction of its edges (Steiner,
         * depth 6, irrational box, beside (−1/2, 0, 0): 0.0045 against a mean edge of
         * 0.0166); six of them did not travel one edge and no way forwards was read, so a
         * step back of 8e-5 between two rim vertices 0.09 cell apart, 5 cells out, stayed
         * and the two ring columns under it, 0.013 cell apart on one sheet, turned 3 edges
         * over. Where the edge reads no way the unit's is taken, for steps back only */
        double unit = 0;
        for (size_t j = 0; j + 1 < len; j++)
            unit += fabs(s[j + 1] - s[j]) / (double)(len - 1);
        cf_loop run = {v, len, whole};
        int got = cf_clip_ears(c, &flat, &run, s, ft, NULL, 0, unit);
        if (got < 0) {
            clipped = -1;
            goto done;
        }
        if (got == 0)
            continue;
        /* the run's vertices left, in order: mark the others gone */
        size_t r = 0;
        for (size_t j = 0; j < len; j++) {
            if (r < run.n && v[r] == l->v[src[j]])
                r++;
            else
                keep[src[j]] = false;
        }
        clipped += got;
    }
    if (clipped > 0) {
        size_t k = 0;
        for (size_t i = 0; i < n; i++) {
            if (!keep[i])
                continue;
            l->v[k] = l->v[i];
            u[k] = u[i];
            cid[k] = cid[i];
            for (int j = 0; j < 3; j++)
                foot[3 * k + j] = foot[3 * i + j];
            k++;
        }
        l->n = k;
    }
done:
    free(ch);
    free(v);
    free(s);
    free(ft);
    free(src);
    free(keep);
    return clipped;
}

/* Rings on the fold. A rim edge whose ends lie on the two sheets of one chart (the sheets'
 * normal coordinate xn changes sign, the fold coordinate xe does not) crosses the fold, and
 * the rings scaled from its ends joined every ladder quad below it across the fold: such a
 * quad's triangles join one sheet to the other through the lens between them (under a tenth
 * of a cell wide within a few cells of the pinch point) and face against ∇f at both ends of
 * their edge on one sheet (Steiner, depth 7, irrational box: 9 of the 22 turned-over edges,
 * 1.4-2.4 cells from a pinch point, each with corners at s = xn / xe of both signs). The
 * rings of the edge's nearer end to the fold are scaled from the edge's point of xn = 0
 * instead (xn is linear along the edge): they lie on the fold itself (on the umbrella
 * x² = y² z the line x = z = 0, where ∇f points along the curve's tangent, so the move along
 * the tangent reaches it), and every quad below the rim lies on one sheet. A column put
 * between the edge's ends instead left the same turned edges and more needles (its rings a
 * small fraction of a cell from a neighbour's where the rim crossed the fold near an end:
 * Steiner, depth 6, irrational box, 523 against 417 triangles under 10° within 4 cells of
 * a pinch point, 335 before; the quality pass left 11 needles where 7 are allowed). */
bool cf_pinch_rim_points(cf_ctx *c, const cf_loop *l, const cf_pinch *const *ch, double *q,
                         bool *on_fold)
{
    size_t n = l->n, ne = l->closed ? n : n - 1;
    double *x = malloc(2 * (n + 1) * sizeof *x); /* per vertex: xn, xe in its chart */
    if (!x)
        return false;
    for (size_t i = 0; i < n; i++) {
        const double *p = c->m->pos + 3 * (size_t)l->v[i];
        for (int d = 0; d < 3; d++)
            q[3 * i + d] = p[d];
        on_fold[i] = false;
        if (ch[i]) {
            double h;
            frame(ch[i], p, &h, &x[2 * i], &x[2 * i + 1]);
        }
    }
    for (size_t i = 0; i < ne; i++) {
        size_t j = (i + 1) % n;
        if (!ch[i] || ch[i] != ch[j] || !(x[2 * i + 1] * x[2 * j + 1] > 0) ||
            !(x[2 * i] * x[2 * j] < 0))
            continue;
        double w = x[2 * i] / (x[2 * i] - x[2 * j]);
        const double *a = c->m->pos + 3 * (size_t)l->v[i], *b = c->m->pos + 3 * (size_t)l->v[j];
        size_t k = w < 0.5 ? i : j;
        for (int d = 0; d < 3; d++)
            q[3 * k + d] = a[d] + w * (b[d] - a[d]);
        on_fold[k] = true;
    }
    free(x);
    return true;
}
