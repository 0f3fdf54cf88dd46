/* dual_crease.c — the dual mesher's crease (dual_crease.h): f = max(a, b) or min(a, b) at
 * the top of its tape, a and b smooth, the crease the curve a = b = 0 (asked for by the
 * option dual_crease; off by default).
 *
 * One vertex per leaf rounds a crease when the vertex is put on f = 0 along ∇f: the quads
 * round the crease then cut across it, a triangle about its size off the surface. Dual
 * contouring keeps sharp features by a vertex at the feature (a QEF of the edges' planes);
 * here the vertex is found on the exact curve instead:
 *
 *          branch a active  |  branch b active           a leaf whose box allows both
 *                           |                            branches (its interval has the
 *      o---------o---------o---------o                   top max as a kink) and whose
 *      |         |       / |         |                   corners change sign gets the
 *      |    A    |   C  /  |    B    |                   vertex C on a = b = 0: minimum-
 *      |    *----|----*    |    *    |                   norm Newton on (a, b) from its
 *      |         |   / \___|____/    |                   centre (then from its corners),
 *      o---------o--/------o---------o                   kept only when it lands in the
 *                  /  crease a = b = 0                   leaf's closed box and each
 *                                                        branch's corner gradients agree
 *                                                        (one sheet of each);
 * A (only a active, a's corner gradients agreeing) and B are plain leaves as before. The
 * quads round a crossed edge beside the crease join A, C, C', B: cut across the diagonal
 * whose midpoint is nearer f = 0 — C-C' runs along the crease, so the two triangles lie on a
 * and on b and the mesh folds along the crease, their chords off it by the crease's own
 * curvature. Where Newton leaves the box but every crossed edge's root is one branch's zero
 * (the switch surface a = b may cross the box away from f = 0), the leaf is that branch's
 * plain leaf. Anything else (crossings on both branches and no crease point in the box: a
 * leaf with two crease pieces, a corner of three branches, Newton running off) splits, and
 * at depth.max declines `min_max`.
 *
 * Small leaves. A leaf at most 4 E across (`small`: judged by the measurement alone, as the
 * primal path's cell_error.c judges such nodes) need not have its branches' corner
 * gradients agree nor its same-sign edges free of roots (the wedge pokes through edges
 * beside the crease at every level), but its faces must each hold one crossing curve; with
 * no crease point in its box it takes the one nearest its centre when that lies within half
 * its size of the box (a ridge passing just outside a cell meets it in two pieces joined
 * outside it: the lens off the lattice at depth 9, 0.1 cell outside, at every level). A
 * small leaf whose corners share a sign and which is not shown empty gets a vertex too (on
 * the crease when one is in or near it, else on f = 0 along ∇f): the ridge's tip pokes into
 * cells without reaching a corner, and a sheet crossing a finer neighbour's edge on its face
 * makes a quad that needs its vertex (called empty unproven, Barth's sextic had holes
 * there); where no crossed edge asks for it, the vertex is not used. What the measurement
 * cannot see — a mesh edge in more than two triangles, a vertex joining two fans (two crease
 * pieces meeting in one small leaf) — splits the leaves there (ism_dual_mark_not_manifold,
 * dual_measure.c; at depth.max: `min_max`). A node whose corners share a sign is empty when
 * one branch's own enclosure (the top max forced to that branch: ism_eval_interval_grad's
 * force), or both on its halves, keep it from 0 as f's max/min needs. Two leaves that found
 * one crease point share its vertex (dual.c weld_crease).
 *
 * The ridge along a face's diagonal. Where the wedge of a max (the solid between the two
 * sheets beside the crease) runs along a face diagonal, the face is crossed four times, two
 * crossings on each branch, at every level alike (Barth's sextic in its own box at 3e-3, and
 * at 1e-3). A small leaf at depth.max whose crossed edges each belong to one branch
 * (ism_dual_edge_branch: the branch changing sign along the edge whose secant root lets it be
 * active) with at most two of a branch on any face is then meshed rather than declined: with
 * a crease point, its one vertex on the crease; without, when each branch has a piece (three
 * crossed edges or more), a pair leaf with a vertex per branch (ism_dual_pair_vertex), the
 * quads round an edge taking the vertex of that edge's branch (dual_walk.c edge_quad) — so the
 * mesh edge from the crease vertex across the four-crossed face is in two quads per branch,
 * not four. Only at depth.max: where the split would decline, so no mesh made before
 * changes. A small leaf at depth.max with plain faces whose crease point Newton missed is a
 * plain leaf. The measurement judges all of them (a miss at depth.max declines).
 *
 * Measuring: |f| / |∇f| is a distance to first order only where the foot along ∇f stays on
 * the active branch's side. Near the switch surface a = b (its first-order distance at most
 * twice f = 0's) the distance is taken as the least of |p − x| + |f(x)| / |∇f(x)| over three
 * feet x: Newton along a onto a = 0, along b onto b = 0, and onto the crease — every x a
 * point from which f = 0 is that near, so each is an upper bound to first order at x (the
 * foot on a branch that is not active there counts what is left to f = 0). Triangles face
 * along ∇f of the branch active at their centroid (dual_balls.c's test), or — when the
 * switch surface passes within the triangle's longest side of its centroid — along either
 * branch's gradient: thin triangles between crease vertices face anywhere between the two
 * normals (Barth's clipped sextic at 1e-2 off the lattice: such triangles split to
 * depth.max).
 *
 * Measured (callgrind, whole ism_mesh_surface, one thread; tests/unit/core/
 * test_dual_crease.c): cut ball, lens: dual in three boxes at 1e-2 and 3e-3, closed-form
 * distances within E. Barth's clipped sextic (30 nodes in the ball, fanned by
 * dual_balls.c) in its own box ±1.6 at 1e-2 / 3e-3 / 1e-3: dual, 56,924 / 78,100 / 160,968
 * triangles against the primal path's 66,064 / 142,560 / 292,752, χ, pieces and nodes the
 * same, in 3.94G / 5.38G / 9.62G instructions against 2.91G / 4.98G / 9.70G; in the box
 * shifted by 1e-3 dual at 1e-2 only, in the irrational box declined at all three (two crease
 * leaves sharing a face crossed four times: non-manifold at depth.max), and a failed try
 * costs up to 75% of the primal path's CPU on top: hence the option, still off. */
#include "core/octree/dual_crease.h"
#include "core/octree/sample_dist.h"
#include "core/analysis/unionfind.h" /* its find (path halving) on this file's own joins */
#include "core/octree/corners.h"
#include "core/octree/crease_split.h"
#include "core/octree/edge_keys.h"
#include "core/util/sort_u64.h"
#include "core/util/vec3.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

/* Newton steps onto one branch's zero set in a distance measurement; what is left after
 * them is counted (|f| / |∇f| at the foot), so fewer steps only lengthen the bound. */
#define FOOT_STEPS 8
/* ... stopping once a step is below this share of the bound: the residual then adds at most
 * a thousandth of E to the distance. */
#define FOOT_STOP 1e-3
/* A point whose first-order distance to the switch surface a = b exceeds this many times its
 * first-order distance to f = 0 is measured by |f| / |∇f|: its foot along the active branch
 * stays on that branch's side (2: the first-order estimates may each be off by their
 * curvature terms, a factor 2 covers cells where those are below the distances). */
#define SWITCH_MARGIN 2.0

/* A pair leaf's vertex moves onto its branch's zero until a step is below this share of the
 * leaf (dual.c's NEWTON_STOP for plain vertices). */
#define PAIR_STOP 1e-9

/* Halvings of a node whose corners share a sign, when neither branch alone keeps f from 0
 * over it (halves_sign): one (8 boxes of half its size, each two interval evaluations). */
#define EMPTY_HALVINGS 1
/* Newton from a start may reach a crease point just outside the node where the crease
 * clips it: it starts again this many times from that point pulled into the box. */
#define VERTEX_RETRIES 1
/* A small leaf's crease point may lie this share of its size outside its box on each side
 * (ism_dual_crease_near): the ridge passing beside the cell (the lens's 0.1 cell), kept on
 * the crease itself (pulled into the box it left the crease: the mesh's crease vertices
 * then broke their band); its triangles are measured as any. */
#define NEAR_SHARE 0.5
/* The corners are tried as Newton's starts only when the centre's crease point lies within
 * this share of the box's size outside it (a crease farther from the centre misses the box;
 * barth's clipped sextic at 1e-2: the nine starts for every kinked node were 2.0G of the
 * run's 6.7G instructions). A quarter: in its own box at 1e-2 / 3e-3 / 1e-3 and the +1e-3
 * box at 1e-2 the meshes are those of a whole box's share (1.0) bit for bit, 3e-3 6.02G ->
 * 5.37G instructions; with 0 they differ (78,100 -> 78,724 triangles at 3e-3). */
#define CORNER_REACH 0.25

static inline double min_of(double x, double y) { return y < x || x != x ? y : x; }
static inline double max_of(double x, double y) { return y > x || x != x ? y : x; }

int ism_dual_mean_value_sign(const double f[8], const ism_ivgrad *g, const double lo[3],
                             const double hi[3])
{
    /* the least and the most f may gain along axis k from a corner on side `far` of it
     * (1: the upper side), toward the other side: two numbers per axis and side, shared by
     * the four corners there (taken per corner, they were most of the cost) */
    double gain_lo[3][2], gain_hi[3][2];
    _Pragma("GCC unroll 3") for (int k = 0; k < 3; k++)
        _Pragma("GCC unroll 2") for (int far = 0; far < 2; far++) {
            double h = hi[k] - lo[k], s = far ? -h : h;
            double p = g->d[k].lo * s, q = g->d[k].hi * s;
            gain_lo[k][far] = min_of(0, min_of(p, q));
            gain_hi[k][far] = max_of(0, max_of(p, q));
        }
    /* f's least bound from some corner above 0 (the 8 bounds intersected: their largest
     * low above 0), or its most from some corner below 0; a NaN bound shows nothing (its
     * comparisons are false) */
    bool above = false, below = false, touch = false;
    /* unrolled (every index a constant): 620 instructions a call rolled on the torus */
    _Pragma("GCC unroll 8") for (int c = 0; c < 8; c++) {
        double a = f[c], b = f[c];
        _Pragma("GCC unroll 3") for (int k = 0; k < 3; k++) {
            a += gain_lo[k][(c >> k) & 1];
            b += gain_hi[k][(c >> k) & 1];
        }
        touch |= f[c] == 0 && a == 0; /* f >= 0 from a zero corner: only zeros added */
        above |= a > 0;
        below |= b < 0;
    }
    return above || touch ? 1 : below ? -1 : 0;
}

/* Is f's top instruction a max (else a min)? */
static bool top_is_max(const ism_tape *t)
{
    static const double rising[2] = {0, 1};
    return ism_top_active_branch(t, rising) == 1;
}

/* Branch k's enclosure over box lo..hi (the top min/max forced to it) into *g; false when
 * the workspace does not fit. force: the caller's tape-length buffer, zero but for its last
 * entry, which this sets. */
static bool branch_enclosure(ism_sampler *s, ism_ivjet_ws *jet, uint8_t *force,
                             const double lo[3], const double hi[3], int k, ism_ivgrad *g)
{
    force[ism_tape_length(s->tape) - 1] = k ? ISM_BRANCH_B : ISM_BRANCH_A;
    ism_interval box[3];
    for (int a = 0; a < 3; a++)
        box[a] = (ism_interval){lo[a], hi[a]};
    s->n_interval++;
    return ism_eval_interval_grad(s->tape, jet, box, force, NULL, g) != (size_t)-1;
}

/* f's sign over the box from its branches' signs sa, sb (1, -1; 0: not shown): max(a, b) > 0
 * when either is, < 0 when both are; min the other way round. */
static int combined(const ism_tape *t, int sa, int sb)
{
    int up = top_is_max(t) ? 1 : -1;
    return sa == up || sb == up ? up : sa == -up && sb == -up ? -up : 0;
}

/* f's sign over lo..hi by its branches' enclosures (0: not shown). */
static int enclosure_sign(ism_sampler *s, ism_ivjet_ws *jet, uint8_t *force,
                          const double lo[3], const double hi[3])
{
    int sg[2];
    for (int k = 0; k < 2; k++) {
        ism_ivgrad g;
        if (!branch_enclosure(s, jet, force, lo, hi, k, &g))
            return 0;
        sg[k] = g.v.lo > 0 ? 1 : g.v.hi < 0 ? -1 : 0;
    }
    return combined(s->tape, sg[0], sg[1]);
}

/* f's sign over lo..hi by its 8 halves' enclosures, a half not shown by its own 8 halves'
 * (levels deep in all): near the crease f may keep a sign that neither branch keeps alone
 * over the whole box (outside the wedge of a max, a > 0 on one side and b > 0 on the
 * other). The box's own enclosures are the caller's (branch_sign). 0: not shown. */
static int halves_sign(ism_sampler *s, ism_ivjet_ws *jet, uint8_t *force, const double lo[3],
                       const double hi[3], int levels)
{
    int sign = 0;
    for (int c = 0; c < 8; c++) {
        double l[3], h[3];
        for (int a = 0; a < 3; a++) {
            double mid = 0.5 * lo[a] + 0.5 * hi[a];
            l[a] = (c >> a & 1) ? mid : lo[a];
            h[a] = (c >> a & 1) ? hi[a] : mid;
        }
        int here = enclosure_sign(s, jet, force, l, h);
        if (!here && levels > 1)
            here = halves_sign(s, jet, force, l, h, levels - 1);
        if (!here || (c && here != sign))
            return 0;
        sign = here;
    }
    return sign;
}

/* The sign branch k keeps over the box (1, -1; 0: not shown): its own enclosure, then the
 * mean-value form from its corner values bv[c][k]. */
static int branch_sign(ism_sampler *s, ism_ivjet_ws *jet, uint8_t *force, const double lo[3],
                       const double hi[3], const double bv[8][2], int k)
{
    ism_ivgrad g;
    if (!branch_enclosure(s, jet, force, lo, hi, k, &g))
        return 0;
    if (g.v.lo > 0 || g.v.hi < 0)
        return g.v.lo > 0 ? 1 : -1;
    double f[8];
    for (int c = 0; c < 8; c++)
        f[c] = bv[c][k];
    return ism_dual_mean_value_sign(f, &g, lo, hi);
}

/* Branch k's unit corner gradients pairwise within acos(cos_min). */
static bool branch_agrees(const double bg[8][2][3], int k, double cos_min)
{
    double n[8][3];
    for (int c = 0; c < 8; c++) {
        memcpy(n[c], bg[c][k], sizeof n[c]);
        double l = ism_norm3(n[c]);
        if (!(l > 0) || !isfinite(l))
            return false;
        for (int a = 0; a < 3; a++)
            n[c][a] /= l;
    }
    for (int i = 0; i < 8; i++)
        for (int j = i + 1; j < 8; j++)
            if (!(ism_dot3(n[i], n[j]) >= cos_min))
                return false;
    return true;
}

/* The branch whose zero is f's on every crossed edge of the node (corners p, f and the
 * branches' values bv there), or -1 when they differ or one edge cannot tell: on each edge
 * the branches changing sign along it have their secant roots x; the root is branch k's
 * when the other branch at x lets k be active with k = 0 (max: the other <= 0, min: >= 0),
 * for exactly one k. With no crease point in the box, the sheet the crossings see is then
 * that branch's alone (the switch surface a = b may still cross the box away from f = 0,
 * so the corners' own branches differ: splitting for them went on to depth.max; and f's
 * secant root may fall where the other branch is active, which f's kink bends it into). */
static int crossings_branch(ism_sampler *s, const double (*p)[3], const double f[8],
                            const double bv[8][2])
{
    int k = -1;
    for (int c0 = 0; c0 < 8; c0++)
        for (int a = 0; a < 3; a++) {
            int c1 = c0 | 1 << a;
            if (c1 == c0 || (f[c0] < 0) == (f[c1] < 0))
                continue;
            int here = ism_dual_edge_branch(s, p[c0], p[c1], bv[c0], bv[c1]);
            if (here < 0 || (k >= 0 && here != k))
                return -1;
            k = here;
        }
    return k;
}

int ism_dual_edge_branch(ism_sampler *s, const double p0[3], const double p1[3],
                         const double bv0[2], const double bv1[2])
{
    bool is_max = top_is_max(s->tape);
    int here = -1;
    for (int b = 0; b < 2; b++) {
        if ((bv0[b] < 0) == (bv1[b] < 0))
            continue;
        double t = bv0[b] / (bv0[b] - bv1[b]), x[3], v[2];
        for (int q = 0; q < 3; q++)
            x[q] = p0[q] + t * (p1[q] - p0[q]);
        s->n_point++;
        if (!ism_eval_top_values(s->tape, s->ws, x[0], x[1], x[2], v))
            return -1;
        if (!(is_max ? v[1 - b] <= 0 : v[1 - b] >= 0))
            continue;
        if (here >= 0)
            return -1; /* both: the crease beside this edge */
        here = b;
    }
    return here;
}

/* ism_dual_crease_branch_faces with the branches' values at the corners given (bv). */
static int branch_faces_bv(ism_sampler *s, const double (*p)[3], const double f[8],
                           const double (*bv)[2])
{
    int per[6][2] = {{0}}, total[2] = {0, 0};
    for (int e = 0; e < 12; e++) {
        int c0, c1, face[2];
        ism_cube_edge(e, &c0, &c1, face);
        if ((f[c0] < 0) == (f[c1] < 0))
            continue;
        int k = ism_dual_edge_branch(s, p[c0], p[c1], bv[c0], bv[c1]);
        if (k < 0)
            return -1;
        total[k]++;
        if (++per[face[0]][k] > 2 || ++per[face[1]][k] > 2)
            return -1;
    }
    /* a piece of one branch alone is a curve round a corner or more (3 edges at least) */
    return total[0] >= 3 && total[1] >= 3 ? 2 : 1;
}

int ism_dual_crease_branch_faces(ism_sampler *s, const double (*p)[3], const double f[8])
{
    double bv[8][2];
    for (int c = 0; c < 8; c++) {
        s->n_point++;
        if (!ism_eval_top_values(s->tape, s->ws, p[c][0], p[c][1], p[c][2], bv[c]))
            return -1;
    }
    return branch_faces_bv(s, p, f, (const double (*)[2])bv);
}

/* Is x within `share` of the box's size of the box along every axis? (NaN: no.) */
static bool within_share(const double x[3], const double lo[3], const double hi[3],
                         double share)
{
    bool near = true;
    for (int a = 0; a < 3; a++) {
        double grow = share * (hi[a] - lo[a]);
        near &= x[a] >= lo[a] - grow && x[a] <= hi[a] + grow;
    }
    return near;
}

/* Newton onto the crease from x, and again from its result pulled into the box
 * (VERTEX_RETRIES times); true when it lands in the closed box. NaN fails the comparisons
 * (not inside). Else x is where the first Newton left it (NaN when it failed). */
static bool crease_from(ism_sampler *s, const double lo[3], const double hi[3], double x[3])
{
    double first[3] = {NAN, NAN, NAN};
    for (int tries = 0; tries <= VERTEX_RETRIES; tries++) {
        if (!ism_crease_newton(s, x))
            break;
        if (!tries)
            memcpy(first, x, sizeof first);
        bool inside = true;
        for (int a = 0; a < 3; a++) {
            inside &= x[a] >= lo[a] && x[a] <= hi[a];
            x[a] = x[a] < lo[a] ? lo[a] : x[a] > hi[a] ? hi[a] : x[a];
        }
        if (inside)
            return true;
    }
    memcpy(x, first, sizeof first);
    return false;
}

/* From the centre, then from each corner in order (a crease clipping a corner of the box
 * is nearest to points outside it from the centre): a function of the box alone. */
bool ism_dual_crease_vertex(ism_sampler *s, const double lo[3], const double hi[3],
                            double x[3])
{
    for (int start = -1; start < 8; start++) {
        for (int a = 0; a < 3; a++)
            x[a] = start < 0 ? 0.5 * lo[a] + 0.5 * hi[a] : (start >> a & 1) ? hi[a] : lo[a];
        if (crease_from(s, lo, hi, x))
            return true;
        if (start < 0 && !within_share(x, lo, hi, CORNER_REACH))
            return false; /* the crease nearest the centre is far: none in the box */
    }
    return false;
}

bool ism_dual_crease_near(ism_sampler *s, const double lo[3], const double hi[3], double x[3])
{
    for (int a = 0; a < 3; a++)
        x[a] = 0.5 * lo[a] + 0.5 * hi[a];
    if (!ism_crease_newton(s, x))
        return false;
    return within_share(x, lo, hi, NEAR_SHARE);
}

enum ism_crease_node ism_dual_crease_node(ism_sampler *s, ism_ivjet_ws *jet, uint8_t *force,
                                          const double (*p)[3], const double f[8],
                                          double cos_min, bool small, bool last)
{
    const ism_tape *t = s->tape;
    double vertex[3]; /* the crease point, found again by the caller (place_vertex) */
    int neg = 0;
    for (int c = 0; c < 8; c++)
        neg += f[c] < 0;
    double bv[8][2], bg[8][2][3];
    if (neg == 0 || neg == 8) {
        for (int c = 0; c < 8; c++) {
            s->n_point++;
            if (!ism_eval_top_values(t, s->ws, p[c][0], p[c][1], p[c][2], bv[c]))
                return ISM_CREASE_SPLIT;
        }
        int sa = branch_sign(s, jet, force, p[0], p[7], (const double (*)[2])bv, 0);
        int sb = branch_sign(s, jet, force, p[0], p[7], (const double (*)[2])bv, 1);
        if (combined(t, sa, sb) || halves_sign(s, jet, force, p[0], p[7], EMPTY_HALVINGS) != 0)
            return ISM_CREASE_EMPTY;
        if (!small)
            return ISM_CREASE_SPLIT;
        /* not shown empty: f = 0 may be in it (the ridge's tip; a sheet crossing a finer
           neighbour's edge on its face, whose quad needs this leaf's vertex) */
        return ism_dual_crease_vertex(s, p[0], p[7], vertex) ||
                       ism_dual_crease_near(s, p[0], p[7], vertex)
                   ? ISM_CREASE_VERTEX
                   : ISM_CREASE_SMOOTH;
    }
    for (int c = 0; c < 8; c++) {
        s->n_gradient++;
        if (!ism_eval_top_branches(t, s->ws, p[c][0], p[c][1], p[c][2], bv[c], bg[c]))
            return ISM_CREASE_SPLIT;
    }
    bool one_a = small || branch_agrees((const double (*)[2][3])bg, 0, cos_min);
    bool one_b = small || branch_agrees((const double (*)[2][3])bg, 1, cos_min);
    if (ism_dual_crease_vertex(s, p[0], p[7], vertex))
        return one_a && one_b ? ISM_CREASE_VERTEX : ISM_CREASE_SPLIT;
    int k = crossings_branch(s, p, f, (const double (*)[2])bv);
    if (k >= 0 && (k ? one_b : one_a))
        return ISM_CREASE_SMOOTH;
    if (small && ism_dual_crease_near(s, p[0], p[7], vertex))
        return ISM_CREASE_VERTEX;
    return small && last && branch_faces_bv(s, p, f, (const double (*)[2])bv) == 2
               ? ISM_CREASE_PAIR
               : ISM_CREASE_SPLIT;
}

void ism_dual_pair_vertex(ism_sampler *s, const double (*p)[3], const double f[8], int k,
                          double x[3])
{
    double bv[8][2], sum[3] = {0, 0, 0}, size = p[7][0] - p[0][0];
    int roots = 0;
    for (int c = 0; c < 8; c++) {
        s->n_point++;
        ism_eval_top_values(s->tape, s->ws, p[c][0], p[c][1], p[c][2], bv[c]);
    }
    for (int e = 0; e < 12; e++) {
        int c0, c1, face[2];
        ism_cube_edge(e, &c0, &c1, face);
        if ((f[c0] < 0) == (f[c1] < 0) ||
            ism_dual_edge_branch(s, p[c0], p[c1], bv[c0], bv[c1]) != k)
            continue;
        double t = bv[c0][k] / (bv[c0][k] - bv[c1][k]); /* branch k's secant root */
        for (int a = 0; a < 3; a++)
            sum[a] += p[c0][a] + t * (p[c1][a] - p[c0][a]);
        roots++;
    }
    for (int a = 0; a < 3; a++)
        x[a] = roots ? sum[a] / roots : 0.5 * p[0][a] + 0.5 * p[7][a];
    for (int it = 0; it < FOOT_STEPS; it++) { /* onto k = 0 along ∇k */
        double v[2], g[2][3];
        s->n_gradient++;
        ism_eval_top_branches(s->tape, s->ws, x[0], x[1], x[2], v, g);
        double gg = ism_dot3(g[k], g[k]);
        if (!isfinite(v[k]) || !(gg > 0) || !isfinite(gg))
            break;
        for (int a = 0; a < 3; a++)
            x[a] -= v[k] * g[k][a] / gg;
        if (fabs(v[k]) / sqrt(gg) < PAIR_STOP * size)
            break;
    }
}

/* |p − x| + |f(x)| / |∇f(x)| for x: Newton from p along branch k onto k = 0 (INFINITY when a
 * step cannot be made). */
static double branch_foot(ism_sampler *s, const double p[3], int k, double e)
{
    double x[3], v[2], g[2][3];
    memcpy(x, p, sizeof x);
    for (int it = 0; it < FOOT_STEPS; it++) {
        s->n_gradient++;
        ism_eval_top_branches(s->tape, s->ws, x[0], x[1], x[2], v, g);
        double gg = ism_dot3(g[k], g[k]);
        if (!isfinite(v[k]) || !(gg > 0) || !isfinite(gg))
            return INFINITY;
        for (int a = 0; a < 3; a++)
            x[a] -= v[k] * g[k][a] / gg;
        if (fabs(v[k]) / sqrt(gg) < FOOT_STOP * e)
            break;
    }
    return ism_dist3(p, x) + ism_sample_dist(s, x);
}

/* The top branches' values and gradients at p into v, g, and whether the switch surface
 * a = b lies within reach of p to first order (|a − b| <= reach |∇a − ∇b|; NaN counts as
 * near: the careful path). False when the tape does not end in min/max. */
static bool switch_near(ism_sampler *s, const double p[3], double reach, double v[2],
                        double g[2][3])
{
    static const double any[2] = {0, 0};
    if (ism_top_active_branch(s->tape, any) < 0)
        return false;
    double gd[3];
    s->n_gradient++;
    ism_eval_top_branches(s->tape, s->ws, p[0], p[1], p[2], v, g);
    for (int a = 0; a < 3; a++)
        gd[a] = g[0][a] - g[1][a];
    return !(fabs(v[0] - v[1]) > reach * ism_norm3(gd));
}

double ism_dual_kink_dist_near(ism_sampler *s, const double p[3], double plain, double e)
{
    double v[2], g[2][3], x[3];
    if (!switch_near(s, p, SWITCH_MARGIN * plain, v, g))
        return plain;
    double best = min_of(branch_foot(s, p, 0, e), branch_foot(s, p, 1, e));
    memcpy(x, p, sizeof x);
    if (ism_crease_newton(s, x))
        best = min_of(best, ism_dist3(p, x) + ism_sample_dist(s, x));
    return best;
}

bool ism_dual_kink_faces(ism_sampler *s, const double c[3], const double nrm[3], double reach,
                         double cos_min)
{
    double v[2], g[2][3];
    if (!switch_near(s, c, reach, v, g))
        return false;
    double nl = ism_norm3(nrm);
    for (int k = 0; k < 2; k++)
        if (ism_dot3(nrm, g[k]) > cos_min * nl * ism_norm3(g[k]))
            return true;
    return false;
}

double ism_dual_dist(ism_sampler *s, const double p[3], double e)
{
    double g[3];
    double f = ism_sample_grad(s, p, g);
    return ism_dual_kink_dist(s, p, ism_plain_dist(s, p, f, g, e), e);
}

/* A vertex's x and its place in ids, sorted by x. */
typedef struct by_x {
    double x;
    size_t k;
} by_x;

static int cmp_x(const void *a, const void *b)
{
    const by_x *p = a, *q = b;
    return p->x < q->x ? -1 : p->x > q->x ? 1 : (p->k > q->k) - (p->k < q->k);
}


bool ism_dual_weld(const double *pos, const uint32_t *ids, size_t n, double tol,
                   uint32_t *to)
{
    by_x *o = malloc((n ? n : 1) * sizeof *o);
    uint32_t *parent = malloc((n ? n : 1) * sizeof *parent);
    if (!o || !parent) {
        free(o);
        free(parent);
        return false;
    }
    for (size_t k = 0; k < n; k++) {
        o[k] = (by_x){pos[3 * (size_t)ids[k]], k};
        parent[k] = (uint32_t)k;
    }
    if (n)
        qsort(o, n, sizeof *o, cmp_x);
    for (size_t i = 0; i < n; i++)
        for (size_t j = i + 1; j < n && o[j].x - o[i].x <= tol; j++) {
            const double *a = &pos[3 * (size_t)ids[o[i].k]], *b = &pos[3 * (size_t)ids[o[j].k]];
            if (!(fabs(a[1] - b[1]) <= tol && fabs(a[2] - b[2]) <= tol))
                continue;
            uint32_t ra = ism_an_uf_find(parent, (uint32_t)o[i].k);
            uint32_t rb = ism_an_uf_find(parent, (uint32_t)o[j].k);
            if (ra == rb)
                continue;
            /* the group's root: the entry with the least id (ties: the first) */
            bool a_first = ids[ra] < ids[rb] || (ids[ra] == ids[rb] && ra < rb);
            parent[a_first ? rb : ra] = a_first ? ra : rb;
        }
    for (size_t k = 0; k < n; k++)
        to[k] = ids[ism_an_uf_find(parent, (uint32_t)k)];
    free(o);
    free(parent);
    return true;
}



size_t ism_dual_not_manifold(const uint32_t *tri, size_t nt, size_t nv, uint32_t *bad)
{
    size_t ne = 3 * nt;
    uint64_t *key = malloc((ne ? ne : 1) * sizeof *key);
    uint32_t *up = malloc((nv ? nv : 1) * sizeof *up);
    if (!key || !up) {
        free(key);
        free(up);
        return (size_t)-1;
    }
    for (size_t t = 0; t < nt; t++)
        for (int j = 0; j < 3; j++)
            key[3 * t + j] = ism_edge_key(tri[3 * t + j], tri[3 * t + (j + 1) % 3]);
    if (ne)
        ism_sort_u64(key, ne);
    size_t n = 0;
    for (size_t i = 0, j; i < ne; i = j) {
        for (j = i + 1; j < ne && key[j] == key[i]; j++)
            ;
        if (j - i > 2) {
            bad[n++] = (uint32_t)(key[i] >> 32);
            bad[n++] = (uint32_t)key[i];
        }
    }
    /* fans: (vertex, triangle) pairs sorted by vertex; each vertex's opposite edges joined
       in a union-find over their ends (reset per vertex) must form one group */
    for (size_t t = 0; t < nt; t++)
        for (int j = 0; j < 3; j++)
            key[3 * t + j] = (uint64_t)tri[3 * t + j] << 32 | t;
    if (ne) /* (vertex, triangle) in one word: sorted as edge keys are */
        ism_sort_u64(key, ne);
    for (size_t v = 0; v < nv; v++)
        up[v] = (uint32_t)v;
    for (size_t i = 0, j; i < ne; i = j) {
        uint32_t v = (uint32_t)(key[i] >> 32);
        for (j = i; j < ne && (uint32_t)(key[j] >> 32) == v; j++) {
            const uint32_t *q = &tri[3 * (uint32_t)key[j]];
            int at = q[0] == v ? 0 : q[1] == v ? 1 : 2;
            uint32_t b = q[(at + 1) % 3], c = q[(at + 2) % 3];
            up[ism_an_uf_find(up, b)] = ism_an_uf_find(up, c);
        }
        uint32_t first = UINT32_MAX;
        bool one = true;
        for (size_t k = i; k < j; k++) {
            const uint32_t *q = &tri[3 * (uint32_t)key[k]];
            int at = q[0] == v ? 0 : q[1] == v ? 1 : 2;
            uint32_t g = ism_an_uf_find(up, q[(at + 1) % 3]);
            first = first == UINT32_MAX ? g : first;
            one = one && g == first;
        }
        if (!one)
            bad[n++] = v;
        for (size_t k = i; k < j; k++) { /* reset the link's ends for the next vertex */
            const uint32_t *q = &tri[3 * (uint32_t)key[k]];
            for (int a = 0; a < 3; a++)
                up[q[a]] = q[a];
        }
    }
    free(key);
    free(up);
    return n;
}
