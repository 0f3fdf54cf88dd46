/* crease_split.c — a leaf's triangles cut where f's top min/max changes branch (see
 * crease_split.h). */
#include "core/octree/crease_split.h"
#include "core/octree/triangulate.h"
#include "core/util/min_norm.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

/* Newton steps toward a = b = 0 from the edge's linear estimate: quadratic convergence
 * reaches rounding in 4-5 on a transversal crease; more do not help where the branches
 * are tangent (the linear estimate is kept then). */
#define CREASE_NEWTON_STEPS 8
/* A Newton result farther than this many edge lengths from the edge is not the edge's
 * crease point (a distant part of the crease curve): the linear estimate is kept. Not 1: a
 * short edge across a sharp wedge has the wedge's tip beyond its ends (an isosceles tip of
 * angle θ lies 1 / (2 sin(θ/2)) edge lengths from each end: 1.46 at cube-minus-ball's 40°;
 * measured there 1.02–1.36), and the linear estimate it fell back to is no crease point. */
#define CREASE_REACH_EDGES 2.0
/* How far beyond CREASE_REACH_EDGES a short edge p-q's (s->wedge_edges_below) crease point x
 * may lie from its linear estimate, as a multiple of the planar bound |pq| / sin(min(w,
 * 90°)), w the solid's wedge angle at x (π
 * minus the angle between the branches' gradients there): with planar branches meeting on
 * a straight crease, p on one at distance d1 from the crease and q on the other at d2,
 * |pq| ≥ max(d1, d2) sin w for w ≤ 90° (≥ max(d1, d2) beyond), and the crease point nearest
 * the segment lies within max(d1, d2) of it. Twice that leaves room for the branches' and the
 * crease's bending over the cell. Where the gyroid ball's gyroid meets its sphere at w = 21°
 * a lattice edge of a depth-10 leaf crosses both sides of the blade 0.00036 apart, its crease
 * point 2.1 edges away (at w = 52°, 1.007 edges); a reach of one edge left that point on
 * one branch and the triangles across the crease 10 E off at E = 1e-4 at depth 10 and 12
 * alike, and two edges still miss the thinnest wedges.
 * Only short edges: on a leaf that can still be split, a crease point far off its edge
 * (the crease outside the polygon) made a level-5 leaf of the gyroid ball at the default
 * bound, a 19-gon fanned across the crease, pass E wound against its neighbours (21 edges
 * run the same way twice, test_winding.c); such leaves split instead, as before. */
#define CREASE_REACH_SLACK 2.0
/* "Short": at most the diagonal of a cell this many levels above depth.max. Depth.max alone
 * (0) left leaves one level above it that appeared in the last refinement round beyond E
 * (1 cell in each shifted box at E = 1e-4, 1.15 E and 1.20 E); one level meets E in all
 * three boxes. Two levels would reach the 19-gon's edges on the depth-7 default bound. */
#define CREASE_WEDGE_LEVELS 1
/* The branches' gradients count as parallel (no crease line through x, the 2 × 2 normal
 * system singular) when |ga|²|gb|² − (ga·gb)² is below this share of |ga|²|gb|²: a sine
 * of the crossing angle under 1e-6 rad, where a step would run along the crease. */
#define CREASE_PARALLEL_SIN2 1e-12

/* Branch labels of a leaf's vertices kept on the stack up to this many vertices (a leaf
 * emits a few dozen); more take the heap. */
#define LABELS_ON_STACK 256
/* A vertex whose branch is not looked up yet. */
#define LABEL_UNKNOWN 2
/* A crease point: on both branches, so no corner of a triangle is alone on its branch for it. */
#define LABEL_ANY 3

/* Does t still end in f's top min/max (not decided by the intervals it was shortened by)? */
static bool top_undecided(const ism_tape *t)
{
    static const double any[2] = {0, 0};
    return ism_top_active_branch(t, any) >= 0;
}

/* The tape whose top min/max gives f's branches at p bit for bit: the leaf's shortened one
 * inside its box while it keeps that min/max (its operands are then computed as f's are, by
 * the same instructions or by a min/max decided strictly), else f's. */
static const ism_tape *top_tape(const ism_sampler *s, const double p[3])
{
    const ism_tape *t = ism_sampler_tape_at(s, p);
    return t == s->local && !top_undecided(t) ? s->tape : t;
}

int ism_crease_branch(ism_sampler *s, const double p[3], double g[3])
{
    double v[2], bg[2][3];
    const ism_tape *t = top_tape(s, p);
    if (!g) { /* the label alone: values, no gradients */
        s->n_point++;
        if (!ism_eval_top_values(t, s->ws, p[0], p[1], p[2], v))
            return -1;
        return ism_top_active_branch(t, v);
    }
    s->n_gradient++;
    if (!ism_eval_top_branches(t, s->ws, p[0], p[1], p[2], v, bg))
        return -1;
    int b = ism_top_active_branch(t, v);
    memcpy(g, bg[b], sizeof bg[b]);
    return b;
}

static bool before(const double *a, const double *b)
{
    for (int k = 0; k < 3; k++)
        if (a[k] != b[k])
            return a[k] < b[k];
    return false;
}

/* One minimum-norm Newton step on (a, b) = 0 from x; false when the branches' gradients
 * are parallel there or a value is not finite. */
static bool newton_step(ism_sampler *s, double x[3])
{
    double v[2], g[2][3];
    s->n_gradient++;
    ism_eval_top_branches(top_tape(s, x), s->ws, x[0], x[1], x[2], v, g);
    double step[3];
    if (!isfinite(v[0]) || !isfinite(v[1]) ||
        !ism_min_norm_step(2, (const double (*)[3])g, v, CREASE_PARALLEL_SIN2, step))
        return false;
    for (int k = 0; k < 3; k++)
        x[k] += step[k];
    return true;
}

/* CREASE_NEWTON_STEPS steps from x (false when one fails), ending early where x comes back
 * to where it was two steps before — a fixed point, or a 2-cycle of rounding: the steps left
 * would only repeat those two, so the last one's result is known. */
bool ism_crease_newton(ism_sampler *s, double x[3])
{
    double back[2][3]; /* back[it % 2]: x before step it */
    for (int it = 0; it < CREASE_NEWTON_STEPS; it++) {
        memcpy(back[it % 2], x, sizeof back[0]);
        if (!newton_step(s, x))
            return false;
        if (it >= 1 && memcmp(x, back[(it + 1) % 2], sizeof back[0]) == 0) {
            if ((CREASE_NEWTON_STEPS - it - 1) % 2)
                memcpy(x, back[it % 2], sizeof back[0]);
            return true;
        }
    }
    return true;
}

/* Is crease point x (a = b = 0) near enough lin, the linear estimate on an edge of length
 * len: within CREASE_REACH_EDGES, or on a short edge within CREASE_REACH_SLACK planar bounds
 * (the wedge is looked up only then)? */
static bool within_reach(ism_sampler *s, const double x[3], const double lin[3], double len)
{
    double d = ism_dist3(x, lin);
    if (d <= CREASE_REACH_EDGES * len)
        return true;
    if (!(len <= s->wedge_edges_below))
        return false;
    double v[2], g[2][3];
    s->n_gradient++;
    if (!ism_eval_top_branches(top_tape(s, x), s->ws, x[0], x[1], x[2], v, g))
        return false;
    double aa = ism_dot3(g[0], g[0]), bb = ism_dot3(g[1], g[1]), ab = ism_dot3(g[0], g[1]);
    /* sin w = sin of the gradients' angle; w ≥ 90° (ab ≥ 0): sin taken as 1 */
    double sin2 = ab >= 0 ? 1 : (aa * bb - ab * ab) / (aa * bb);
    return sin2 > 0 && d * d * sin2 <= CREASE_REACH_SLACK * CREASE_REACH_SLACK * len * len;
}

/* The crease point of edge p-q (branches differ at its ends): Newton on a = b = 0 from
 * where a - b changes sign along the edge (flagged ISM_FP_CREASE; true), or that linear
 * estimate moved onto f = 0 (false). */
static bool crease_point(ism_sampler *s, const double *p0, const double *q0, ism_fpoint *out)
{
    const double *p = before(q0, p0) ? q0 : p0, *q = p == p0 ? q0 : p0;
    double v[2], d[2];
    const double *ends[2] = {p, q};
    for (int e = 0; e < 2; e++) {
        s->n_point++;
        ism_eval_top_values(top_tape(s, ends[e]), s->ws, ends[e][0], ends[e][1], ends[e][2], v);
        d[e] = v[0] - v[1];
    }
    double t = d[0] / (d[0] - d[1]);
    if (!(t >= 0 && t <= 1))
        t = 0.5;
    double lin[3], x[3];
    for (int k = 0; k < 3; k++)
        lin[k] = x[k] = p[k] + t * (q[k] - p[k]);
    bool ok = ism_crease_newton(s, x);
    ok = ok && within_reach(s, x, lin, ism_dist3(p, q));
    if (!ok) {
        memcpy(x, lin, sizeof x); /* onto f = 0 along ∇f at least */
        for (int it = 0; it < CREASE_NEWTON_STEPS; it++) {
            double gf[3];
            double f = ism_sample_grad(s, x, gf), gg = ism_dot3(gf, gf);
            if (!(gg > 0) || !isfinite(f))
                break;
            for (int k = 0; k < 3; k++)
                x[k] -= f * gf[k] / gg;
        }
        if (!(ism_dist3(x, lin) <= CREASE_REACH_EDGES * ism_dist3(p, q)))
            memcpy(x, ism_dist3(lin, p) <= ism_dist3(lin, q) ? p : q, sizeof x);
    }
    memcpy(out->p, x, sizeof out->p);
    ism_sample_grad(s, x, out->g);
    out->flags = ok ? ISM_FP_INTERIOR | ISM_FP_CREASE : ISM_FP_INTERIOR;
    return ok;
}

/* The branch of vertex v (labels[v - first], looked up once); LABEL_ANY for a crease point
 * a polygon was cut at (ism_crease_cut_loop), which lies on both. */
static int vertex_branch(ism_sampler *s, const ism_cell_out *out, uint8_t *labels,
                         uint32_t first, uint32_t v)
{
    if (out->verts[v].flags & ISM_FP_CREASE)
        return LABEL_ANY;
    uint8_t *l = &labels[v - first];
    if (*l == LABEL_UNKNOWN)
        *l = (uint8_t)ism_crease_branch(s, out->verts[v].p, NULL);
    return *l;
}

/* Splits triangles first_tri..ntris - 1, whose vertices lie in first..first + n - 1 (labels:
 * n entries of LABEL_UNKNOWN). */
static bool split_labelled(ism_sampler *s, ism_cell_out *out, size_t first_tri, size_t ntris,
                           uint8_t *labels, uint32_t first)
{
    for (size_t t = first_tri; t < ntris; t++) {
        int br[3];
        for (int k = 0; k < 3; k++)
            br[k] = vertex_branch(s, out, labels, first, out->tris[3 * t + k]);
        if (br[0] == LABEL_ANY || br[1] == LABEL_ANY || br[2] == LABEL_ANY)
            continue; /* a cut polygon's triangle: its other corners share one branch */
        if (br[0] == br[1] && br[1] == br[2])
            continue;
        /* r: the corner alone on its branch; the others follow it in winding order */
        int r = br[0] == br[1] ? 2 : br[0] == br[2] ? 1 : 0;
        uint32_t a = out->tris[3 * t + r], b = out->tris[3 * t + (r + 1) % 3],
                 c = out->tris[3 * t + (r + 2) % 3];
        ism_fpoint ab, ac;
        crease_point(s, out->verts[a].p, out->verts[b].p, &ab);
        crease_point(s, out->verts[a].p, out->verts[c].p, &ac);
        uint32_t iab, iac;
        if (!ism_cell_out_vert(out, &ab, &iab) || !ism_cell_out_vert(out, &ac, &iac))
            return false;
        uint32_t *tri = out->tris + 3 * t;
        tri[0] = a, tri[1] = iab, tri[2] = iac;
        if (!ism_cell_out_tri(out, iab, b, c) || !ism_cell_out_tri(out, iab, c, iac))
            return false;
    }
    return true;
}

/* The leaf's shortened tape when it decides f's top min/max (strictly) over its closed box,
 * so the points it holds (ism_sampler_tape_at) lie on the one branch it keeps; else NULL.
 * Looked up once per leaf: a lookup per point cost 0.3% more instructions on
 * cube-minus-ball (callgrind). */
static const ism_tape *deciding_local(const ism_sampler *s)
{
    return s->local && !top_undecided(s->local) ? s->local : NULL;
}

/* Do all vertices of triangles first_tri..ntris - 1 lie on one branch (deciding_local)? */
static bool one_branch(const ism_sampler *s, const ism_cell_out *out, size_t first_tri,
                       size_t ntris)
{
    const ism_tape *local = deciding_local(s);
    if (!local)
        return false;
    for (size_t i = 3 * first_tri; i < 3 * ntris; i++)
        if (ism_sampler_tape_at(s, out->verts[out->tris[i]].p) != local)
            return false;
    return true;
}

/* Branch labels for the vertices of triangles first_tri..ntris - 1, all LABEL_UNKNOWN: stack
 * when they fit, else malloc'd (the caller frees what is not stack; NULL: out of memory);
 * *lo: the lowest of those vertices, labels[v - *lo] vertex v's. */
static uint8_t *leaf_labels(const ism_cell_out *out, size_t first_tri,
                            uint8_t stack[LABELS_ON_STACK], uint32_t *lo)
{
    uint32_t hi = 0;
    *lo = UINT32_MAX;
    for (size_t i = 3 * first_tri; i < 3 * out->ntris; i++) {
        *lo = out->tris[i] < *lo ? out->tris[i] : *lo;
        hi = out->tris[i] > hi ? out->tris[i] : hi;
    }
    size_t n = (size_t)hi - *lo + 1;
    uint8_t *labels = n <= LABELS_ON_STACK ? stack : malloc(n);
    if (labels)
        memset(labels, LABEL_UNKNOWN, n);
    return labels;
}

bool ism_crease_split(ism_sampler *s, ism_cell_out *out, size_t first_tri)
{
    size_t ntris = out->ntris;
    if (first_tri == ntris || one_branch(s, out, first_tri, ntris))
        return true;
    double v[2];
    const double *p0 = out->verts[out->tris[3 * first_tri]].p;
    const ism_tape *t0 = top_tape(s, p0);
    s->n_point++;
    if (!ism_eval_top_values(t0, s->ws, p0[0], p0[1], p0[2], v))
        return true; /* no min/max at the top of the tape */
    uint32_t lo;
    uint8_t stack[LABELS_ON_STACK], *labels = leaf_labels(out, first_tri, stack, &lo);
    if (!labels)
        return false;
    labels[out->tris[3 * first_tri] - lo] = (uint8_t)ism_top_active_branch(t0, v);
    bool ok = split_labelled(s, out, first_tri, ntris, labels, lo);
    if (labels != stack)
        free(labels);
    return ok;
}

/* A triangle faces against ∇f at its centroid when their directions are more than 120° apart
 * (a smooth patch's triangles, even bent beside a crease, face within a few tens of degrees
 * of it). */
#define CREASE_TURNED_COS (-0.5)

/* A chord between two crease points whose middle lies farther than this share of max_error
 * from the crease (Newton from the middle) leaves its leaf to be split: the chord's
 * triangles on either side lie that far off their branches near it. */
#define CREASE_CHORD_SAG 0.5

/* A cut polygon has at most this many corners (a leaf's polygons have a few dozen at most:
 * crack repair adds the finer neighbours' points to a face); a larger one is triangulated
 * whole and its triangles split (ism_crease_split). */
#define CUT_MAX_CORNERS 64

/* A crease point within this share of its edge's length from an end is that corner (on the
 * crease, up to rounding: the double torus's corners on its mirror plane x = 1.1): the polygon
 * is not cut there, since cut pieces would join a corner and a point a rounding error apart,
 * two vertices the weld keeps apart (an edge in four triangles, the regression box of
 * test_polygonise_crease.c's double_torus_closed_under_a_bound). */
#define CUT_CORNER_SHARE 1e-6

/* Is every component of g finite? */
static bool finite3(const double g[3])
{
    return isfinite(g[0]) && isfinite(g[1]) && isfinite(g[2]);
}

/* The run of corners from + 1 .. to (cyclically) of pts between crease points a and b into
 * sub, in the polygon's order: a, the run, b (the chord b-a closes it); its length. */
static size_t branch_polygon(const ism_fpoint *pts, size_t n, size_t from, size_t to,
                             const ism_fpoint *a, const ism_fpoint *b, ism_fpoint *sub)
{
    size_t m = 0;
    sub[m++] = *a;
    for (size_t i = (from + 1) % n;; i = (i + 1) % n) {
        sub[m++] = pts[i];
        if (i == to)
            break;
    }
    sub[m++] = *b;
    return m;
}

bool ism_crease_cut_loop(ism_sampler *s, const ism_fpoint *pts, size_t n, double reach,
                         const double node[6], double max_error, ism_cell_out *out, bool *done)
{
    *done = false;
    if (n < 3 || n > CUT_MAX_CORNERS || !top_undecided(s->tape))
        return true; /* f does not end in min/max */
    const ism_tape *local = deciding_local(s);
    size_t held = 0;
    while (local && held < n && ism_sampler_tape_at(s, pts[held].p) == local)
        held++;
    if (held == n)
        return true; /* one branch over the whole leaf (one_branch) */
    int br[CUT_MAX_CORNERS];
    size_t mixed[2], nmixed = 0;
    for (size_t i = 0; i < n; i++)
        if ((br[i] = ism_crease_branch(s, pts[i].p, NULL)) < 0)
            return true; /* no min/max at the top of the tape */
    for (size_t i = 0; i < n; i++)
        if (br[i] != br[(i + 1) % n] && nmixed++ < 2)
            mixed[nmixed - 1] = i;
    if (nmixed != 2)
        return true; /* one branch, or the crease crossing the polygon more than once */
    ism_fpoint x[2];
    for (int k = 0; k < 2; k++) {
        const double *p = pts[mixed[k]].p, *q = pts[(mixed[k] + 1) % n].p;
        double near = CUT_CORNER_SHARE * ism_dist3(p, q);
        if (!crease_point(s, p, q, &x[k]) || !(ism_dist3(x[k].p, p) > near) ||
            !(ism_dist3(x[k].p, q) > near))
            return true; /* no crease point found on that edge, or a corner on the crease */
    }
    if (!memcmp(x[0].p, x[1].p, sizeof x[0].p))
        return true;
    bool flip = ism_loop_reversed(s, node, pts, n);
    /* end[k]: the crease points as corners of the run after mixed edge k, with its branch's
       gradients (so the run's own fans are judged on one smooth surface) */
    ism_fpoint end[2][2], sub[CUT_MAX_CORNERS + 2];
    for (int j = 0; j < 2; j++) { /* x[j] starts run j and ends run 1 - j: both branches */
        double v[2], g[2][3];
        s->n_gradient++;
        if (!ism_eval_top_branches(top_tape(s, x[j].p), s->ws, x[j].p[0], x[j].p[1], x[j].p[2],
                                   v, g))
            return true;
        int bj = br[(mixed[j] + 1) % n], bo = br[(mixed[1 - j] + 1) % n];
        end[j][0] = x[j];
        memcpy(end[j][0].g, g[bj], sizeof end[j][0].g);
        end[1 - j][1] = x[j];
        memcpy(end[1 - j][1].g, g[bo], sizeof end[1 - j][1].g);
        if (!finite3(end[j][0].g) || !finite3(end[1 - j][1].g))
            return true;
    }
    for (int k = 0; k < 2; k++) {
        size_t m = branch_polygon(pts, n, mixed[k], mixed[1 - k], &end[k][0], &end[k][1], sub);
        if (!ism_triangulate_wound(s, sub, m, reach, node, max_error, flip, out))
            return false;
    }
    *done = true;
    return true;
}

/* Does the crease pass between triangle v's corners unseen: an edge whose two ends lie off
 * the crease on one branch with its midpoint on the other, or three such corners with the
 * centroid on the other; or an edge between two crease points whose middle lies farther than
 * sag from the crease (Newton from it)? */
static bool unseen_crease(ism_sampler *s, const ism_cell_out *out, const uint32_t *v,
                          double sag, uint8_t *labels, uint32_t first)
{
    const double *p[3];
    int b[3];
    for (int k = 0; k < 3; k++) {
        p[k] = out->verts[v[k]].p;
        b[k] = vertex_branch(s, out, labels, first, v[k]);
        b[k] = b[k] == LABEL_ANY ? -1 : b[k];
    }
    double m[3], x[3];
    for (int e = 0; e < 3; e++) {
        const double *a = p[e], *c = p[(e + 1) % 3];
        for (int k = 0; k < 3; k++)
            m[k] = x[k] = (a[k] + c[k]) / 2;
        if (b[e] < 0 && b[(e + 1) % 3] < 0) { /* a chord of the crease */
            if (ism_crease_newton(s, x) && ism_dist3(x, m) > sag)
                return true;
        } else if (b[e] >= 0 && b[e] == b[(e + 1) % 3] && ism_crease_branch(s, m, NULL) != b[e])
            return true;
    }
    if (b[0] < 0 || b[0] != b[1] || b[1] != b[2])
        return false;
    for (int k = 0; k < 3; k++)
        m[k] = (p[0][k] + p[1][k] + p[2][k]) / 3;
    return ism_crease_branch(s, m, NULL) != b[0];
}

bool ism_crease_unresolved(ism_sampler *s, const ism_cell_out *out, size_t first_tri,
                           double max_error, const double (*centroid_g)[3])
{
    if (first_tri == out->ntris || !top_undecided(s->tape) ||
        one_branch(s, out, first_tri, out->ntris))
        return false;
    uint32_t lo;
    uint8_t stack[LABELS_ON_STACK], *labels = leaf_labels(out, first_tri, stack, &lo);
    if (!labels)
        return false; /* out of memory: the leaf is kept as measured */
    bool unresolved = false;
    for (size_t t = first_tri; t < out->ntris && !unresolved; t++) {
        const uint32_t *v = out->tris + 3 * t;
        if ((unresolved = unseen_crease(s, out, v, CREASE_CHORD_SAG * max_error, labels, lo)))
            break;
        const double *a = out->verts[v[0]].p, *b = out->verts[v[1]].p, *c = out->verts[v[2]].p;
        double m[3], nrm[3], g[3];
        ism_tri_cross3(a, b, c, nrm);
        if (centroid_g) {
            memcpy(g, centroid_g[t - first_tri], sizeof g);
        } else {
            for (int k = 0; k < 3; k++)
                m[k] = (a[k] + b[k] + c[k]) / 3;
            ism_sample_grad(s, m, g);
        }
        double d = ism_dot3(nrm, g), l = ism_norm3(nrm) * ism_norm3(g);
        unresolved = l > 0 && d < CREASE_TURNED_COS * l;
    }
    if (labels != stack)
        free(labels);
    return unresolved;
}

double ism_crease_wedge_edges(const ism_grid *g, int max_depth, double max_error)
{
    if (!(max_error > 0))
        return 0;
    int level = max_depth > CREASE_WEDGE_LEVELS ? max_depth - CREASE_WEDGE_LEVELS : 0;
    int32_t steps = ism_grid_cell_steps(g, level);
    double d2 = 0;
    for (int a = 0; a < 3; a++) {
        double side = ism_grid_coord(g, a, steps) - ism_grid_coord(g, a, 0);
        d2 += side * side;
    }
    return sqrt(d2);
}
