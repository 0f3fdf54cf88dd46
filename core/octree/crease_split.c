/* crease_split.c — a leaf's triangles cut where f's top min/max changes branch, or where f
 * changes smooth piece (see crease_split.h). */
#include "core/octree/crease_split.h"
#include "core/octree/crease_memo.h"
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
/* The point where three pieces meet (Newton on the three from the centroid of the crease
 * points between them) is kept within this many times the crease points' largest distance
 * from that centroid: the three creases cross a polygon (or triangle) running round the
 * meeting point, so it lies about that far in; farther, Newton found another meeting point
 * (the cube's next corner) and the centroid on f = 0 stands in. */
#define CORNER_REACH 2.0
/* The branches' gradients count as parallel (no crease line through x, the 2 × 2 normal
 * system singular) when |ga|²|gb|² − (ga·gb)² is below this share of |ga|²|gb|²: a sine
 * of the crossing angle under 1e-6 rad, where a step would run along the crease. */
#define CREASE_PARALLEL_SIN2 1e-12

/* Branch labels of a leaf's vertices kept on the stack up to this many vertices (a leaf
 * emits a few dozen); more take the heap. */
#define LABELS_ON_STACK 256

/* A vertex's label: its branch of f's top min/max (0 or 1), or, where f has kinks below its
 * top or passes its min/max on (pieces mode, s->crease_pieces: cube-minus-ball's cube max(|x|, |y|, |z|) − 1
 * inside its top max, the cube itself), its smooth piece (ism_eval_piece): the crease
 * between two labels is where their functions (the top's branches, or f on each piece) are
 * both 0. In either mode a pair of labels is taken in increasing order (lo, hi): the top's
 * branches 0 and 1 as ism_eval_top_branches gives them. */
typedef ism_piece label_t;
/* A vertex whose label is not looked up yet (no piece: pieces mode asks ≤ ISM_PIECE_KINKS). */
#define LABEL_UNKNOWN ISM_PIECE_NONE
/* A crease point: on both branches, so no corner of a triangle is alone on its branch for it.
 * (Two bits 11 name no branch: no piece is this.) */
#define LABEL_ANY (ISM_PIECE_NONE - 1)

bool ism_crease_pieces(const ism_tape *f)
{
    size_t k = ism_tape_kinks(f);
    return k && k <= ISM_PIECE_KINKS && !ism_tape_top_min_max_only(f);
}

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

/* The label of point p computed: its piece in pieces mode (pm), else its top branch (a
 * pure function of p: top_tape gives f's branches bit for bit). */
static label_t label_fresh(ism_sampler *s, bool pm, const double p[3])
{
    if (!pm)
        return (label_t)ism_crease_branch(s, p, NULL);
    s->n_point++;
    return ism_eval_piece(s->tape, s->ws, p[0], p[1], p[2]);
}

/* The label of point p (label_t), through the sampler's label memo while s->tape is
 * s->memo_tape (sampler.h; none on the scalar reference path): the same
 * point's label once (pm is the sampler's crease_pieces, fixed for its run). Barth's sextic
 * at 1e-2 labelled its top branch 226,880 times without the memo, 123.6M of 3,205M
 * instructions (a leaf's vertices up to three times, its neighbours' shared ones again). */
static label_t label_at(ism_sampler *s, bool pm, const double p[3])
{
    if (s->memo_tape != s->tape)
        return label_fresh(s, pm, p);
    uint64_t b[3];
    memcpy(b, p, sizeof b);
    uint64_t h = (b[0] * 0x9e3779b97f4a7c15u) ^ (b[1] * 0xc2b2ae3d27d4eb4fu) ^
                 (b[2] * 0x165667b19e3779f9u);
    struct ism_label_memo *e = &s->label_memo[(h >> 32) % ISM_LABEL_MEMO];
    if (e->tape == s->tape && !memcmp(e->p, p, sizeof e->p))
        return e->label;
    label_t l = label_fresh(s, pm, p);
    memcpy(e->p, p, sizeof e->p);
    e->tape = s->tape;
    e->label = l;
    return l;
}

/* l[0], l[1] swapped when out of increasing order. */
static void order_pair(label_t *l)
{
    if (l[0] > l[1]) {
        label_t t = l[0];
        l[0] = l[1], l[1] = t;
    }
}

/* Labels l[0..m) (m = 2 or 3) put in increasing order, as every pair and triple of labels is
 * taken: the same bits in every leaf. */
static void order_labels(label_t *l, int m)
{
    order_pair(l);
    if (m == 3) {
        order_pair(l + 1);
        order_pair(l);
    }
}

/* The values and gradients at x of labels lo < hi's functions (v[0], g[0]: lo's): in pieces
 * mode f on each piece, else the top's two branches (lo, hi = 0, 1). False when f has no top
 * min/max (not in pieces mode). */
static bool pair_at(ism_sampler *s, bool pm, const double x[3], label_t lo, label_t hi,
                    double v[2], double g[2][3])
{
    s->n_gradient++;
    if (!pm)
        return ism_eval_top_branches(top_tape(s, x), s->ws, x[0], x[1], x[2], v, g);
    const label_t l[2] = {lo, hi};
    for (int k = 0; k < 2; k++)
        v[k] = ism_eval_piece_gradient(s->tape, s->ws, l[k], x[0], x[1], x[2], g[k]);
    return true;
}

/* The minimum-norm Newton step from x on m = 2 or 3 equations (labels l[0..m), each 0 on
 * its function); false when their gradients are dependent there or a value is not finite. */
static bool newton_delta(ism_sampler *s, bool pm, const double x[3], int m, const label_t *l,
                         double step[3])
{
    double v[3], g[3][3];
    pair_at(s, pm, x, l[0], l[1], v, g);
    if (m == 3) {
        s->n_gradient++;
        v[2] = ism_eval_piece_gradient(s->tape, s->ws, l[2], x[0], x[1], x[2], g[2]);
    }
    for (int k = 0; k < m; k++)
        if (!isfinite(v[k]))
            return false;
    return ism_min_norm_step(m, (const double (*)[3])g, v, CREASE_PARALLEL_SIN2, step);
}

/* x moved by one newton_delta step; false (x as it was) when that fails. */
static bool newton_step(ism_sampler *s, bool pm, double x[3], int m, const label_t *l)
{
    double step[3];
    if (!newton_delta(s, pm, x, m, l, step))
        return false;
    for (int k = 0; k < 3; k++)
        x[k] += step[k];
    return true;
}

/* CREASE_NEWTON_STEPS steps from x (false when one fails), ending early where a step leaves
 * x where it was (a fixed point: each step left would evaluate the same point and take the
 * same step) or x comes back to where it was two steps before (a 2-cycle of rounding: the
 * steps left would only repeat those two, so the last one's result is known). */
static bool newton(ism_sampler *s, bool pm, double x[3], int m, const label_t *l)
{
    double back[2][3]; /* back[it % 2]: x before step it */
    for (int it = 0; it < CREASE_NEWTON_STEPS; it++) {
        memcpy(back[it % 2], x, sizeof back[0]);
        if (!newton_step(s, pm, x, m, l))
            return false;
        if (memcmp(x, back[it % 2], sizeof back[0]) == 0)
            return true;
        if (it >= 1 && memcmp(x, back[(it + 1) % 2], sizeof back[0]) == 0) {
            if ((CREASE_NEWTON_STEPS - it - 1) % 2)
                memcpy(x, back[it % 2], sizeof back[0]);
            return true;
        }
    }
    return true;
}

bool ism_crease_newton(ism_sampler *s, double x[3])
{
    static const label_t top[2] = {0, 1};
    return newton(s, false, x, 2, top);
}

/* Is crease point x (lo = hi = 0) near enough lin, the linear estimate on an edge of length
 * len: within CREASE_REACH_EDGES, or on a short edge within CREASE_REACH_SLACK planar bounds
 * (the wedge is looked up only then)? */
static bool within_reach(ism_sampler *s, bool pm, const double x[3], const double lin[3],
                         double len, label_t lo, label_t hi)
{
    double d = ism_dist3(x, lin);
    if (d <= CREASE_REACH_EDGES * len)
        return true;
    if (!(len <= s->wedge_edges_below))
        return false;
    double v[2], g[2][3];
    if (!pair_at(s, pm, x, lo, hi, v, g))
        return false;
    double aa = ism_dot3(g[0], g[0]), bb = ism_dot3(g[1], g[1]), ab = ism_dot3(g[0], g[1]);
    /* sin w = sin of the gradients' angle; w ≥ 90° (ab ≥ 0): sin taken as 1 */
    double sin2 = ab >= 0 ? 1 : (aa * bb - ab * ab) / (aa * bb);
    return sin2 > 0 && d * d * sin2 <= CREASE_REACH_SLACK * CREASE_REACH_SLACK * len * len;
}

/* lo − hi's value at p: the top's a − b, or f on piece lo minus f on hi (values alone, the
 * bits pair_at's gradient passes give: ism_eval_piece_value). */
static double label_gap(ism_sampler *s, bool pm, const double p[3], label_t lo, label_t hi)
{
    double v[2];
    if (pm) {
        s->n_point += 2;
        v[0] = ism_eval_piece_value(s->tape, s->ws, lo, p[0], p[1], p[2]);
        v[1] = ism_eval_piece_value(s->tape, s->ws, hi, p[0], p[1], p[2]);
    } else {
        s->n_point++;
        ism_eval_top_values(top_tape(s, p), s->ws, p[0], p[1], p[2], v);
    }
    return v[0] - v[1];
}

/* x moved onto f = 0 along ∇f (up to CREASE_NEWTON_STEPS steps, fewer where ∇f vanishes or
 * f is not finite). */
static void onto_surface(ism_sampler *s, double x[3])
{
    for (int it = 0; it < CREASE_NEWTON_STEPS; it++) {
        double gf[3];
        double f = ism_sample_grad(s, x, gf), gg = ism_dot3(gf, gf);
        if (!(gg > 0) || !isfinite(f))
            break;
        for (int k = 0; k < 3; k++)
            x[k] -= f * gf[k] / gg;
    }
}

/* Pieces whose gradients at their crease point face one way within this sine (0.57°) meet
 * almost flat there: Steinmetz's cylinders x² + y² and x² + z² touch at (1, 0, 0), their
 * crease y = ±z crossing there at a vanishing angle. Cut at such a point, the triangles beside
 * it were slivers facing any way (normals from rounding: leaves split for "turned" triangles
 * at every level, the mesh at depth.max 10 no longer the one at 8); folded across it, a
 * triangle h wide lies about h × 0.01 / 4 off, which the measurement judges as anywhere. */
#define CREASE_FLAT_SIN 0.01

/* In pieces mode a mixed edge on which f lies within this share of max_error of 0 where its
 * pieces' values cross (fold_within) is left whole, the crease folded across it. A cut turns
 * one triangle into three and slivers them where the crease passes near a corner; folds within
 * the bound need none (default bound, own box: the cube 12,000 triangles cut everywhere,
 * 9,624 folded where they may; three balls 8,686 -> 8,230). Decided from the edge alone, so
 * the leaves sharing it agree (a leaf's own choice, fold or cut, left cracks where its
 * neighbour chose the other: three balls at E = 1e-4, χ −216). Not the whole bound: near a
 * point where three pieces meet a third piece bends the fold's triangles beyond what their
 * edges measure (Steinmetz at E = 1e-4 in the 1e-3 box: at 1.0 two depth-10 leaves beside its
 * corner (1, −1, 1) / √2 missed, 1.17 E; at 0.75 none). A leaf whose folds and bending
 * together miss the bound is split, as any leaf that misses it. */
#define CREASE_FOLD_SHARE 0.75

double ism_crease_fold_below(double max_error)
{
    return max_error > 0 ? CREASE_FOLD_SHARE * max_error : 0;
}

/* Is f within s->fold_below of 0 at lin, the point of a mixed edge where its pieces' values
 * cross (|f| / |∇f|)? For two planar pieces f on the edge is the larger (or smaller) of two
 * linear functions, so its distance peaks there; and on a triangle folded across one crease
 * it peaks on the kink line's ends, which are such points of its mixed edges: the triangle is
 * within what its edges are. */
static bool fold_within(ism_sampler *s, const double lin[3])
{
    if (!(s->fold_below > 0))
        return false;
    double g[3], f = ism_sample_grad(s, lin, g), gn = ism_norm3(g);
    return gn > 0 && fabs(f) <= s->fold_below * gn;
}

/* A fold is allowed only where the pieces' gradients at the crease point are at most this
 * cosine's angle apart (120°: a wedge of 60° or more, the cube's 90° edges, the three balls'
 * valleys): across a sharper wedge (cube-minus-ball's 40° between a face and its ball) a
 * folded triangle faces more than 120° from the gradient at its centroid on one side, the
 * turned test (CREASE_TURNED_COS) splits its leaf, and the default bound's mesh doubled
 * (17,704 -> 34,736 triangles). */
#define CREASE_FOLD_COS (-0.5)

/* A crease point within this share of its edge's length from an end is that corner (on the
 * crease, up to rounding: the double torus's corners on its mirror plane x = 1.1): neither the
 * polygon cut nor the triangle split (crease_point's at_end, both modes) cuts there, since the
 * pieces would join a corner and a point a rounding error apart, two vertices the weld keeps
 * apart (an edge in four triangles: test_polygonise_crease.c's
 * double_torus_closed_under_a_bound; zero-area triangles: its
 * double_torus_one_vertex_per_crease_point). */
#define CUT_CORNER_SHARE 1e-6

/* Why a mixed edge is left whole (crease_point's *whole; 0: it is cut at its crease point):
 * folded within the bound, its pieces almost flat at the crease, or the crease through one of
 * its ends (CUT_CORNER_SHARE: a new vertex there would be a second, unwelded copy of that
 * corner, its triangles flat — three balls' crease in the lattice plane y = 0 of its own box,
 * 4 such triangles; Steinmetz's corners on x = y, an edge in four triangles). */
enum { WHOLE_FOLD = 1, WHOLE_FLAT = 2, WHOLE_END = 3 };

/* Is crease point x one of edge p-q's ends, to within CUT_CORNER_SHARE of its length? */
static bool at_end(const double *p, const double *q, const double x[3])
{
    double near = CUT_CORNER_SHARE * ism_dist3(p, q);
    return !(ism_dist3(x, p) > near) || !(ism_dist3(x, q) > near);
}

/* Is a mixed edge p-q with crease point x of labels l[0], l[1] (pieces mode) better left
 * whole: WHOLE_FLAT where the pieces meet almost flat at x (CREASE_FLAT_SIN), WHOLE_FOLD where
 * the fold is within the bound at lin (fold_within, lin the point where the pieces' values
 * cross on the edge) across a wedge no sharper than CREASE_FOLD_COS allows; else 0 (x is
 * not one of its ends: at_end, tested first). */
static int whole_edge(ism_sampler *s, const double lin[3], const double x[3], const label_t l[2])
{
    double v[2], g[2][3];
    pair_at(s, true, x, l[0], l[1], v, g);
    double aa = ism_dot3(g[0], g[0]), bb = ism_dot3(g[1], g[1]), ab = ism_dot3(g[0], g[1]);
    if (ab > 0 && aa * bb - ab * ab < CREASE_FLAT_SIN * CREASE_FLAT_SIN * aa * bb)
        return WHOLE_FLAT;
    return ab >= CREASE_FOLD_COS * sqrt(aa * bb) && fold_within(s, lin) ? WHOLE_FOLD : 0;
}

/* The crease point of edge p-q (p before q), whose ends carry labels l[0] < l[1]: Newton on
 * l[0] = l[1] = 0 from where l[0] − l[1] changes sign along the edge (flagged ISM_FP_CREASE;
 * true), or that linear estimate moved onto f = 0 (false). *whole: nonzero where the edge is better left whole:
 * WHOLE_END where that point is one of its ends (at_end; in either mode, found by Newton or
 * not: a crease through a corner, as the double torus's on its own box's middle plane x = 1.1,
 * gives a point a rounding error from it, 1e-16 to 1e-14 off, which a cut would add as a second,
 * unwelded copy of the corner beside zero-area triangles); in pieces mode also where the
 * pieces meet almost flat there or the fold is within the bound (whole_edge). */
static bool crease_point_fresh(ism_sampler *s, bool pm, const double *p, const double *q,
                               const label_t l[2], ism_fpoint *out, int *whole)
{
    double d[2];
    const double *ends[2] = {p, q};
    for (int e = 0; e < 2; e++)
        d[e] = label_gap(s, pm, ends[e], l[0], l[1]);
    double t = d[0] / (d[0] - d[1]);
    if (!(t >= 0 && t <= 1))
        t = 0.5;
    double lin[3], x[3];
    for (int k = 0; k < 3; k++)
        lin[k] = x[k] = p[k] + t * (q[k] - p[k]);
    bool ok = newton(s, pm, x, 2, l);
    ok = ok && within_reach(s, pm, x, lin, ism_dist3(p, q), l[0], l[1]);
    if (!ok) {
        memcpy(x, lin, sizeof x); /* onto f = 0 along ∇f at least */
        onto_surface(s, x);
        if (!(ism_dist3(x, lin) <= CREASE_REACH_EDGES * ism_dist3(p, q)))
            memcpy(x, ism_dist3(lin, p) <= ism_dist3(lin, q) ? p : q, sizeof x);
    }
    memcpy(out->p, x, sizeof out->p);
    ism_sample_grad(s, x, out->g);
    out->flags = ok ? ISM_FP_INTERIOR | ISM_FP_CREASE : ISM_FP_INTERIOR;
    *whole = at_end(p, q, x) ? WHOLE_END : pm && ok ? whole_edge(s, lin, x, l) : 0;
    return ok;
}

/* crease_point_fresh's answer for edge p0-q0 (its ends in ism_edge_key_set's order, its
 * labels lp != lq in increasing order: the same bits from either leaf beside it), through
 * the sampler's crease memo when it has one for the tape it evaluates (crease_memo.h: a hit
 * is that answer, stored). */
static bool crease_point(ism_sampler *s, bool pm, const double *p0, const double *q0,
                         label_t lp, label_t lq, ism_fpoint *out, int *whole)
{
    label_t l[2] = {lp, lq};
    order_labels(l, 2);
    ism_edge_key k;
    ism_edge_key_set(&k, p0, q0, l[0], l[1]);
    ism_crease_memo *m = s->memo_tape == s->tape ? s->crease_memo : NULL;
    ism_crease_entry *e = m ? ism_crease_memo_slot(m, &k) : NULL;
    if (e && ism_edge_key_same(&e->k, &k)) {
        m->hits++;
        *out = e->x;
        *whole = e->whole;
        return e->found;
    }
    bool ok = crease_point_fresh(s, pm, k.p, k.q, l, out, whole);
    if (e && l[0] != l[1]) {
        e->k = k;
        e->x = *out;
        e->whole = *whole;
        e->found = ok;
    }
    return ok;
}

/* Where the creases between crease points x[0..k) meet (k = 3 or 4), the pieces of l[0..m)
 * all 0 there (m = 3: three pieces meet, the cube's corner, three faces' planes; m = 2: one
 * crease crossing itself, Steinmetz's y = ±z on its cylinders x² + y² and x² + z² at
 * (1, 0, 0)): Newton on the m from the crease points' centroid, kept when it lands within
 * CORNER_REACH times their spread (largest distance from the centroid; true, flagged
 * ISM_FP_CREASE); else the centroid moved onto f = 0 (false). */
static bool corner_point(ism_sampler *s, const ism_fpoint *x, int k, const label_t *l, int m,
                         ism_fpoint *out)
{
    double c[3] = {0, 0, 0}, p[3], spread = 0;
    for (int j = 0; j < k; j++)
        for (int a = 0; a < 3; a++)
            c[a] += x[j].p[a] / k;
    for (int j = 0; j < k; j++)
        spread = fmax(spread, ism_dist3(x[j].p, c));
    label_t o[3] = {l[0], l[1], m == 3 ? l[2] : 0};
    order_labels(o, m);
    memcpy(p, c, sizeof p);
    bool ok = newton(s, true, p, m, o) && ism_dist3(p, c) <= CORNER_REACH * spread;
    if (!ok) {
        memcpy(p, c, sizeof p);
        onto_surface(s, p);
    }
    memcpy(out->p, p, sizeof out->p);
    ism_sample_grad(s, p, out->g);
    out->flags = ok ? ISM_FP_INTERIOR | ISM_FP_CREASE : ISM_FP_INTERIOR;
    return ok;
}

/* The label of vertex v (labels[v - first], looked up once); LABEL_ANY for a crease point
 * a polygon was cut at (ism_crease_cut_loop), which lies on both. */
static label_t vertex_label(ism_sampler *s, bool pm, const ism_cell_out *out, label_t *labels,
                            uint32_t first, uint32_t v)
{
    if (out->verts[v].flags & ISM_FP_CREASE)
        return LABEL_ANY;
    label_t *l = &labels[v - first];
    if (*l == LABEL_UNKNOWN)
        *l = label_at(s, pm, out->verts[v].p);
    return *l;
}

/* Triangle t (corners a, b, c on three pieces) cut at its edges' crease points and the
 * point where the three pieces meet, into six: each corner's quadrilateral (corner, crease
 * point, meeting point, crease point) on its piece alone. An edge left whole (crease_point's
 * whole: the fold within s->fold_below, almost flat, or its crease point one of its ends,
 * at_end) is not cut, its triangle with the
 * meeting point folded across it; the meeting point is inserted even when all three are
 * whole: a fold's distance is bounded by its edges' only where one crease crosses it, and the
 * corner where three meet (the cube's) stands off the triangle across all three (Steinmetz at
 * E = 1e-4 in the 1e-3 box: 2 leaves missed, 1.17 E). */
static bool split_three(ism_sampler *s, ism_cell_out *out, size_t t, const label_t br[3])
{
    uint32_t c[3], x[3] = {UINT32_MAX, UINT32_MAX, UINT32_MAX}, m;
    ism_fpoint e[3], mid;
    int whole[3];
    memcpy(c, out->tris + 3 * t, sizeof c);
    for (int k = 0; k < 3; k++) /* e[k]: on edge c[k]-c[k+1] */
        crease_point(s, true, out->verts[c[k]].p, out->verts[c[(k + 1) % 3]].p, br[k],
                     br[(k + 1) % 3], &e[k], &whole[k]);
    corner_point(s, e, 3, br, 3, &mid);
    /* the meeting point on a corner or a crease point (to rounding: the three balls' in the
       irrational box, on its edge) is that vertex, not a copy the weld keeps apart; on a
       corner, an edge whose crease point is that corner too (within the same tolerance,
       though further than its own edge's WHOLE_END share) is left whole, else its cut
       triangles would join two copies of one point */
    double size = 0;
    for (int k = 0; k < 3; k++)
        size = fmax(size, ism_dist3(out->verts[c[k]].p, out->verts[c[(k + 1) % 3]].p));
    double tol = CUT_CORNER_SHARE * size;
    m = UINT32_MAX;
    for (int k = 0; k < 3 && m == UINT32_MAX; k++)
        if (!(ism_dist3(out->verts[c[k]].p, mid.p) > tol))
            m = c[k];
    for (int k = 0; k < 3 && m != UINT32_MAX; k++)
        if (!whole[k] && !(ism_dist3(e[k].p, out->verts[m].p) > tol))
            whole[k] = WHOLE_END;
    for (int k = 0; k < 3; k++)
        if (!whole[k] && !ism_cell_out_vert(out, &e[k], &x[k]))
            return false;
    for (int k = 0; k < 3 && m == UINT32_MAX; k++)
        if (!whole[k] && !(ism_dist3(out->verts[x[k]].p, mid.p) > tol))
            m = x[k];
    if (m == UINT32_MAX && !ism_cell_out_vert(out, &mid, &m))
        return false;
    /* corner k's triangles: toward its next corner (or that edge's point), and back to the
       point on the edge before it (a whole edge's one triangle is the corner before's); the
       first replaces t, none with a repeated vertex (m on one of them) */
    uint32_t tris[6][3];
    int n = 0;
    for (int k = 0; k < 3; k++) {
        uint32_t next = whole[k] ? c[(k + 1) % 3] : x[k], prev = x[(k + 2) % 3];
        if (next != m && c[k] != m)
            tris[n][0] = c[k], tris[n][1] = next, tris[n][2] = m, n++;
        if (!whole[(k + 2) % 3] && prev != m && c[k] != m)
            tris[n][0] = c[k], tris[n][1] = m, tris[n][2] = prev, n++;
    }
    memcpy(out->tris + 3 * t, tris[0], sizeof tris[0]);
    for (int j = 1; j < n; j++)
        if (!ism_cell_out_tri(out, tris[j][0], tris[j][1], tris[j][2]))
            return false;
    return true;
}

/* Splits triangles first_tri..ntris - 1, whose vertices lie in first..first + n - 1 (labels:
 * n entries of LABEL_UNKNOWN). */
static bool split_labelled(ism_sampler *s, bool pm, ism_cell_out *out, size_t first_tri,
                           size_t ntris, label_t *labels, uint32_t first)
{
    for (size_t t = first_tri; t < ntris; t++) {
        label_t br[3];
        for (int k = 0; k < 3; k++)
            br[k] = vertex_label(s, pm, out, labels, first, out->tris[3 * t + k]);
        if (br[0] == LABEL_ANY || br[1] == LABEL_ANY || br[2] == LABEL_ANY)
            continue; /* a cut polygon's triangle: its other corners share one branch */
        if (br[0] == br[1] && br[1] == br[2])
            continue;
        if (br[0] != br[1] && br[1] != br[2] && br[0] != br[2]) { /* pieces mode only */
            if (!split_three(s, out, t, br))
                return false;
            continue;
        }
        /* r: the corner alone on its branch; the others follow it in winding order */
        int r = br[0] == br[1] ? 2 : br[0] == br[2] ? 1 : 0;
        uint32_t a = out->tris[3 * t + r], b = out->tris[3 * t + (r + 1) % 3],
                 c = out->tris[3 * t + (r + 2) % 3];
        label_t la = br[r], lo = br[(r + 1) % 3];
        ism_fpoint ab, ac;
        int fab, fac; /* an edge better left whole stays so (crease_point's *whole) */
        crease_point(s, pm, out->verts[a].p, out->verts[b].p, la, lo, &ab, &fab);
        crease_point(s, pm, out->verts[a].p, out->verts[c].p, la, lo, &ac, &fac);
        uint32_t iab, iac, *tri = out->tris + 3 * t;
        if ((!fab && !ism_cell_out_vert(out, &ab, &iab)) ||
            (!fac && !ism_cell_out_vert(out, &ac, &iac)))
            return false;
        if (fab && fac)
            continue;
        if (fab) { /* a-c alone cut: (a, b, ac), (ac, b, c) */
            tri[0] = a, tri[1] = b, tri[2] = iac;
            if (!ism_cell_out_tri(out, iac, b, c))
                return false;
            continue;
        }
        if (fac) { /* a-b alone cut: (a, ab, c), (ab, b, c) */
            tri[0] = a, tri[1] = iab, tri[2] = c;
            if (!ism_cell_out_tri(out, iab, b, c))
                return false;
            continue;
        }
        tri[0] = a, tri[1] = iab, tri[2] = iac;
        if (!ism_cell_out_tri(out, iab, b, c) || !ism_cell_out_tri(out, iab, c, iac))
            return false;
    }
    return true;
}

/* The leaf's shortened tape when it holds f to one label over its closed box — it decides
 * f's top min/max (strictly), or in pieces mode its intervals decide every kink on f's
 * path (ism_tape_one_piece: one interval pass of the short tape) — so the points it holds
 * (ism_sampler_tape_at) lie on the one branch it keeps; else NULL. Looked up once per leaf,
 * at its first use there (kept in s->local_deciding): a lookup per point cost 0.3% more
 * instructions on cube-minus-ball (callgrind), and one per polygon repeated the pieces mode's
 * tape scan and interval pass for the same local and box. */
static const ism_tape *deciding_local(ism_sampler *s)
{
    if (s->local_decided)
        return s->local_deciding;
    const ism_tape *d = NULL;
    if (s->local && !s->crease_pieces) {
        d = !top_undecided(s->local) ? s->local : NULL;
    } else if (s->local) {
        const double *b = s->local_box;
        ism_interval x = {b[0], b[3]}, y = {b[1], b[4]}, z = {b[2], b[5]};
        d = ism_tape_one_piece(s->local, s->ws, x, y, z) ? s->local : NULL;
    }
    s->local_deciding = d;
    s->local_decided = true;
    return d;
}

/* Do all vertices of triangles first_tri..ntris - 1 lie on one branch (deciding_local)? */
static bool one_branch(ism_sampler *s, const ism_cell_out *out, size_t first_tri,
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

/* Labels for the vertices of triangles first_tri..ntris - 1, all LABEL_UNKNOWN: stack when
 * they fit, else malloc'd (the caller frees what is not stack; NULL: out of memory); *lo: the
 * lowest of those vertices, labels[v - *lo] vertex v's. */
static label_t *leaf_labels(const ism_cell_out *out, size_t first_tri,
                            label_t stack[LABELS_ON_STACK], uint32_t *lo)
{
    uint32_t hi = 0;
    *lo = UINT32_MAX;
    for (size_t i = 3 * first_tri; i < 3 * out->ntris; i++) {
        *lo = out->tris[i] < *lo ? out->tris[i] : *lo;
        hi = out->tris[i] > hi ? out->tris[i] : hi;
    }
    size_t n = (size_t)hi - *lo + 1;
    label_t *labels = n <= LABELS_ON_STACK ? stack : malloc(n * sizeof *labels);
    for (size_t i = 0; labels && i < n; i++)
        labels[i] = LABEL_UNKNOWN;
    return labels;
}

bool ism_crease_split(ism_sampler *s, ism_cell_out *out, size_t first_tri)
{
    size_t ntris = out->ntris;
    bool pm = s->crease_pieces;
    if (first_tri == ntris || one_branch(s, out, first_tri, ntris))
        return true;
    double v[2];
    const double *p0 = out->verts[out->tris[3 * first_tri]].p;
    const ism_tape *t0 = top_tape(s, p0);
    if (!pm) {
        s->n_point++;
        if (!ism_eval_top_values(t0, s->ws, p0[0], p0[1], p0[2], v))
            return true; /* no min/max at the top of the tape */
    }
    uint32_t lo;
    label_t stack[LABELS_ON_STACK], *labels = leaf_labels(out, first_tri, stack, &lo);
    if (!labels)
        return false;
    if (!pm)
        labels[out->tris[3 * first_tri] - lo] = (label_t)ism_top_active_branch(t0, v);
    bool ok = split_labelled(s, pm, out, first_tri, ntris, labels, lo);
    if (labels != stack)
        free(labels);
    return ok;
}

/* A triangle faces against ∇f at its centroid when their directions are more than 120° apart
 * (a smooth patch's triangles, even bent beside a crease, face within a few tens of degrees
 * of it). */
#define CREASE_TURNED_COS (-0.5)

/* A chord between two crease points whose middle lies farther than this share of max_error
 * from the crease (Newton from the middle: chord_foot, chord_strays) is followed first: the
 * cut puts crease points along it (crease_path); where that cannot, or a chord of the leaf's
 * triangles still strays, the leaf is left to be split (ism_crease_unresolved): the chord's
 * triangles on either side lie that far off their branches near it. */
#define CREASE_CHORD_SAG 0.5

/* A cut polygon has at most this many corners (a leaf's polygons have a few dozen at most:
 * crack repair adds the finer neighbours' points to a face); a larger one is triangulated
 * whole and its triangles split (ism_crease_split). */
#define CUT_MAX_CORNERS 64


/* Runs of one label a cut polygon may have: 2 (one crease across it), 3 (three pieces
 * meeting in it) or 4 (two pieces, their crease crossing itself in it). */
#define CUT_MAX_RUNS 4

/* Do the runs after mixed edges mixed[0..k) (pieces mode) meet in one point: three runs on
 * three pieces, or four alternating on two? */
static bool meeting_runs(const label_t *br, size_t n, const size_t *mixed, size_t k)
{
    label_t r[CUT_MAX_RUNS];
    if (k != 3 && k != 4)
        return false;
    for (size_t j = 0; j < k; j++)
        r[j] = br[(mixed[j] + 1) % n];
    if (k == 3)
        return r[0] != r[1] && r[1] != r[2] && r[0] != r[2];
    return r[0] == r[2] && r[1] == r[3] && r[0] != r[1];
}

/* Is every component of g finite? */
static bool finite3(const double g[3])
{
    return isfinite(g[0]) && isfinite(g[1]) && isfinite(g[2]);
}

/* The run of corners from + 1 .. to (cyclically) of pts between crease points a and b into
 * sub, in the polygon's order: a, the run, b (the chord b-a closes it), then c when not NULL
 * (the point where three pieces meet); a or b NULL: the run's edge there is left whole (its
 * end corner closes the polygon instead); its length. */
static size_t branch_polygon(const ism_fpoint *pts, size_t n, size_t from, size_t to,
                             const ism_fpoint *a, const ism_fpoint *b, const ism_fpoint *c,
                             ism_fpoint *sub)
{
    size_t m = 0;
    if (a)
        sub[m++] = *a;
    for (size_t i = (from + 1) % n;; i = (i + 1) % n) {
        sub[m++] = pts[i];
        if (i == to)
            break;
    }
    if (b)
        sub[m++] = *b;
    if (c)
        sub[m++] = *c;
    return m;
}

/* p with the gradient of f on piece l there (pieces mode): false when not finite. */
static bool on_piece(ism_sampler *s, ism_fpoint *p, label_t l)
{
    s->n_gradient++;
    ism_eval_piece_gradient(s->tape, s->ws, l, p->p[0], p->p[1], p->p[2], p->g);
    return finite3(p->g);
}

/* A polygon whose corners run on k = 3 pieces, or on two pieces in k = 4 alternating runs
 * (mixed edges mixed[0..k)), cut at its mixed edges' crease points x and the point where those
 * creases meet (corner_point): each run's polygon (the crease point before it, the run, the one
 * after it, the meeting point) triangulated on its own. A mixed edge left whole (whole[j], a
 * fold within the bound: whole_edge) is not cut: the runs beside it end at its corners, and
 * its one triangle with the meeting point folds across it (the meeting point is kept: the
 * corner where three pieces meet stands off any triangle folded round it, Steinmetz's corner
 * (1, −1, 1) / √2 at E = 1e-4 two leaves 1.17 E off). *done false when the meeting point is not
 * found. */
static bool cut_runs(ism_sampler *s, const ism_fpoint *pts, size_t n, const label_t *br,
                     const size_t *mixed, int k, const ism_fpoint *x, const int *whole,
                     double reach, const double node[6], double max_error, ism_cell_out *out,
                     bool *done)
{
    label_t run[CUT_MAX_RUNS];
    for (int j = 0; j < k; j++)
        run[j] = br[(mixed[j] + 1) % n];
    ism_fpoint c;
    if (!corner_point(s, x, k, run, k == 3 ? 3 : 2, &c))
        return true;
    /* run j (after mixed edge j, up to mixed edge j + 1): its crease points and the meeting
       point with its piece's gradients (its fans judged on one smooth surface) */
    ism_fpoint a[CUT_MAX_RUNS], b[CUT_MAX_RUNS], m[CUT_MAX_RUNS], sub[CUT_MAX_CORNERS + 3];
    for (int j = 0; j < k; j++) {
        a[j] = x[j], b[j] = x[(j + 1) % k], m[j] = c;
        if (!on_piece(s, &a[j], run[j]) || !on_piece(s, &b[j], run[j]) ||
            !on_piece(s, &m[j], run[j]))
            return true;
    }
    bool flip = ism_loop_reversed(s, node, pts, n);
    for (int j = 0; j < k; j++) {
        size_t len = branch_polygon(pts, n, mixed[j], mixed[(j + 1) % k], whole[j] ? NULL : &a[j],
                                    whole[(j + 1) % k] ? NULL : &b[j], &m[j], sub);
        if (!ism_triangulate_wound(s, sub, len, reach, node, max_error, flip, out))
            return false;
        if (!whole[j])
            continue;
        /* the whole edge before run j and the meeting point */
        sub[0] = pts[mixed[j]], sub[1] = pts[(mixed[j] + 1) % n], sub[2] = m[j];
        if (!ism_triangulate_wound(s, sub, 3, reach, node, max_error, flip, out))
            return false;
    }
    *done = true;
    return true;
}

/* A cut's chord whose middle lies farther than CREASE_CHORD_SAG × the bound from the crease
 * is replaced by a path of crease points, each the middle of its two neighbours moved onto the
 * crease by Newton, halved again where a half's middle still lies that far, down to this many
 * halvings (up to 2^CUT_PATH_HALVINGS − 1 points). Barth's sextic cut by its ball at E 0.0259:
 * the crease is a small loop round the spike's tip, 12 level-4 leaves hold an arc of it whose
 * chord's middle lay 0.0185 from it (E / 2 = 0.013), and a second round split them (1,128
 * leaves polygonised again); with the path the mesh is made in one round. Only on f's top
 * min/max of two branches, not in pieces mode: there a path between two pieces can pass where
 * a third takes over (three-balls' triple point (0, 0, 0.374) at the default bound: an 8.7°
 * needle at it the quality pass kept, tests/cli/test_quality.py). */
#define CUT_PATH_HALVINGS 3
#define CUT_PATH_MAX ((1 << CUT_PATH_HALVINGS) - 1)

/* The middle of chord a-b between two crease points moved onto the crease of labels l[0] <
 * l[1] (Newton from it) in x: its distance from the middle, the chord's sag; -1 where Newton
 * fails. */
static double chord_foot(ism_sampler *s, bool pm, const double *a, const double *b,
                         const label_t l[2], double x[3])
{
    double m[3];
    for (int k = 0; k < 3; k++)
        m[k] = x[k] = (a[k] + b[k]) / 2;
    return newton(s, pm, x, 2, l) ? ism_dist3(x, m) : -1;
}

/* Does a chord whose middle's foot lies d from it (chord_foot) stray from the crease: d past
 * sag = CREASE_CHORD_SAG × max_error (a failed or not finite foot does not)? The one rule
 * both crease_path (follow the crease) and unseen_crease (split the leaf) read. */
static bool chord_strays(double d, double sag)
{
    return d >= 0 && d > sag;
}

/* A point of the crease path: the crease point's position and both branches' gradients. */
typedef struct path_pt {
    double p[3], g[2][3];
} path_pt;

/* Is x strictly inside node (lo xyz, hi xyz)? (A path point on a face would lie in the
 * neighbour's polygon's side without the neighbour knowing: a crack.) */
static bool in_node(const double x[3], const double node[6])
{
    for (int k = 0; k < 3; k++)
        if (!(x[k] > node[k] && x[k] < node[3 + k]))
            return false;
    return true;
}

/* The crease points between a and b (labels lo < hi), in order from a, appended to
 * path[*n..): the chord a-b's middle moved onto the crease (chord_far's Newton) when it lands
 * farther than sag from the middle, with both halves followed the same way while halvings are
 * left. False when a point is not found, leaves the node, or has a gradient that is not
 * finite: the chord then stays (ism_crease_unresolved judges it). */
static bool crease_path(ism_sampler *s, bool pm, const double *a, const double *b, label_t lo,
                        label_t hi, double sag, const double node[6], int halvings,
                        path_pt *path, int *n)
{
    double x[3], v[2];
    const label_t l[2] = {lo, hi};
    if (halvings == 0)
        return true;
    double d = chord_foot(s, pm, a, b, l, x);
    if (d < 0)
        return false;
    if (!chord_strays(d, sag))
        return true;
    if (!in_node(x, node) || *n >= CUT_PATH_MAX)
        return false;
    if (!crease_path(s, pm, a, x, lo, hi, sag, node, halvings - 1, path, n))
        return false;
    path_pt *q = &path[(*n)++];
    memcpy(q->p, x, sizeof x);
    if (!pair_at(s, pm, x, lo, hi, v, q->g) || !finite3(q->g[0]) || !finite3(q->g[1]))
        return false;
    return crease_path(s, pm, q->p, b, lo, hi, sag, node, halvings - 1, path, n);
}

/* Does the crease path leave its end x, the crease point on the polygon's edge pts[i] →
 * pts[i + 1], into the polygon: its point p next to x strictly on the inner side of that
 * edge's line, seen along the polygon's normal nrm (Newell's: the inside is on the left of
 * each edge)? At x the two run polygons share the path's first segment and take one half of
 * the edge each; with p on the outer side both turn back at x (their angles there sum past a
 * half-turn) and their triangles overlap: a fold, whatever the path does farther on. That is
 * how a foot on another arc of the crease shows: a crease loop most of which lies inside the
 * polygon, the chord between its two crease points cutting off a short arc outside it (Newton
 * from the chord's middle goes to the nearer, outer arc, which leaves x outward). A foot a
 * little past another side of a curved polygon, its path leaving both ends inward, is kept: it
 * lies inside the node (in_node), on the crease between the ends (Barth's 12 paths at 0.0259
 * reach 0.20 of their chord past the polygon's projection and leave their ends 0.40 / 0.48
 * of it inward). */
static bool leaves_inward(const ism_fpoint *pts, size_t n, size_t i, const double nrm[3],
                          const double *x, const double *p)
{
    double e[3], in[3], d[3];
    for (int k = 0; k < 3; k++) {
        e[k] = pts[(i + 1) % n].p[k] - pts[i].p[k];
        d[k] = p[k] - x[k];
    }
    ism_cross3(nrm, e, in);
    return ism_dot3(in, d) > 0;
}

/* The crease path of a cut polygon pts[0..n) between its crease points x[0] and x[1] (on the
 * edges after corners mixed[0], mixed[1]): crease_path's points into path, their count; 0
 * (the chord stays) where crease_path cannot follow the crease or the path does not leave
 * both ends into the polygon (leaves_inward). */
static int follow_crease(ism_sampler *s, bool pm, const ism_fpoint *pts, size_t n,
                         const size_t mixed[2], const ism_fpoint x[2], label_t lo, label_t hi,
                         const double node[6], path_pt *path)
{
    int npath = 0;
    if (!crease_path(s, pm, x[0].p, x[1].p, lo, hi, CREASE_CHORD_SAG * s->dist_above, node,
                     CUT_PATH_HALVINGS, path, &npath))
        return 0;
    if (npath == 0)
        return 0;
    double nrm[3];
    ism_newell(pts, n, nrm);
    if (!leaves_inward(pts, n, mixed[0], nrm, x[0].p, path[0].p) ||
        !leaves_inward(pts, n, mixed[1], nrm, x[1].p, path[npath - 1].p))
        return 0;
    return npath;
}

bool ism_crease_cut_loop(ism_sampler *s, const ism_fpoint *pts, size_t n, double reach,
                         const double node[6], double max_error, ism_cell_out *out, bool *done)
{
    *done = false;
    bool pm = s->crease_pieces;
    if (n < 3 || n > CUT_MAX_CORNERS || (!pm && !top_undecided(s->tape)))
        return true; /* f does not end in min/max */
    const ism_tape *local = deciding_local(s);
    size_t held = 0;
    while (local && held < n && ism_sampler_tape_at(s, pts[held].p) == local)
        held++;
    if (held == n)
        return true; /* one branch over the whole leaf (one_branch) */
    label_t br[CUT_MAX_CORNERS];
    size_t mixed[CUT_MAX_RUNS], nmixed = 0;
    for (size_t i = 0; i < n; i++)
        if ((br[i] = label_at(s, pm, pts[i].p)) == ISM_PIECE_NONE)
            return true; /* no min/max at the top of the tape (-1 as a label_t) */
    for (size_t i = 0; i < n; i++)
        if (br[i] != br[(i + 1) % n] && nmixed++ < CUT_MAX_RUNS)
            mixed[nmixed - 1] = i;
    if (nmixed != 2 && !(pm && meeting_runs(br, n, mixed, nmixed)))
        return true; /* one branch, or the crease crossing the polygon more than once */
    ism_fpoint x[CUT_MAX_RUNS];
    int whole[CUT_MAX_RUNS];
    for (size_t k = 0; k < nmixed; k++) {
        size_t i = mixed[k], j = (i + 1) % n;
        if (!crease_point(s, pm, pts[i].p, pts[j].p, br[i], br[j], &x[k], &whole[k]) ||
            whole[k] == WHOLE_FLAT || whole[k] == WHOLE_END || (whole[k] && nmixed == 2))
            return true; /* no crease point found on that edge (or an almost flat one, or a
                            fold across the one crease: its triangles split alone), or a
                            corner on the crease */
    }
    if (nmixed > 2)
        return cut_runs(s, pts, n, br, mixed, (int)nmixed, x, whole, reach, node, max_error,
                        out, done);
    if (!memcmp(x[0].p, x[1].p, sizeof x[0].p))
        return true;
    bool flip = ism_loop_reversed(s, node, pts, n);
    /* end[k]: the crease points as corners of the run after mixed edge k, with its branch's
       gradients (so the run's own fans are judged on one smooth surface) */
    ism_fpoint end[2][2], sub[CUT_MAX_CORNERS + 3 + CUT_PATH_MAX];
    label_t run[2] = {br[(mixed[0] + 1) % n], br[(mixed[1] + 1) % n]}; /* the runs' labels */
    order_labels(run, 2);
    label_t lo = run[0], hi = run[1];
    for (int j = 0; j < 2; j++) { /* x[j] starts run j and ends run 1 - j: both branches */
        double v[2], g[2][3];
        if (!pair_at(s, pm, x[j].p, lo, hi, v, g))
            return true;
        label_t bj = br[(mixed[j] + 1) % n], bo = br[(mixed[1 - j] + 1) % n];
        end[j][0] = x[j];
        memcpy(end[j][0].g, g[bj == lo ? 0 : 1], sizeof end[j][0].g);
        end[1 - j][1] = x[j];
        memcpy(end[1 - j][1].g, g[bo == lo ? 0 : 1], sizeof end[1 - j][1].g);
        if (!finite3(end[j][0].g) || !finite3(end[1 - j][1].g))
            return true;
    }
    /* the crease between x[0] and x[1] followed where their chord strays from it */
    path_pt path[CUT_PATH_MAX];
    int npath = !pm && s->dist_above > 0
                    ? follow_crease(s, pm, pts, n, mixed, x, lo, hi, node, path)
                    : 0;
    for (int k = 0; k < 2; k++) {
        size_t m = branch_polygon(pts, n, mixed[k], mixed[1 - k], &end[k][0], &end[k][1], NULL,
                                  sub);
        /* run k ends at x[1 - k]: the path back to x[k], its branch's gradients */
        int side = br[(mixed[k] + 1) % n] == lo ? 0 : 1;
        for (int j = 0; j < npath; j++) {
            const path_pt *q = &path[k == 0 ? npath - 1 - j : j];
            ism_fpoint *o = &sub[m++];
            memcpy(o->p, q->p, sizeof o->p);
            memcpy(o->g, q->g[side], sizeof o->g);
            o->flags = ISM_FP_INTERIOR | ISM_FP_CREASE;
        }
        if (!ism_triangulate_wound(s, sub, m, reach, node, max_error, flip, out))
            return false;
    }
    *done = true;
    return true;
}

/* A crease point whose distance to lo = hi = 0 (one Newton step's length) is within this
 * share of the chord sag lies on that crease: Newton leaves it there to rounding, while a
 * crease point of another crease (the cube's next edge, a cut polygon's chord across a face
 * from one edge to the next) lies a part of a cell away. */
#define ON_CREASE_SHARE 1e-3

/* Does x lie on the crease of labels l[0] < l[1] (pieces mode), to within ON_CREASE_SHARE ×
 * sag? */
static bool on_crease(ism_sampler *s, const double x[3], const label_t l[2], double sag)
{
    double step[3];
    return newton_delta(s, true, x, 2, l, step) && ism_norm3(step) <= ON_CREASE_SHARE * sag;
}

/* Does the middle of chord a-c between two crease points lie farther than sag from the
 * crease of labels l[0] < l[1] (Newton from it)? In pieces mode only where a and c both lie
 * on that crease (on_crease): else they are crease points of two creases, a chord across
 * one piece. */
static bool chord_far(ism_sampler *s, bool pm, const double *a, const double *c,
                      const label_t l[2], double sag)
{
    if (pm && (!on_crease(s, a, l, sag) || !on_crease(s, c, l, sag)))
        return false;
    double x[3];
    return chord_strays(chord_foot(s, pm, a, c, l, x), sag);
}

/* The chords one leaf's triangles asked chord_far about, while they are tested: the chord
 * between a cut's two crease points is the edge the triangles each side of it share, so both
 * ask (gyroid-ball E = 0.0109 at depth 10: 2,303 chords' Newton, 17.0M of 822.6M
 * instructions, half of them repeats). A leaf cuts a few polygons: this many recent chords. */
#define CHORD_MEMO 8

typedef struct chord_memo {
    struct {
        ism_edge_key k; /* the chord's ends (the two sides' triangles hold them as vertices
                           of their own: each side's gradients) and its crease's labels */
        bool far;       /* chord_far's answer: a pure function of k within the leaf */
    } e[CHORD_MEMO];
    unsigned n; /* chords asked (the newest in e[(n - 1) % CHORD_MEMO]) */
} chord_memo;

/* chord_far for the chord va-vc, through memo. */
static bool chord_far_memo(ism_sampler *s, bool pm, const double *va, const double *vc,
                           const label_t l[2], double sag, chord_memo *memo)
{
    ism_edge_key k;
    ism_edge_key_set(&k, va, vc, l[0], l[1]);
    for (unsigned i = 0; i < memo->n && i < CHORD_MEMO; i++)
        if (ism_edge_key_same(&memo->e[i].k, &k))
            return memo->e[i].far;
    bool far = chord_far(s, pm, va, vc, l, sag);
    unsigned slot = memo->n++ % CHORD_MEMO;
    memo->e[slot].k = k;
    memo->e[slot].far = far;
    return far;
}

/* Does the crease pass between triangle v's corners unseen: an edge whose two ends lie off
 * the crease on one branch with its midpoint on the other, or three such corners with the
 * centroid on the other; or an edge between two crease points whose middle lies farther than
 * sag from the crease (Newton from it; in pieces mode on the pieces of the third corner and
 * of its mirror image across the edge)? */
static bool unseen_crease(ism_sampler *s, bool pm, const ism_cell_out *out, const uint32_t *v,
                          double sag, label_t *labels, uint32_t first, chord_memo *chords)
{
    const double *p[3];
    label_t b[3];
    for (int k = 0; k < 3; k++) {
        p[k] = out->verts[v[k]].p;
        b[k] = vertex_label(s, pm, out, labels, first, v[k]);
    }
    double m[3];
    for (int e = 0; e < 3; e++) {
        const double *a = p[e], *c = p[(e + 1) % 3];
        for (int k = 0; k < 3; k++)
            m[k] = (a[k] + c[k]) / 2;
        if (b[e] == LABEL_ANY && b[(e + 1) % 3] == LABEL_ANY) { /* a chord of the crease */
            label_t l[2] = {0, 1}, third = b[(e + 2) % 3];
            if (pm) {
                double mirror[3];
                for (int k = 0; k < 3; k++)
                    mirror[k] = 2 * m[k] - p[(e + 2) % 3][k];
                label_t other = label_at(s, pm, mirror);
                if (third == LABEL_ANY || other == third)
                    continue;
                l[0] = third, l[1] = other;
                order_labels(l, 2);
            }
            if (chord_far_memo(s, pm, a, c, l, sag, chords))
                return true;
        } else if (b[e] != LABEL_ANY && b[e] == b[(e + 1) % 3] && label_at(s, pm, m) != b[e])
            return true;
    }
    if (b[0] == LABEL_ANY || b[0] != b[1] || b[1] != b[2])
        return false;
    for (int k = 0; k < 3; k++)
        m[k] = (p[0][k] + p[1][k] + p[2][k]) / 3;
    return label_at(s, pm, m) != b[0];
}

bool ism_crease_unresolved(ism_sampler *s, const ism_cell_out *out, size_t first_tri,
                           double max_error, const double (*centroid_g)[3])
{
    bool pm = s->crease_pieces;
    if (first_tri == out->ntris || (!pm && !top_undecided(s->tape)) ||
        one_branch(s, out, first_tri, out->ntris))
        return false;
    uint32_t lo;
    label_t stack[LABELS_ON_STACK], *labels = leaf_labels(out, first_tri, stack, &lo);
    if (!labels)
        return false; /* out of memory: the leaf is kept as measured */
    bool unresolved = false;
    chord_memo chords = {.n = 0};
    for (size_t t = first_tri; t < out->ntris && !unresolved; t++) {
        const uint32_t *v = out->tris + 3 * t;
        if ((unresolved = unseen_crease(s, pm, out, v, CREASE_CHORD_SAG * max_error, labels,
                                        lo, &chords)))
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
