/* rm_crease_slide.c — vertices beside a min/max crease moved onto it and along it. Where f's
 * top is min(a, b) or max(a, b) (a CSG union or intersection) the surface has a crease on
 * the curve a = b = 0. Without a bound the polygoniser puts no vertex on that curve: its
 * vertices there are edge roots, each on one branch's surface and up to a fraction of a cell
 * off the other's (the gyroid ball: about 1/8 of a cell), a chamfer of thin triangles spaced
 * as the cells cut it (1/400 of a cell to a cell apart); the pass locks most of them as a
 * crease (rm_locks.c), and every triangle between two near ones and a far one is a needle
 * no flip mends. Here a corner v of a triangle under ISM_RM_COLLAPSE_DEG (locked or free,
 * not RM_PINNED, ∇f not vanishing, as the collapses look only there) whose
 * triangles form one closed manifold fan (no boundary, no non-manifold edge, none of the
 * caller's locked edges, one label) and which lies within ISM_RM_CREASE_NEAR_REL of its mean
 * edge of both branches' zero sets (under max_error, or within ISM_RM_CREASE_NEAR_ERRORS
 * bounds) is, the first that passes:
 *   - merged with a neighbour w closer than ISM_RM_CREASE_MERGE_REL of the mean edge and
 *     beside the crease too (the nearest first, up to ISM_RM_CREASE_MERGE_TRIES of them),
 *     the merged vertex put on the crease nearest their middle (two vertices of the two
 *     surfaces across the chamfer become one on it; the link condition keeps the
 *     topology, rm_merge.h);
 *   - snapped onto the crease, its nearest point of a = b = 0, when v is not on it yet;
 *   - slid along it, when it is on it (within ISM_RM_CREASE_ON_REL) and exactly two of its
 *     neighbours are too (a chain: a crease corner, or a crease met twice, has more): toward
 *     the middle of those two, kept between them in order; a half and a quarter step are
 *     tried after the whole one (a vertex on it with fewer than two, a chain's end, is
 *     only merged).
 * Points go onto a = b = 0 by minimum-norm Newton steps on the two branches, and a moved
 * vertex ends within ISM_RM_CREASE_ON_REL of its mean edge of both surfaces and locked (on
 * the crease: the relaxation would move it off). The branches are those of f's last
 * min/max, passed on through the one-operand steps after it (the cube's and steinmetz's
 * max(...) − 1: ism_eval_crease_branches), or the same of f shortened over the fan's box
 * (a nested min/max whose other operands the box proves dominated: three-balls, the
 * cube's edges); a fan with neither is left alone. A move is kept only when each triangle
 * stays within ISM_RM_COLLAPSE_MAX_TURN_DEG of its own normal before (across a crease the
 * fan's mean normal says nothing) and no outer edge bends past the crease angle by more
 * than ISM_RM_CROWD_BEND_DEG over what it did (rm_crease_tri_ok) — or, a chamfer triangle
 * ending on one of the two surfaces, faces within ISM_RM_CREASE_FACE_DEG of that branch's
 * normal at the crease point (or no farther from the nearer one than before) and bends by no
 * more than the crease's own angle and ISM_RM_CROWD_BEND_DEG (tri_ok) —, the smallest angle of
 * the fan (of both fans, for a merge) grows, and the distances the pass keeps are kept
 * (centroids: rm_centroids_stay for a move, the fans' farthest or the mesh's for a merge,
 * midpoints too; under max_error every centroid and edge midpoint of the fan within it,
 * rm_bound.h). */
#include "core/remesh/rm_bound.h"
#include "core/remesh/rm_cbound.h"
#include "core/remesh/rm_merge.h"
#include "core/remesh/rm_pass.h"
#include "core/util/vec3.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

/* Fans of more triangles than this are not slid (the fan walk keeps them on the stack; the
 * polygoniser's crease vertices have about 6). */
#define ISM_RM_CREASE_SLIDE_MAX_DEGREE 24
/* A vertex is beside the crease, and snapped onto it, when both branches measure within
 * this × its mean edge: the gyroid ball's locked vertices lie up to ~0.3 of an edge off the
 * other branch's surface, the cube-minus-ball's chamfer vertices (a thin strip of short
 * edges) farther; beyond an edge the nearest crease point would be another vertex's.
 * bench_remesh needles (own / 1e-3 / 0.37-cell / √2−1 boxes) with 0.5 -> 0.75 (1.0 gave the
 * same but gyroid-ball 20 in the last box): cube-minus-ball 0 / 11 / 108 / 124 -> 0 / 3 /
 * 49 / 58, gyroid-ball 19 / 20 / 24 / 19 -> 16 / 17 / 13 / 21, but the cube 0 / 0 / 0 / 0
 * -> 0 / 0 / 4 / 4 (as before session 15). */
#define ISM_RM_CREASE_NEAR_REL 0.75
/* Newton may land at most this × the mean edge from where it started (farther: it found
 * another part of the crease curve). A vertex within ISM_RM_CREASE_NEAR_REL of both surfaces
 * lies up to about that / sin(crease angle) from the crease along its own surface: the
 * cube-minus-ball's face meets its sphere at 40°, and 0.5 refused 1,635 snaps in its
 * irrational box (bench_remesh needles 373 -> 359 there with 1.0; gyroid-ball 48 / 46 / 74 /
 * 54 -> 45 / 43 / 70 / 50). */
#define ISM_RM_CREASE_PROJECT_MAX_REL 1.0
/* Under max_error the crease's cells stop at 4 bounds across (plot_test.c's
 * CREASE_CELL_ERRORS), whatever their triangles' size: the polygoniser's vertices there lie
 * up to ~2.3 bounds off the other branch's surface (gyroid-ball at its default bound: 0.012
 * at E 0.0052), on fans whose mean edge can be a tenth of that, so "beside" and "lands
 * near" also reach this many bounds: within ISM_RM_CREASE_NEAR_ERRORS × max_error of both
 * surfaces, Newton landing within ISM_RM_CREASE_REACH_ERRORS × max_error (each or its share
 * of the mean edge, the larger). bench_remesh needles under 10° (own / 1e-3 / 0.37-cell /
 * √2−1 boxes, default bound): gyroid-ball 49 / 66 / 81 / 78 -> 43 / 58 / 73 / 70,
 * cube-minus-ball 127 / 137 / 64 / 71 -> 90 / 108 / 52 / 59 (4 and 8: 41 / 58 / 73 / 68 and
 * 88 / 107 / 50 / 60; 1 and 2: 47 / 63 / 75 / 73). The distance checks under the bound
 * refused none of these vertices' moves, before or after: what still blocks is the fans'
 * shape (rm_crease_tri_ok / tri_ok, and the smallest angle not growing) and vertices on the
 * crease whose neighbours on it are not (no chain to slide along). */
#define ISM_RM_CREASE_NEAR_ERRORS 2.0
#define ISM_RM_CREASE_REACH_ERRORS 4.0

/* A vertex beside the crease is merged onto it with a neighbour closer than this × its mean
 * edge, the nearest first and at most ISM_RM_CREASE_MERGE_TRIES of them (snap_merge). Under
 * max_error the chamfer across the crease is a strip of triangles about an edge long whose
 * short sides join a vertex on one surface to one on the other, 0.25-0.5 of the mean edge
 * apart (gyroid-ball: 0.0125 against edges of 0.07, both ends 2E off the other surface); the
 * nearest neighbour alone within ISM_RM_CROWD (0.25, the crease merges' own) left them.
 * bench_remesh needles under 10° (own / 0.37-cell boxes, default bound; measured before
 * to_crease's last step): gyroid-ball 31 / 68 with the nearest within 0.25, 23 / 54 within
 * 0.6, 16 / 48 within 0.8, 16 / 49 within 1.0; with up to 3 tried in order 12 / 21 within
 * 0.8 (16 / 19 within 1.0, 21 / 46 within 0.6; 6 tried: 14 / 21); cube-minus-ball 100 / 50
 * -> 60 / 29 (the nearest within 0.8) -> 8 / 7 (3 tried). Folds (edges bending over 90°)
 * fall with them: 1,104 / 1,112 -> 791 / 815 and 2,130 / 1,947 -> 1,529 / 1,337. */
#define ISM_RM_CREASE_MERGE_REL 0.8
#define ISM_RM_CREASE_MERGE_TRIES 3

/* One vertex's fan: the triangles in order round v (tri[i] runs v, ring[i], then the next
 * ring vertex), its two neighbours on the crease when it slides, the tape, and what the
 * tape's branches measured at v. */
typedef struct crease_fan {
    uint32_t n, tri[ISM_RM_CREASE_SLIDE_MAX_DEGREE], ring[ISM_RM_CREASE_SLIDE_MAX_DEGREE];
    uint32_t end[2];   /* v's two neighbours on the crease (sliding) */
    const ism_tape *f; /* the tape whose top min/max gives the branches there */
    double val[2], gn[2]; /* the branches' values and gradient lengths at v in f */
} crease_fan;

/* How far from both surfaces a vertex of mean edge `edge` counts as beside the crease, and
 * how far from its start Newton may land (without a bound: shares of the edge alone). */
static double near_tol(const rm_pass *p, double edge)
{
    return fmax(ISM_RM_CREASE_NEAR_REL * edge, ISM_RM_CREASE_NEAR_ERRORS * p->max_error);
}

static double reach_tol(const rm_pass *p, double edge)
{
    return fmax(ISM_RM_CREASE_PROJECT_MAX_REL * edge, ISM_RM_CREASE_REACH_ERRORS * p->max_error);
}

/* The triangles of v as one closed fan of oriented manifold edges, none locked by the
 * caller, of one label: tri[i] and tri[i + 1] share the edge v ring[i + 1]. False otherwise. */
static bool walk_fan(const rm_pass *p, uint32_t v, crease_fan *c)
{
    const rm_mesh *r = &p->r;
    const uint32_t *tri = r->m->tri;
    uint32_t n = r->count[v];
    if (n < 3 || n > ISM_RM_CREASE_SLIDE_MAX_DEGREE)
        return false;
    uint32_t t = r->vt[r->start[v]];
    for (uint32_t i = 0; i < n; i++) {
        int k = rm_corner(r->m, t, v);
        uint32_t next = tri[3 * t + (k + 1) % 3], prev = tri[3 * t + (k + 2) % 3], two[2];
        int count;
        if (next == v || prev == v || !rm_edge_triangles(r, v, prev, two, &count) ||
            rm_edge_locked(r, v, prev) || rm_label(r, two[0]) != rm_label(r, two[1]))
            return false;
        c->tri[i] = t;
        c->ring[i] = next; /* tri[i] runs v -> next -> prev; tri[i + 1] runs v -> prev */
        t = two[0];        /* the triangle running v -> prev */
        if (i + 1 < n && t == c->tri[0])
            return false; /* a fan shorter than v's triangles: v joins two sheets */
    }
    c->n = n;
    return t == c->tri[0];
}

/* Both branches' values and gradients at x, in the fan's tape; false where it has none. */
static bool branches(rm_pass *p, const ism_tape *f, const double x[3], double val[2],
                     double g[2][3])
{
    return ism_eval_crease_branches(f, p->ws, x[0], x[1], x[2], val, g) && isfinite(val[0]) &&
           isfinite(val[1]);
}

/* f's two top branches, for rm_newton_two. */
typedef struct branch_pair {
    rm_pass *p;
    const ism_tape *f;
} branch_pair;

static bool branches_of(void *ctx, const double x[3], double val[2], double g[2][3])
{
    const branch_pair *c = ctx;
    return branches(c->p, c->f, x, val, g);
}

/* Both branches' values v within tol × their gradients' lengths n: on the crease. */
static bool within_both(const double v[2], const double n[2], double tol)
{
    return fabs(v[0]) <= tol * n[0] && fabs(v[1]) <= tol * n[1];
}

/* x lies within tol of both branches' zero sets (first order). val and gn, when not NULL,
 * get the branches' values and gradient lengths there (when they are finite). */
static bool on_crease(rm_pass *p, const ism_tape *f, const double x[3], double tol,
                      double *val, double *gn)
{
    double v[2], g[2][3], n[2];
    if (!branches(p, f, x, v, g))
        return false;
    for (int s = 0; s < 2; s++) {
        n[s] = ism_norm3(g[s]);
        if (val)
            val[s] = v[s], gn[s] = n[s];
    }
    return within_both(v, n, tol);
}

/* The tape for v's fan: f, or f shortened over the fan's box when f's top branches do not
 * both vanish at v (a nested min/max whose other operands the box proves dominated). NULL:
 * none. val and gn get what the returned tape's branches measure at v. */
static const ism_tape *fan_tape(rm_pass *p, uint32_t v, double tol, ism_tape *local,
                                double val[2], double gn[2])
{
    const rm_mesh *r = &p->r;
    const double *x = rm_pos(p, v);
    if (on_crease(p, p->f, x, tol, val, gn))
        return p->f;
    if (!local)
        return NULL;
    ism_interval box[3];
    for (int k = 0; k < 3; k++)
        box[k].lo = box[k].hi = x[k];
    for (uint32_t i = 0; i < r->count[v]; i++) {
        const uint32_t *t = r->m->tri + 3 * (size_t)r->vt[r->start[v] + i];
        for (int j = 0; j < 3; j++)
            for (int k = 0; k < 3; k++) {
                box[k].lo = fmin(box[k].lo, rm_pos(p, t[j])[k]);
                box[k].hi = fmax(box[k].hi, rm_pos(p, t[j])[k]);
            }
    }
    if (!ism_tape_shorten(p->f, p->ws, box[0], box[1], box[2], local, NULL))
        return NULL;
    return on_crease(p, local, x, tol, val, gn) ? local : NULL;
}

/* The corners of v's i-th fan triangle with v at x. */
static void fan_corners(const rm_pass *p, const crease_fan *c, uint32_t v, uint32_t i,
                        const double *x, const double *q[3])
{
    const uint32_t *t = p->r.m->tri + 3 * (size_t)c->tri[i];
    for (int k = 0; k < 3; k++)
        q[k] = t[k] == v ? x : rm_pos(p, t[k]);
}

/* v's fan and what it may do: 1 snap onto the crease (v near it, not on it), 2 slide along
 * it (v on it, exactly two of its neighbours on it: c->end), 3 merge only (v on it, fewer
 * than two of its neighbours on it: the end of a chain), 0 nothing (a crease corner, or
 * the crease met again: three or more neighbours on it). */
static int find_chain(rm_pass *p, uint32_t v, double mean_edge, ism_tape *local,
                      crease_fan *c)
{
    if (!(c->f = fan_tape(p, v, near_tol(p, mean_edge), local, c->val, c->gn)) ||
        !walk_fan(p, v, c))
        return 0;
    double on = ISM_RM_CREASE_ON_REL * mean_edge;
    for (int s = 0; s < 2; s++) /* on_crease at v, from what fan_tape measured */
        if (!(fabs(c->val[s]) <= on * c->gn[s]))
            return 1;
    int ends = 0;
    for (uint32_t i = 0; i < c->n; i++)
        if (on_crease(p, c->f, rm_pos(p, c->ring[i]), on, NULL, NULL)) {
            if (ends == 2)
                return 0; /* a corner, or a crease met again */
            c->end[ends++] = c->ring[i];
        }
    /* a chain's end (0 or 1 neighbours on the crease: the crease goes on across one of v's
       triangles) may still merge with a neighbour onto it: the cube minus a ball's own box,
       a vertex of 3 triangles on the crease at (-0.402, -1, -0.727) beside one 3e-3 along
       it, whose needle (7.75°) comes back 4 times by the symmetry; chamfer17 counted 78 such
       vertices on gyroid-ball's own box. bench_remesh needles (default bound, own / 1e-3 /
       0.37-cell / √2−1 boxes, with tri_ok's "no farther than before"): gyroid-ball 2 / 8 /
       19 / 27 -> 1 / 8 / 16 / 20, cube-minus-ball 9 / 12 / 6 / 13 -> 6 / 5 / 4 / 7; folds
       776 / 818 / 809 / 821 -> 733 / 785 / 770 / 774 and 1,526 / 1,472 / 1,329 / 1,381 ->
       1,404 / 1,330 / 1,261 / 1,309 */
    return ends == 2 ? 2 : 3;
}

/* The two branches' unit normals at a crease point (oriented as ∇f on each side: f is the
 * branch there), and what tri_ok compares with them: the cosines of the most a chamfer
 * triangle may bend (the crease's angle and ISM_RM_CROWD_BEND_DEG, at most 180°) and turn
 * from a branch's normal (ISM_RM_CREASE_FACE_DEG). */
typedef struct crease_frame {
    double n[2][3], cos_bend, cos_face;
} crease_frame;

/* cf from the branches' gradients g at a crease point; false where one vanishes. */
static bool frame_of(const double g[2][3], crease_frame *cf)
{
    for (int s = 0; s < 2; s++) {
        double l = ism_norm3(g[s]);
        if (!(l > 0))
            return false;
        for (int k = 0; k < 3; k++)
            cf->n[s][k] = g[s][k] / l;
    }
    double angle = acos(fmax(-1, fmin(1, ism_dot3(cf->n[0], cf->n[1]))));
    cf->cos_bend = cos(fmin(M_PI, angle + ISM_RM_CROWD_BEND_DEG * M_PI / 180));
    cf->cos_face = cos(ISM_RM_CREASE_FACE_DEG * M_PI / 180);
    return true;
}

/* Newton from x onto both branches of the fan's tape (rm_newton_two), to within
 * ISM_RM_CREASE_ON_REL × scale of both (on_crease's test, on the values the step would use:
 * no evaluation more), and one step more; false when it does not get there. On success
 * *framed says whether cf holds the crease's frame there, from the gradients the last step
 * measured (frame_of). */
static bool to_crease(rm_pass *p, const ism_tape *f, double x[3], double scale,
                      crease_frame *cf, bool *framed)
{
    branch_pair c = {p, f};
    double g[2][3];
    if (!rm_newton_two(branches_of, &c, x, ISM_RM_CREASE_ON_REL * scale, g))
        return false;
    *framed = frame_of((const double (*)[3])g, cf);
    return true;
}

/* rm_crease_tri_ok, or (cf not NULL) the triangle ends on one of the two surfaces meeting
 * at the crease: q faces within ISM_RM_CREASE_FACE_DEG of a branch's normal at the crease
 * point — or no farther from the nearer of the two than o did — and bends against the
 * triangle across its outer edge ab by no more than the crease's own angle and
 * ISM_RM_CROWD_BEND_DEG (a chamfer triangle between the two surfaces turns by up to the
 * crease angle as its corner goes onto the crease, and its neighbour across the crease
 * bends by that angle). Under a bound the chamfer holds clusters of triangles a few
 * thousandths long standing across both surfaces (walls: 80-110° off both normals, the
 * gyroid ball's own box at (-0.897, -0.422, -0.984)); the 60° alone refused every merge
 * among them, the "no farther than before" lets them go onto the crease. bench_remesh
 * needles under 10°, default bound, own / 1e-3 / 0.37-cell / √2−1 boxes: gyroid-ball
 * 13 / 11 / 20 / 29 -> 2 / 8 / 19 / 27, cube-minus-ball 9 / 12 / 8 / 14 -> 9 / 12 / 6 / 13,
 * folds (edges bent over 90°) about equal (777 / 812 / 805 / 820 -> 776 / 818 / 809 / 821).
 * Letting the bend grow by ISM_RM_CROWD_BEND_DEG over the old one's as well changed one
 * needle. */
static bool tri_ok(const rm_pass *p, const crease_frame *cf, uint32_t t, uint32_t a,
                   uint32_t b, const double *o[3], const double *q[3])
{
    if (rm_crease_tri_ok(p, t, a, b, o, q))
        return true;
    double n[3], ln = rm_cross(q[0], q[1], q[2], n);
    if (!cf || !(ln > 0))
        return false;
    double m[3], lo = rm_cross(o[0], o[1], o[2], m);
    /* or no farther from the nearer branch's normal than o was (a wall of the chamfer) */
    double was = lo > 0 ? fmax(ism_dot3(m, cf->n[0]), ism_dot3(m, cf->n[1])) / lo : -1;
    double face = fmin(cf->cos_face, was) * ln;
    if (!(ism_dot3(n, cf->n[0]) > face || ism_dot3(n, cf->n[1]) > face))
        return false;
    uint32_t s = rm_merge_across(&p->r, a, b, t);
    if (s == UINT32_MAX)
        return true;
    const uint32_t *z = p->r.m->tri + 3 * (size_t)s;
    double u[3], lu = rm_cross(rm_pos(p, z[0]), rm_pos(p, z[1]), rm_pos(p, z[2]), u);
    return lu > 0 && ism_dot3(n, u) >= cf->cos_bend * ln * lu;
}

/* The fan with v at x: every triangle and its outer edge (not v's) as tri_ok allows (cf: the
 * crease there, NULL: rm_crease_tri_ok alone), and its smallest sine over min_sine. */
static bool fan_shape_ok(rm_pass *p, uint32_t v, const crease_fan *c, const double *x,
                         const crease_frame *cf, double min_sine)
{
    const double *pos = rm_pos(p, v);
    double sine = INFINITY;
    for (uint32_t i = 0; i < c->n; i++) {
        const double *q[3], *o[3];
        fan_corners(p, c, v, i, x, q);
        /* a sine at or under min_sine fails, asked before tri_ok's bends (the dearer test) */
        double s = rm_min_sine(q[0], q[1], q[2]);
        if (s <= min_sine)
            return false;
        sine = fmin(sine, s);
        fan_corners(p, c, v, i, pos, o);
        const uint32_t *t = p->r.m->tri + 3 * (size_t)c->tri[i];
        int k = rm_corner(p->r.m, c->tri[i], v);
        if (!tri_ok(p, cf, c->tri[i], t[(k + 1) % 3], t[(k + 2) % 3], o, q))
            return false;
    }
    /* (leaving fewer triangles under ISM_RM_COLLAPSE_DEG instead, as the merges may, made
       caps of 6.8° beside the cube-minus-ball's crease in its own box: 0 needles -> 18) */
    return sine > min_sine;
}

/* The corners of triangle t with v and w read at x (new) or where they are (old). */
static void merge_corners(const rm_pass *p, const rm_merge *g, uint32_t t, const double *x,
                          const double *o[3], const double *q[3])
{
    const uint32_t *c = p->r.m->tri + 3 * (size_t)t;
    for (int k = 0; k < 3; k++) {
        o[k] = rm_pos(p, c[k]);
        q[k] = c[k] == g->v || c[k] == g->w ? x : o[k];
    }
}

/* The farthest from f = 0 of the centroids of g's two fans and of the midpoints of the
 * edges at v and w, before the merge (after: the merged fan with w at x, t1 and t2 gone). */
static void merge_distances(rm_pass *p, const rm_merge *g, const double *x, bool after,
                            double *cen, double *mid)
{
    const rm_mesh *r = &p->r;
    uint32_t ends[2] = {g->v, g->w};
    *cen = *mid = 0;
    for (int e = 0; e < 2; e++)
        for (uint32_t i = 0; i < r->count[ends[e]]; i++) {
            uint32_t t = r->vt[r->start[ends[e]] + i];
            if (after && (t == g->t1 || t == g->t2))
                continue;
            const double *o[3], *q[3], *const *use = after ? q : o;
            merge_corners(p, g, t, x, o, q);
            int at = rm_corner(r->m, t, ends[e]);
            *cen = fmax(*cen, rm_centroid_distance(p, use[0], use[1], use[2]));
            *mid = fmax(*mid, rm_midpoint_distance(p, use[at], use[(at + 1) % 3]));
        }
}

/* The merged fan of g (v into w, w then at x) against the two fans before: every new
 * triangle and its outer edge as tri_ok allows, its centroid and the midpoints of
 * the edges at x within what the pass keeps, and the smallest angle grown over both fans' —
 * or, as for merges along a crease (rm_collapse.c), fewer triangles under
 * ISM_RM_COLLAPSE_DEG and no sine below ISM_RM_CROWD_SINE_FLOOR of the smallest before
 * (needles along a crease come in strips: bench_remesh gyroid-ball 54 / 51 / 86 -> 48 / 46
 * / 73 needles, the same smallest angle). */
static bool merged_fan_ok(rm_pass *p, const rm_merge *g, const double *x,
                          const crease_frame *cf)
{
    const rm_mesh *r = &p->r;
    double old_sine = INFINITY, new_sine = INFINITY, poor = rm_collapse_poor();
    int poor_before = 0, poor_after = 0; /* t1 and t2 counted once, from v's fan */
    uint32_t ends[2] = {g->v, g->w};
    /* the fans before from the sines the pass keeps (rm_tri_sine: rm_min_sine's bits) */
    for (int e = 0; e < 2; e++)
        for (uint32_t i = 0; i < r->count[ends[e]]; i++) {
            uint32_t t = r->vt[r->start[ends[e]] + i];
            double so = rm_tri_sine(p, t);
            old_sine = fmin(old_sine, so);
            poor_before += (e == 0 || rm_corner(r->m, t, g->v) < 0) && so < poor;
        }
    /* a new sine at or under half the old smallest fails both rules below */
    double least = ISM_RM_CROWD_SINE_FLOOR * old_sine;
    for (int e = 0; e < 2; e++) /* shapes first: the distances cost 20 times as much */
        for (uint32_t i = 0; i < r->count[ends[e]]; i++) {
            uint32_t t = r->vt[r->start[ends[e]] + i];
            if (t == g->t1 || t == g->t2)
                continue;
            const double *o[3], *q[3];
            merge_corners(p, g, t, x, o, q);
            double sn = rm_min_sine(q[0], q[1], q[2]);
            if (sn <= least)
                return false;
            /* t's outer edge (not at ends[e]) has neither v nor w: only t1 and t2 have both */
            const uint32_t *c = r->m->tri + 3 * (size_t)t;
            int at = rm_corner(r->m, t, ends[e]);
            if (!tri_ok(p, cf, t, c[(at + 1) % 3], c[(at + 2) % 3], o, q))
                return false;
            new_sine = fmin(new_sine, sn);
            poor_after += (e == 0 || rm_corner(r->m, t, g->v) < 0) && sn < poor;
        }
    bool fewer = poor_after < poor_before && new_sine > ISM_RM_CROWD_SINE_FLOOR * old_sine;
    if (!(new_sine > old_sine || fewer))
        return false;
    double new_cen, new_mid, old_cen, old_mid;
    merge_distances(p, g, x, true, &new_cen, &new_mid);
    if (p->bounded)
        return new_cen <= p->max_error && new_mid <= p->max_error;
    if (new_cen <= p->centroid_bound && new_mid <= p->midpoint_low)
        return true; /* within the mesh's before: the fans' own need not be asked */
    merge_distances(p, g, x, false, &old_cen, &old_mid);
    return (new_cen <= p->centroid_bound || new_cen <= old_cen) &&
           (new_mid <= p->midpoint_low || new_mid <= old_mid);
}

/* v merged into its neighbour w beside the crease too, w put on the crease nearest their
 * middle (two vertices of the two surfaces crowding at the crease become one on it); when v
 * is on a junction (locked and rm_junction_vertex_on), w merged into v where v is
 * instead: merged away or moved to the pair's middle it would leave the junction (the cube
 * with its crease cells stopped by the cut polygons' error, crease25's c775dd5: edges 0.025
 * long at a corner, then 0.2; corner (-1, -1, -1) merged into (-1, -1, -0.975), the nearest
 * vertex 0.012 off it, 8.65° beside it). *junction: whether v is one, once asked (-1
 * before: snap_merge's tries share the answer). True when done; false also when out of
 * memory (rm_merge_apply then changes nothing). */
static bool merge_onto_crease(rm_pass *p, uint32_t v, uint32_t w, const crease_fan *c,
                              const rm_fan *f, int *junction)
{
    const rm_mesh *r = &p->r;
    crease_fan cw;
    rm_merge g;
    if (!walk_fan(p, w, &cw) ||
        !on_crease(p, c->f, rm_pos(p, w), near_tol(p, f->mean_edge), NULL, NULL))
        return false;
    /* v into w first; a junction's vertex is asked only where that merge is there or v is
       locked (a free vertex is on no junction), and then w goes into v whether or not v
       could go into w (the two differ: v's degree, a fan of three) */
    bool v_into_w = rm_merge_find_any(r, v, w, ISM_RM_COLLAPSE_MAX_DEGREE, &g) &&
                    rm_merge_link_ok(r, &g);
    if (!v_into_w && !r->locked[v])
        return false;
    double x[3], mid[3], grad[3];
    crease_frame cf;
    bool framed = false;
    if (*junction < 0)
        *junction = r->locked[v] && rm_junction_vertex_on(p, v);
    if (*junction) {
        if (!rm_merge_find_any(r, w, v, ISM_RM_COLLAPSE_MAX_DEGREE, &g) ||
            !rm_merge_link_ok(r, &g))
            return false;
        memcpy(x, rm_pos(p, v), sizeof x);
    } else {
        if (!v_into_w)
            return false;
        rm_midpoint(rm_pos(p, v), rm_pos(p, w), mid);
        memcpy(x, mid, sizeof x);
        if (!to_crease(p, c->f, x, f->mean_edge, &cf, &framed) ||
            !(rm_dist(x, mid) <= reach_tol(p, f->mean_edge)))
            return false;
    }
    if (!merged_fan_ok(p, &g, x, framed ? &cf : NULL))
        return false;
    ism_eval_gradient(p->f, p->ws, x[0], x[1], x[2], grad);
    if (!(ism_norm3(grad) > p->gthresh))
        return false;
    uint32_t fan[ISM_RM_MERGE_MAX_DEGREE], n;
    if (!rm_merge_apply(&p->r, &g, fan, &n))
        return false;
    rm_cbound_drop(p);
    rm_commit_move(p, g.w, x, grad);
    for (uint32_t i = 0; i < r->count[g.w]; i++) {
        const uint32_t *t = r->m->tri + 3 * (size_t)r->vt[r->start[g.w] + i];
        for (int k = 0; k < 3; k++)
            p->active[t[k]] = 1;
    }
    p->active[g.v] = p->slide[g.v] = 0;
    p->r.locked[g.w] = 1; /* on the crease now: kept there */
    p->collapses++;
    return true;
}

/* v's neighbours closer than ISM_RM_CREASE_MERGE_REL × v's mean edge (and not at v), not
 * RM_PINNED, not a junction's vertex (rm_junction_vertex: it stays put), nearest first (in
 * ring order among equals), at most ISM_RM_CREASE_MERGE_TRIES of them, none as near as one
 * tried before: the first that merges with v onto the crease (merge_onto_crease). True when
 * one did. The candidates are sorted once and rm_junction_vertex asked only of the one about
 * to be tried (each try asked it of every candidate nearer than the best so far: cube, own
 * box, 3,120 asks of 11.7M instructions). */
static bool snap_merge(rm_pass *p, uint32_t v, const crease_fan *c, const rm_fan *f)
{
    const rm_mesh *r = &p->r;
    uint32_t near[ISM_RM_CREASE_SLIDE_MAX_DEGREE];
    double dist[ISM_RM_CREASE_SLIDE_MAX_DEGREE], reach = ISM_RM_CREASE_MERGE_REL * f->mean_edge;
    uint32_t n = 0;
    for (uint32_t i = 0; i < c->n; i++) {
        double d = rm_dist(rm_pos(p, v), rm_pos(p, c->ring[i]));
        if (!(d < reach && d > 0) || r->locked[c->ring[i]] == RM_PINNED)
            continue;
        uint32_t j = n++;
        for (; j > 0 && dist[j - 1] > d; j--) /* stable: equals keep ring order */
            near[j] = near[j - 1], dist[j] = dist[j - 1];
        near[j] = c->ring[i], dist[j] = d;
    }
    double after = 0; /* the last one tried was this far */
    int junction = -1;  /* v a junction's vertex: not asked yet */
    for (uint32_t j = 0, tries = 0; j < n && tries < ISM_RM_CREASE_MERGE_TRIES; j++) {
        if (!(dist[j] > after) || rm_junction_vertex(p, near[j]))
            continue;
        if (merge_onto_crease(p, v, near[j], c, f, &junction))
            return true;
        after = dist[j];
        tries++;
    }
    return false;
}

/* Tries to move v onto the crease (snap) or along it (slide); true when it moved. A
 * junction's vertex (locked: on its creases, rm_locks.c; and rm_junction_vertex_on) is not
 * slid: along one of its creases it leaves the junction (the cube with its crease cells
 * stopped by the cut polygons' error, crease25's c775dd5: a corner slid to (-0.990, -1, -1)).
 * Asked only of a move about to be made, after every other test (each a measure that
 * changes nothing, so the same moves are made). */
static bool slide_vertex(rm_pass *p, uint32_t v, ism_tape *local)
{
    rm_fan f;
    rm_fan_measure(p, v, &f);
    crease_fan c;
    int kind = find_chain(p, v, f.mean_edge, local, &c);
    if (!kind)
        return false;
    if (snap_merge(p, v, &c, &f))
        return true;
    if (kind == 3)
        return false; /* on the crease, no chain to slide along */
    const double *pos = rm_pos(p, v);
    const double *a = kind == 2 ? rm_pos(p, c.end[0]) : pos;
    const double *b = kind == 2 ? rm_pos(p, c.end[1]) : pos;
    /* a slide tries the whole way to the middle, then a half and a quarter; a snap the
       nearest crease point only */
    for (double step = 1; step >= (kind == 2 ? 0.25 : 1); step *= 0.5) {
        double x[3], start[3], g[3];
        for (int k = 0; k < 3; k++)
            x[k] = start[k] = pos[k] + step * (0.5 * (a[k] + b[k]) - pos[k]);
        crease_frame cf;
        bool framed = false;
        if (!to_crease(p, c.f, x, f.mean_edge, &cf, &framed) ||
            !(rm_dist(x, start) <= reach_tol(p, f.mean_edge)) ||
            (kind == 2 && !rm_in_order(x, a, b)) ||
            !fan_shape_ok(p, v, &c, x, framed ? &cf : NULL, f.min_sine))
            continue;
        ism_eval_gradient(p->f, p->ws, x[0], x[1], x[2], g);
        if (!(ism_norm3(g) > p->gthresh) || !rm_centroids_stay(p, v, x))
            continue;
        if (p->r.locked[v] && rm_junction_vertex_on(p, v))
            return false; /* a junction's vertex stays */
        rm_commit_move(p, v, x, g);
        p->r.locked[v] = 1; /* on the crease: kept there (the relaxation would move it off) */
        return true;
    }
    return false;
}

/* v is a corner of a triangle under ISM_RM_COLLAPSE_DEG (the sines as rm_mark_active
 * measured them, or since); *key gets its fan's sines summed (what changes when its fan
 * does). */
static bool corner_of_poor(rm_pass *p, uint32_t v, double poor, double *key)
{
    const rm_mesh *r = &p->r;
    bool any = false;
    *key = r->count[v];
    for (uint32_t i = 0; i < r->count[v]; i++) {
        double s = rm_tri_sine(p, r->vt[r->start[v] + i]);
        any |= s < poor;
        *key += s;
    }
    return any;
}

size_t rm_crease_slide_sweep(rm_pass *p)
{
    const rm_mesh *r = &p->r;
    double poor = rm_collapse_poor();
    if (!ism_tape_has_min_max(p->f) || !(p->poorest < poor))
        return 0; /* no min/max: no crease of branches; no triangle under 20°: no need */
    rm_collapse_bounds_need(p); /* what merges onto the crease keep to */
    if (!p->crease_tried &&
        (p->crease_tried = malloc((r->cap_verts ? r->cap_verts : 1) * sizeof *p->crease_tried)))
        for (size_t v = 0; v < r->cap_verts; v++)
            p->crease_tried[v] = NAN; /* (out of memory: every one asked every time) */
    /* room for f shortened over a fan's box (out of memory: f's own top only) */
    ism_tape *local = ism_tape_new_like(p->f);
    size_t moves = 0;
    /* only the corners of triangles under ISM_RM_COLLAPSE_DEG (active 1: near a poor
       triangle), as the collapses, and not again while their fan is as it was when nothing
       passed: callgrind, isomesh --surface gyroid-ball --threads 1 --quality good, this
       sweep asking every active vertex 452M instructions (the pass 1.23 × polygonise),
       every poor triangle's corners each time 58M, now 38.6M (1.011), for the same
       needles */
    for (size_t v = 0; v < r->m->nverts; v++) {
        double key;
        if (p->active[v] != 1 || r->locked[v] == RM_PINNED || !r->count[v] || r->gone[v] ||
            p->slide[v] || rm_normal_zero(p, (uint32_t)v) ||
            !corner_of_poor(p, (uint32_t)v, poor, &key) ||
            (p->crease_tried && p->crease_tried[v] == key))
            continue;
        bool moved = slide_vertex(p, (uint32_t)v, local);
        moves += moved;
        if (p->crease_tried)
            p->crease_tried[v] = moved ? NAN : key;
    }
    ism_tape_free(local);
    p->moves += moves;
    return moves;
}

/* An upper bound on v's mean edge (rm_fan_measure's): the root of the summed squares from v
 * to its fan's corners already bounds its longest edge, so the mean; the factor 2 is margin
 * only, for rounding in either sum (~1e-16 relative). */
static double mean_edge_above(const rm_pass *p, uint32_t v)
{
    const rm_mesh *r = &p->r;
    const double *x = rm_pos(p, v);
    double sum2 = 0;
    for (uint32_t i = 0; i < r->count[v]; i++) {
        const uint32_t *t = r->m->tri + 3 * (size_t)rm_slot(r, v, i);
        for (int k = 0; k < 3; k++) {
            const double *z = rm_pos(p, t[k]);
            double e[3] = {z[0] - x[0], z[1] - x[1], z[2] - x[2]};
            sum2 += ism_dot3(e, e);
        }
    }
    return 2 * sqrt(sum2);
}

size_t rm_crease_lock_on(rm_pass *p)
{
    rm_mesh *r = &p->r;
    if (!ism_tape_has_min_max(p->f))
        return 0;
    size_t locked = 0;
    for (size_t v = 0; v < r->m->nverts; v++) {
        if (r->locked[v] || !r->count[v] || r->gone[v])
            continue;
        /* off the crease by more than the widest tolerance its fan could give: most free
           vertices (cube, 0.37-cell box: 8,883 fans measured, 10.3M of the pass's 742M
           instructions, for a tolerance only) */
        double val[2], gn[2];
        if (!on_crease(p, p->f, rm_pos(p, (uint32_t)v),
                       ISM_RM_CREASE_ON_REL * mean_edge_above(p, (uint32_t)v), val, gn))
            continue;
        rm_fan f;
        rm_fan_measure(p, (uint32_t)v, &f);
        /* the same test at the fan's own tolerance, on the values just measured */
        if (within_both(val, gn, ISM_RM_CREASE_ON_REL * f.mean_edge)) {
            r->locked[v] = 1; /* on the crease: kept there, as a vertex moved onto it is */
            locked++;
        }
    }
    return locked;
}
