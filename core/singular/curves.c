/* curves.c — the singular-curve stage: seeds from the search's rank-2 boxes, a trace both
 * ways from each (curve_trace.c), the two halves joined and split at pinch points into
 * curves of one kind each, and the ends typed once every branch is known (a collapse point
 * where three or more branches end is a triple point). See curves.h. */
#include "core/singular/curves.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include "core/eval/eval.h"
#include "core/singular/curve_trace.h"
#include "core/singular/search.h"
#include "core/util/grow.h"
#include "core/util/sym3.h"
#include "core/util/vec3.h"

/* Newton's tolerance (× box diagonal): a step this small leaves the point far inside the
 * 1e-9 × diagonal the locus promises (the iteration is quadratic). */
#define CURVES_NEWTON_TOL_REL 1e-12

/* Step bounds in finest search cells: at most half a cell (every box the curve crosses gets
 * a vertex or a segment through it; chords stay close), at least 1e-6 of one (below, the
 * corrector is failing for good). */
#define CURVES_HMAX_CELLS 0.5
#define CURVES_HMIN_CELLS 1e-6

/* A box is explained by a traced segment passing within this many cells of its projected
 * point; a seed within it of a traced curve is that curve. A sixteenth of a cell is far
 * above the chord's deviation (h/40) and Newton's error, far below the gap between two
 * curves that separate cells can tell apart. */
#define CURVES_DELTA_CELLS 0.0625

/* A path ends at an existing point it passes this close to (cells): a collapse point found
 * by one branch is met by the others within their extrapolation error (~1e-10 × diagonal),
 * far below this, long before they would approach it step by step. */
#define CURVES_SNAP_CELLS 1e-3

/* Vertices closer than this (cells) to the previous one are dropped (pinch points and ends
 * stay): the approach to a collapse point halves its steps down to 1e-10 × diagonal, and
 * that many vertices on a few hundredths of a cell serve no mesh. */
#define CURVES_MIN_GAP_CELLS 0.05

/* ... where the polyline without them stays within this (cells) of the one with them: a
 * loop smaller than a cell keeps the vertices its turning needs. */
#define CURVES_THIN_SAG_CELLS 1e-3

/* Newton iterations projecting a seed onto its curve (it starts up to a cell away). */
#define CURVES_SEED_IT 30

/* Work budget: vertices over all curves (24 bytes each), and units of work — a step attempt
 * or a seed tried, each a few Hessian evaluations — per vertex allowed. */
#define CURVES_MAX_VERTICES ((size_t)1 << 20)
#define CURVES_ATTEMPTS_PER_VERTEX 8

/* Deepest search the stage accepts (cells a side fit the index's 21-bit coordinates). */
#define CURVES_MAX_DEPTH 20

/* Branches meeting at a collapse point that make it a triple point. */
#define CURVES_TRIPLE_BRANCHES 3

/* Projections of Hessian rank ≤ 1 (pinch and triple points, where curves meet) probed for
 * seeds (degenerate_seeds): the probing stops after this many distinct points none of whose
 * probes landed on a curve. A double sheet's rank-1 boxes (10⁵ of them) project onto as many
 * distinct points, and no probe there lands (the Hessian across has rank 1); the heart's ring
 * of H = 0 on a smooth sheet neither. Points whose probes land do not count: nine planes
 * sin πx sin πy sin πz in ±1.9 at depth 3 project onto 27 triple points and 24 more just
 * outside the box (±2), every one of them a curve's end; a cap of 32 distinct points there
 * left the 7 last triple points without curves (84 of 108, typed degenerate). */
#define CURVES_DEGENERATE_BARREN_MAX 32
/* Distinct rank ≤ 1 projections probed at most (each is compared with every earlier one):
 * an arrangement of 10 × 10 × 10 planes has 1000 triple points; more points where curves
 * meet than this, at the search's depth, would be a locus too fine for its cells. */
#define CURVES_DEGENERATE_PROBES_MAX 1024
/* The probe's step along a null direction of the Hessian there (cells): well off the point,
 * where the curve's Hessian across has its full rank 2, well inside the cell. */
#define CURVES_DEGENERATE_STEP_CELLS 0.25
/* Without rank-2 seeds, more rank ≤ 1 boxes than this are a double sheet's (each its own
 * point, none a curve's end): the stage returns without building its index, as before. */
#define CURVES_DEGENERATE_BOXES_MAX 1024
/* A probe's seed counts as on a curve traced already within this fraction of the probe's
 * step (and tr->delta): the branch through q on the probe's far side passes a step away
 * (straight on) or more, the branch the probe landed on at 0. */
#define CURVES_DEGENERATE_NEAR 0.5
/* Two rank ≤ 1 projections this close (cells) are one point, probed once: a pinch or
 * triple point is one point seen from several boxes; a curve of them (the heart's ring
 * z = 0, where H vanishes on a smooth sheet) is probed once a cell. */
#define CURVES_DEGENERATE_SAME_CELLS 1.0
/* Newton iterations projecting a probe onto its curve: it starts 0.25 cell off, where Newton
 * across is quadratic at once; a probe that does not land by then is no seed (on the heart's
 * ring, CURVES_SEED_IT's 30 each doubled the stage's Hessian evaluations at depth 6). */
#define CURVES_DEGENERATE_IT 8

/* Branches ending at a rank-1 point whose rank-1 system is singular that make it a crossing
 * of curves rather than a contact of two sheets (which no curve reaches). */
#define CURVES_CROSSING_BRANCHES 2

static bool options_ok(const ism_locus_options *o, ism_error *err)
{
    for (int k = 0; k < 3; k++)
        if (!(isfinite(o->box[k]) && isfinite(o->box[k + 3]) && o->box[k] < o->box[k + 3]))
            return ism_error_set(err, "singular curves: the box is empty or not finite");
    if (o->max_depth < 0 || o->max_depth > CURVES_MAX_DEPTH)
        return ism_error_set(err, "singular curves: max_depth %d is outside 0..%d",
                             o->max_depth, CURVES_MAX_DEPTH);
    return true;
}

static void tracer_init(ism_ctracer *tr, const ism_locus_options *o, ism_locus *io)
{
    memset(tr, 0, sizeof *tr);
    tr->io = io;
    tr->o = o;
    memcpy(tr->box, o->box, sizeof tr->box);
    double side = INFINITY;
    for (int k = 0; k < 3; k++)
        side = fmin(side, o->box[k + 3] - o->box[k]);
    tr->diag = ism_box_diagonal(o->box);
    tr->cell = ldexp(side, -o->max_depth);
    tr->hmax = CURVES_HMAX_CELLS * tr->cell;
    tr->hmin = CURVES_HMIN_CELLS * tr->cell;
    tr->delta = CURVES_DELTA_CELLS * tr->cell;
    tr->snap = CURVES_SNAP_CELLS * tr->cell;
    tr->jet.tol = CURVES_NEWTON_TOL_REL * tr->diag;
    tr->vertices_left = CURVES_MAX_VERTICES;
    tr->attempts_left = CURVES_MAX_VERTICES * CURVES_ATTEMPTS_PER_VERTEX;
}

/* The kind of the part v[0..n): the sign of the normal-plane determinant at most of its
 * inner vertices, or at its chord's middle when it has none. */
static int part_kind(ism_ctracer *tr, const ism_cvert *v, size_t n)
{
    long neg = 0, pos = 0;
    for (size_t i = 1; i + 1 < n; i++)
        neg += v[i].D < 0, pos += v[i].D > 0;
    if (neg == pos) {
        double m[3], t[3];
        for (int k = 0; k < 3; k++) {
            m[k] = 0.5 * (v[0].p[k] + v[n - 1].p[k]);
            t[k] = v[n - 1].p[k] - v[0].p[k];
        }
        double l = sqrt(ism_dot3(t, t));
        ism_cpoint c;
        ism_cjet_frame(&tr->jet, m, l > 0 ? (double[3]){t[0] / l, t[1] / l, t[2] / l} : NULL,
                       &c);
        neg = c.D < 0, pos = c.D > 0;
    }
    return neg > pos ? ISM_CURVE_DOUBLE : ISM_CURVE_WHISKER;
}

/* Adds the curve v[0..n) with its two ends (type, point), or a closed loop. */
static void add_part(ism_ctracer *tr, const ism_cvert *v, size_t n, const int type[2],
                     const int point[2], bool closed)
{
    ism_sing_curve c = {.kind = part_kind(tr, v, n), .closed = closed, .n = n};
    c.xyz = malloc(3 * n * sizeof *c.xyz);
    if (!c.xyz) {
        tr->oom = true;
        return;
    }
    for (size_t i = 0; i < n; i++)
        memcpy(c.xyz + 3 * i, v[i].p, 3 * sizeof *c.xyz);
    for (int e = 0; e < 2; e++) {
        c.end_type[e] = closed ? ISM_END_BOX : type[e];
        c.end_point[e] = closed ? -1 : point[e];
    }
    if (!ism_locus_add_curve(tr->io, &c)) {
        free(c.xyz);
        tr->oom = true;
    }
}

/* Splits the chain v[0..n) (ends typed) at its pinch vertices into curves of one kind. */
static void split_chain(ism_ctracer *tr, const ism_cvert *v, size_t n, const int type[2],
                        const int point[2])
{
    size_t a = 0;
    for (size_t i = 1; i < n && !tr->oom; i++) {
        bool last = i == n - 1;
        if (!last && v[i].point < 0)
            continue;
        int t[2] = {a == 0 ? type[0] : ISM_END_PINCH, last ? type[1] : ISM_END_PINCH};
        int p[2] = {a == 0 ? point[0] : v[a].point, last ? point[1] : v[i].point};
        add_part(tr, v + a, i - a + 1, t, p, false);
        a = i;
    }
}

/* May the vertex x go, its neighbours being a and b? Only when it is within gap of one of
 * them and within sag of the chord a–b (thinning never bends the polyline). */
static bool droppable(const double *a, const double *x, const double *b, double gap, double sag)
{
    return (ism_dist3(a, x) < gap || ism_dist3(x, b) < gap) &&
           ism_dist_segment(x, a, b, NULL) <= sag;
}

/* Drops the vertices of v[0..*n) that crowd the previous vertex kept or the next anchor
 * (the ends, pinch points, which stay) where the curve is straight. A loop's last vertex
 * must also keep its distance from the first. */
static void thin(ism_cvert *v, size_t *n, double gap, double sag, bool closed)
{
    size_t m = 0;
    for (size_t i = 0; i < *n; i++) {
        bool anchor = i == 0 || (i == *n - 1 && !closed) || v[i].point >= 0;
        if (!anchor) {
            const double *next = i + 1 < *n ? v[i + 1].p : v[0].p;
            bool near_prev = ism_dist3(v[m - 1].p, v[i].p) < gap;
            bool near_next = (i + 1 < *n ? v[i + 1].point >= 0 || (i + 1 == *n - 1 && !closed)
                                         : closed) && ism_dist3(v[i].p, next) < gap;
            if ((near_prev || near_next) && droppable(v[m - 1].p, v[i].p, next, gap, sag))
                continue;
        } else { /* an anchor displaces the crowding vertices just before it */
            while (m > 1 && v[m - 1].point < 0 && ism_dist3(v[m - 1].p, v[i].p) < gap &&
                   ism_dist_segment(v[m - 1].p, v[m - 2].p, v[i].p, NULL) <= sag)
                m--;
        }
        v[m++] = v[i];
    }
    *n = m;
}

/* Joins the backward path (reversed) and the forward one into the seed's chain and emits
 * it: one closed curve, or curves split at pinch points (a loop with pinch points is cut
 * open at its first). */
static void emit(ism_ctracer *tr, const ism_cpath *fw, const ism_cpath *bw)
{
    size_t n = fw->n + (fw->closed ? 1 : bw->n);
    ism_cvert *v = malloc(n * sizeof *v);
    if (!v) {
        tr->oom = true;
        return;
    }
    size_t m = 0, first_pinch = n;
    if (!fw->closed)
        for (size_t i = bw->n; i-- > 1;)
            v[m++] = bw->v[i];
    for (size_t i = 0; i < fw->n; i++)
        v[m++] = fw->v[i];
    thin(v, &m, CURVES_MIN_GAP_CELLS * tr->cell, CURVES_THIN_SAG_CELLS * tr->cell, fw->closed);
    for (size_t i = 0; i < m && first_pinch == n; i++)
        if (v[i].point >= 0)
            first_pinch = i;
    if (!fw->closed) {
        int type[2] = {bw->end_type, fw->end_type}, point[2] = {bw->end_point, fw->end_point};
        split_chain(tr, v, m, type, point);
    } else if (first_pinch == n) {
        int none[2] = {-1, -1};
        add_part(tr, v, m, none, none, true);
    } else { /* rotate so the loop starts and ends at its first pinch point */
        ism_cvert *r = malloc((m + 1) * sizeof *r);
        if (!r) {
            tr->oom = true;
        } else {
            for (size_t i = 0; i <= m; i++)
                r[i] = v[(first_pinch + i) % m];
            int type[2] = {ISM_END_PINCH, ISM_END_PINCH};
            int point[2] = {v[first_pinch].point, v[first_pinch].point};
            split_chain(tr, r, m + 1, type, point);
            free(r);
        }
    }
    free(v);
}

/* Projects the seed box's q onto its curve; false when it does not lead onto a curve of the
 * zero set inside the box. */
static bool seed_point(ism_ctracer *tr, const ism_lbox *bx, int iters, ism_cpoint *s)
{
    double p0[3];
    ism_cjet_frame(&tr->jet, bx->q, NULL, s);
    if (!ism_cjet_correct(&tr->jet, bx->q, s->n, s->n, tr->cell, iters, p0, NULL) ||
        !ism_ctracer_inside(tr, p0))
        return false;
    double t[3];
    memcpy(t, s->t, sizeof t);
    ism_cjet_frame(&tr->jet, p0, t, s);
    return ism_cjet_seed_ok(s, tr->io->hessian_scale, tr->diag, 1.0);
}

/* Traces the curve through the seed s of box bx unless a curve traced already passes within
 * near of it. */
static void trace_from(ism_ctracer *tr, ism_lbox *bx, const ism_cpoint *seed, double near)
{
    ism_cpoint s = *seed;
    if (ism_cindex_near_segment(&tr->idx, s.p, near)) {
        bx->flags |= ISM_LBOX_USED; /* on a curve traced already */
        return;
    }
    ism_cpath fw = {0}, bw = {0};
    ism_ctrace(tr, &s, -1, true, &fw);
    if (!fw.closed && !tr->oom) {
        ism_cpoint r = s;
        ism_cjet_reverse(&r);
        ism_ctrace(tr, &r, -1, false, &bw);
    }
    if (fw.n + bw.n > 2) /* it went somewhere: a curve through the seed */
        bx->flags |= ISM_LBOX_USED;
    if (!tr->oom)
        emit(tr, &fw, &bw);
    free(fw.v);
    free(bw.v);
}

static void trace_seed(ism_ctracer *tr, ism_lbox *bx)
{
    ism_cpoint s;
    if (seed_point(tr, bx, CURVES_SEED_IT, &s))
        trace_from(tr, bx, &s, tr->delta);
}

/* Types the ends at points, now that every branch is known: a point where ≥ 3 branches end
 * (and that is no pinch) is a triple point. */
static void type_ends(ism_ctracer *tr, size_t first_curve)
{
    ism_locus *io = tr->io;
    int *count = calloc(io->npoints + 1, sizeof *count);
    if (!count) {
        tr->oom = true;
        return;
    }
    for (size_t c = first_curve; c < io->ncurves; c++)
        for (int e = 0; e < 2; e++)
            if (!io->curves[c].closed && io->curves[c].end_point[e] >= 0)
                count[io->curves[c].end_point[e]]++;
    for (size_t j = 0; j < io->npoints; j++)
        if (count[j] >= CURVES_TRIPLE_BRANCHES && io->points[j].type != ISM_SING_PINCH)
            io->points[j].type = ISM_SING_TRIPLE;
    for (size_t c = first_curve; c < io->ncurves; c++)
        for (int e = 0; e < 2; e++) {
            int j = io->curves[c].end_point[e];
            if (io->curves[c].closed || j < 0)
                continue;
            int type = io->points[j].type;
            io->curves[c].end_type[e] = type == ISM_SING_TRIPLE  ? ISM_END_TRIPLE
                                        : type == ISM_SING_PINCH ? ISM_END_PINCH
                                                                 : ISM_END_POINT;
        }
    free(count);
}

static bool is_seed(const ism_lbox *b)
{
    return (b->flags & ISM_LBOX_PROJECTED) && b->rank == 2 && !(b->flags & ISM_LBOX_USED);
}

/* A box projected onto a point of Hessian rank ≤ 1 — also when the points stage explained
 * it by a point it published (USED): the curves leaving a pinch or triple point still need
 * seeds (the cross-cap at depth 4: its boxes below z = −1 project onto (0, 0, −1), and the
 * whisker z < −1 had none). */
static bool is_degenerate(const ism_lbox *b)
{
    return (b->flags & ISM_LBOX_PROJECTED) && b->rank <= 1;
}

/* Whether q lies within the enclosure of a point standing for a whisker loop too small to
 * trace (points.c's small_loop): that loop is reported as the point, not traced. */
static bool in_small_loop(const ism_locus *io, const double q[3])
{
    for (size_t i = 0; i < io->npoints; i++)
        if (io->points[i].uncertified_why == ISM_UNCERT_LOOP &&
            ism_dist3(io->points[i].p, q) <= io->points[i].radius)
            return true;
    return false;
}

/* Whether p lies within near of a segment of the curves io holds before this stage
 * (curves[0 .. first)): the curve index holds only the curves traced here. */
static bool near_earlier_curve(const ism_ctracer *tr, const double p[3], size_t first,
                               double near)
{
    for (size_t c = 0; c < first; c++) {
        const ism_sing_curve *cu = &tr->io->curves[c];
        size_t segs = cu->closed ? cu->n : cu->n - 1;
        for (size_t i = 0; i < segs; i++) {
            const double *a = cu->xyz + 3 * i, *b = cu->xyz + 3 * ((i + 1) % cu->n);
            double d2 = ism_sqdist_segment3(p, a, b);
            if (d2 <= near * near)
                return true;
        }
    }
    return false;
}

/* Half the way from q to the box's boundary along v (side 0) or −v (side 1), when q is in
 * the box; infinity otherwise. A curve from a triple point to a face closer than a probe's
 * step is seeded halfway: nine planes in ±1.9 shifted 0.37 cell at depth 3 have 48 such
 * stubs, 0.009 to 0.095 long, from the triple points at ±2 (the step is 0.12). */
static double inside_step(const ism_ctracer *tr, const double q[3], const double v[3], int side)
{
    if (!ism_ctracer_inside(tr, q))
        return INFINITY;
    double t = INFINITY;
    for (int k = 0; k < 3; k++) {
        double w = side ? -v[k] : v[k];
        if (w > 0)
            t = fmin(t, (tr->box[k + 3] - q[k]) / w);
        else if (w < 0)
            t = fmin(t, (tr->box[k] - q[k]) / w);
    }
    return 0.5 * t;
}

/* Seeds next to a projection q of Hessian rank ≤ 1 (a pinch or triple point): a step of
 * CURVES_DEGENERATE_STEP_CELLS (at most halfway to the box's boundary) each way along every
 * null direction of the Hessian at q, each tried as a seed box of its own (seed_point
 * decides). At a coarse depth the boxes along a
 * curve may all project onto its end points, leaving no rank-2 seed: the cross-cap at depth
 * 3 in ±1.2 (cell 0.3, the z axis on cell edges) projected onto (0, 0, −1), (0, 0, 0) and
 * (0, 0, 1) only, and its double segment and whiskers were not traced at all (no point
 * either: the points stage starts only from rank ≥ 2 in such a cluster). Returns whether
 * some probe landed on a curve (traced now or before). */
static bool degenerate_seeds(ism_ctracer *tr, const ism_lbox *bx, size_t first_curve)
{
    double g[3], h[6], eig[3], vec[3][3];
    ism_eval_hessian(tr->jet.f, tr->jet.ws, bx->q[0], bx->q[1], bx->q[2], g, h);
    tr->jet.evals++;
    ism_sym3_eigen(h, eig, vec);
    double m = fmax(fabs(eig[0]), fmax(fabs(eig[1]), fabs(eig[2])));
    double zero = fmax(ISM_SING_RANK_REL * m, ISM_SING_HZERO_REL * tr->io->hessian_scale);
    if (!(m > zero)) /* H vanishes: its eigenvectors are rounding; probe along the axes */
        for (int i = 0; i < 3; i++)
            for (int k = 0; k < 3; k++)
                vec[i][k] = i == k;
    double d = CURVES_DEGENERATE_STEP_CELLS * tr->cell;
    bool landed = false;
    for (int i = 0; i < 3 && !tr->stop && !tr->oom; i++) {
        if (m > 0 && fabs(eig[i]) > zero)
            continue; /* not a null direction */
        for (int side = 0; side < 2 && ism_ctracer_go(tr); side++) {
            double step = (side ? -1.0 : 1.0) * fmin(d, inside_step(tr, bx->q, vec[i], side));
            ism_lbox probe = *bx;
            for (int k = 0; k < 3; k++)
                probe.q[k] = bx->q[k] + step * vec[i][k];
            probe.rank = 2;
            ism_cpoint sp;
            if (!seed_point(tr, &probe, CURVES_DEGENERATE_IT, &sp))
                continue;
            landed = true;
            /* a branch ending at q passes |step| from the probe on the far side */
            double near = fmin(tr->delta, CURVES_DEGENERATE_NEAR * fabs(step));
            if (!near_earlier_curve(tr, sp.p, first_curve, near))
                trace_from(tr, &probe, &sp, near);
        }
    }
    return landed;
}

/* Whether q lies farther outside the box than a probe's step: no probe from there starts
 * inside (the search's boxes at the box's faces project onto points up to a cell out: nine
 * planes in ±1.9 at depth 4 onto 23 triple points at ±2, 0.1 out, the step 0.06). */
static bool out_of_reach(const ism_ctracer *tr, const double q[3])
{
    double d = CURVES_DEGENERATE_STEP_CELLS * tr->cell, out2 = 0.0;
    for (int k = 0; k < 3; k++) {
        double o = fmax(tr->box[k] - q[k], q[k] - tr->box[k + 3]);
        out2 += o > 0.0 ? o * o : 0.0;
    }
    return out2 > d * d;
}

/* The points probed so far (degenerate_seeds), and how many of them gave nothing. */
typedef struct probed {
    double (*p)[3];
    size_t n, cap, barren;
} probed;

/* Probes q (degenerate_seeds) unless a point within same of it was probed already; false
 * when out of memory. */
static bool probe_once(ism_ctracer *tr, probed *pr, const double q[3], double same,
                       size_t first_curve)
{
    for (size_t s = 0; s < pr->n; s++)
        if (ism_dist3(pr->p[s], q) <= same)
            return true;
    if (!ism_grow((void **)&pr->p, &pr->cap, pr->n + 1, sizeof pr->p[0], 64))
        return false;
    memcpy(pr->p[pr->n++], q, sizeof pr->p[0]);
    ism_lbox bx = {.rank = 2, .flags = ISM_LBOX_PROJECTED};
    memcpy(bx.q, q, sizeof bx.q);
    pr->barren += !degenerate_seeds(tr, &bx, first_curve);
    return true;
}

static bool probing(const ism_ctracer *tr, const probed *pr)
{
    return pr->n < CURVES_DEGENERATE_PROBES_MAX && pr->barren < CURVES_DEGENERATE_BARREN_MAX &&
           !tr->stop && !tr->oom;
}

/* Every distinct rank ≤ 1 projection within a probe's reach of the box probed for seeds
 * (degenerate_seeds), until CURVES_DEGENERATE_BARREN_MAX of them gave nothing or
 * CURVES_DEGENERATE_PROBES_MAX were probed; then every point where a curve traced here
 * ends, for its other branches, until no new curve comes: nine planes in ±1.9 shifted 0.37
 * cell at depth 3 have triple points at y = −2, 0.009 inside the box, onto which no box
 * projects; the curves from y = −1 end there, and the 16 stubs to the face start there. */
static void trace_degenerate(ism_ctracer *tr, size_t first_curve)
{
    probed pr = {0};
    ism_locus *io = tr->io;
    double same = CURVES_DEGENERATE_SAME_CELLS * tr->cell;
    for (size_t b = 0; b < io->nboxes && probing(tr, &pr); b++) {
        const ism_lbox *bx = &io->boxes[b];
        if (is_degenerate(bx) && !out_of_reach(tr, bx->q) && !in_small_loop(io, bx->q) &&
            !probe_once(tr, &pr, bx->q, same, first_curve))
            tr->oom = true;
    }
    for (size_t c = first_curve; c < io->ncurves && probing(tr, &pr); c++)
        for (int e = 0; e < 2 && !io->curves[c].closed; e++) {
            int j = io->curves[c].end_point[e];
            if (j >= 0 && !probe_once(tr, &pr, io->points[j].p, tr->delta, first_curve))
                tr->oom = true;
        }
    free(pr.p);
}

bool ism_sing_trace_curves(const ism_tape *f, const ism_locus_options *o, ism_locus *io,
                           ism_error *err)
{
    if (!options_ok(o, err))
        return false;
    size_t seeds = 0, degenerate = 0;
    for (size_t b = 0; b < io->nboxes; b++) {
        seeds += is_seed(&io->boxes[b]);
        degenerate += is_degenerate(&io->boxes[b]);
    }
    if (seeds == 0 && (degenerate == 0 || degenerate > CURVES_DEGENERATE_BOXES_MAX))
        return true; /* nothing to trace (a double sheet's 10⁵ rank-1 boxes: no index built) */
    ism_ctracer tr;
    tracer_init(&tr, o, io);
    tr.jet.f = f;
    tr.jet.ws = ism_eval_ws_new(f);
    if (!tr.jet.ws || !ism_cindex_build(&tr.idx, io->boxes, io->nboxes, o->box, tr.cell)) {
        ism_eval_ws_free(tr.jet.ws);
        return ism_error_set(err, "singular curves: out of memory");
    }
    size_t first_curve = io->ncurves;
    for (size_t b = 0; b < io->nboxes && !tr.stop && !tr.oom; b++) {
        ism_lbox *bx = &io->boxes[b];
        if (is_seed(bx) && ism_ctracer_go(&tr))
            trace_seed(&tr, bx);
    }
    trace_degenerate(&tr, first_curve);
    if (!tr.oom)
        type_ends(&tr, first_curve);
    size_t lost = 0;
    for (size_t c = first_curve; c < io->ncurves; c++)
        for (int e = 0; e < 2; e++)
            lost += !io->curves[c].closed && io->curves[c].end_type[e] == ISM_END_LOST;
    if ((tr.stop || lost) && !io->incomplete) {
        io->incomplete = true;
        if (tr.stop)
            snprintf(io->incomplete_why, sizeof io->incomplete_why, "%s", tr.why);
        else
            snprintf(io->incomplete_why, sizeof io->incomplete_why,
                     "singular curves: %zu curve ends lost (the corrector did not converge)", lost);
    }
    io->evals_jet += tr.jet.evals;
    ism_cindex_free(&tr.idx);
    ism_eval_ws_free(tr.jet.ws);
    if (tr.oom)
        return ism_error_set(err, "singular curves: out of memory");
    return true;
}

bool ism_sing_name_crossings(ism_locus *io)
{
    int *count = calloc(io->npoints + 1, sizeof *count);
    if (!count)
        return false;
    for (size_t c = 0; c < io->ncurves; c++)
        for (int e = 0; e < 2; e++)
            if (!io->curves[c].closed && io->curves[c].end_point[e] >= 0)
                count[io->curves[c].end_point[e]]++;
    for (size_t j = 0; j < io->npoints; j++) {
        ism_sing_point *p = &io->points[j];
        if (count[j] >= CURVES_CROSSING_BRANCHES && p->uncertified_why == ISM_UNCERT_CONTACT) {
            p->uncertified_why = ISM_UNCERT_CROSSING;
            p->exists_radius = 0.0; /* Miranda's existence is a contact's (∇f = 0 along the
                                       curves here: nothing to prove) */
        }
    }
    free(count);
    return true;
}
