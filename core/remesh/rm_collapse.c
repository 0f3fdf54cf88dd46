/* rm_collapse.c — edge collapses that remove needles and caps no flip or move can mend
 * (a short edge beside long ones: the conformance balls around Kummer's nodes, Steiner's
 * pinch points, the box cut). A free vertex v is merged into a neighbour w (w keeps its
 * place, so it may be locked: a feature vertex stays on its feature): v's two triangles on
 * vw go, its others take w instead of v. Taken only when the mesh keeps saying the same
 * thing — the link condition (no vertex but the two opposite ones is a neighbour of both v
 * and w, counted over every sheet at w), so the topology is kept exactly; every new triangle
 * faces the fan's way and bends no more than a crease against its outer neighbour; the
 * smallest angle of the fan grows; and no new centroid or edge midpoint lies farther from
 * f = 0 than the farthest of the fan's before.
 *
 * A crease (edges bending as one, rm_locks.c, hold their vertices) is shortened the same
 * way where its own vertices crowd: a crease vertex v merged into a neighbour w much nearer
 * than its other neighbours; every vertex the crease keeps stays where it was (on both
 * surfaces), and the triangles on both sides are re-fanned to w (crease_merge_find). Such a
 * merge is tested against each triangle's own normal before (the fan's mean normal across a
 * crease says nothing) and its bends may grow by ISM_RM_CROWD_BEND_DEG (rm_crease_tri_ok,
 * which rm_crease_slide.c's moves along min/max creases share). The polygoniser's
 * crease points on the gyroid ball lie as close as 5e-5 where its cells are 0.023: 264 of
 * its 340 needles had their short edge between two such vertices (bench_remesh gyroid-ball,
 * needles under 10° in its three boxes: 340 / 335 / 424 -> 115 / 113 / 149). The caller's
 * locked edges (curves cut into the mesh, creases among them) stay as they are: merging
 * there would undo the curves stage's crease refinement (3,559 of the gyroid ball's 8,404
 * cut crease points went when it was tried). */
#include "core/analysis/select.h"
#include "core/remesh/rm_bound.h"
#include "core/remesh/rm_cbound.h"
#include "core/remesh/rm_merge.h"
#include "core/remesh/rm_pass.h"
#include "core/util/vec3.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

/* A new triangle may bend against its outer neighbour by at most this (degrees), or by no more
 * than the old triangle did: the crease angle of rm_locks.c, so a collapse makes no crease. */
#define ISM_RM_COLLAPSE_MAX_BEND_DEG 40.0
/* Sweeps over the triangles per call: a collapse leaves its neighbours' needles for the next. */
#define ISM_RM_COLLAPSE_SWEEPS 3

static void corners(const rm_pass *p, uint32_t t, uint32_t v, const double *x, const double *q[3])
{
    rm_merge_corners(&p->r, t, v, x, q);
}

bool rm_crease_tri_ok(const rm_pass *p, uint32_t t, uint32_t a, uint32_t b,
                      const double *o[3], const double *q[3])
{
    double n[3], m[3];
    double ln = rm_cross(q[0], q[1], q[2], n), lo = rm_cross(o[0], o[1], o[2], m);
    if (!(rm_cos_bend(m, lo, n, ln) > cos(ISM_RM_COLLAPSE_MAX_TURN_DEG * M_PI / 180)))
        return false;
    return rm_crease_bend_ok(p, t, a, b, n, ln, m, lo, false);
}

bool rm_crease_bend_ok(const rm_pass *p, uint32_t t, uint32_t a, uint32_t b, const double *n,
                       double ln, const double *m, double lo, bool curvature)
{
    double u[3];
    uint32_t s = rm_merge_across(&p->r, a, b, t);
    if (s == UINT32_MAX)
        return true; /* not manifold: its bend is no crease test's */
    const uint32_t *z = p->r.m->tri + 3 * (size_t)s;
    double lu = rm_cross(rm_pos(p, z[0]), rm_pos(p, z[1]), rm_pos(p, z[2]), u);
    double now = rm_cos_bend(n, ln, u, lu), before = rm_cos_bend(m, lo, u, lu);
    /* a crease's edge bends as it did, give or take the hair moved */
    before = cos(fmin(M_PI, acos(fmax(-1, fmin(1, before))) + ISM_RM_CROWD_BEND_DEG * M_PI / 180));
    if (now >= fmin(before, rm_crease_cos()))
        return true;
    double ab = rm_dist(rm_pos(p, a), rm_pos(p, b));
    return curvature && ab > 0 &&
           rm_bend_is_curvature(p, a, b, acos(fmax(-1, fmin(1, now))), (ln + lu) / ab, NULL);
}

/* New triangle t (v at w's place) faces the fan's way, does not turn over against ∇f where
 * it did not before (Steiner's 0.37-cell box: collapses beside the pinch points turned 9
 * triangles over once the curvature there no longer read as creases), and bends against
 * the triangle across its outer edge no more than the crease angle or than it did before;
 * along a crease, rm_crease_tri_ok. *sine gets its smallest angle's sine, asked first: a
 * sine at or under least fails the merge whatever the rest says (merge_ok), and the bends'
 * triangle across is the dearest part (cube, --quality good, own box: 2,371 of 9,963 merges
 * tried failed on their sines). */
static bool new_triangle_ok(const rm_pass *p, const rm_merge *g, uint32_t t, const double *fan_n,
                            double least, double *sine)
{
    const double *q[3], *o[3];
    corners(p, t, g->v, rm_pos(p, g->w), q);
    *sine = rm_min_sine(q[0], q[1], q[2]);
    if (*sine <= least)
        return false;
    corners(p, t, g->v, rm_pos(p, g->v), o);
    const uint32_t *c = p->r.m->tri + 3 * t;
    int k = rm_corner(p->r.m, t, g->v);
    uint32_t a = c[(k + 1) % 3], b = c[(k + 2) % 3];
    if (g->along)
        return rm_crease_tri_ok(p, t, a, b, o, q);
    double n[3], m[3], u[3];
    double ln = rm_cross(q[0], q[1], q[2], n), lo = rm_cross(o[0], o[1], o[2], m);
    if (!(rm_cos_bend(fan_n, sqrt(ism_dot3(fan_n, fan_n)), n, ln) >
          cos(ISM_RM_COLLAPSE_MAX_TURN_DEG * M_PI / 180)) ||
        rm_turns_over(p, c, g->v, p->normal + 3 * (size_t)g->w, n))
        return false;
    uint32_t s = rm_merge_across(&p->r, a, b, t);
    if (s == UINT32_MAX)
        return true;
    const uint32_t *z = p->r.m->tri + 3 * s;
    double lu = rm_cross(rm_pos(p, z[0]), rm_pos(p, z[1]), rm_pos(p, z[2]), u);
    double now = rm_cos_bend(n, ln, u, lu);
    if (now >= fmin(rm_cos_bend(m, lo, u, lu), cos(ISM_RM_COLLAPSE_MAX_BEND_DEG * M_PI / 180)))
        return true;
    /* a bend f's curvature accounts for is no crease (rm_locks.c asks the same of an edge),
       in the last mending (bend_curvature): beside cusp-a2's cusp the surface is a tube of
       radius z^1.5 (6e-4 at z = 0.007, its edges 2e-3) that a few triangles go round, every
       edge bending by 50°-115°, and each collapse there bent some edge more than before */
    double ab = rm_dist(rm_pos(p, a), rm_pos(p, b));
    return p->bend_curvature && ab > 0 &&
           rm_bend_is_curvature(p, a, b, acos(fmax(-1, fmin(1, now))), (ln + lu) / ab, NULL);
}

/* The farthest of the fan's centroids and of the midpoints of v's edges from f = 0, with v
 * at x (before: x is v's place) or merged into w (after: the removed triangles and the edges
 * to c and d, which are w's already, left out). */
static void fan_distances(rm_pass *p, const rm_merge *g, bool after, double *cen, double *mid)
{
    const rm_mesh *r = &p->r;
    const double *x = rm_pos(p, after ? g->w : g->v);
    *cen = *mid = 0;
    for (uint32_t i = 0; i < r->count[g->v]; i++) {
        uint32_t t = rm_slot(r, g->v, i);
        if (after && (t == g->t1 || t == g->t2))
            continue;
        const double *q[3];
        corners(p, t, g->v, x, q);
        *cen = fmax(*cen, rm_centroid_distance(p, q[0], q[1], q[2]));
        uint32_t next = r->m->tri[3 * t + (rm_corner(r->m, t, g->v) + 1) % 3];
        if (!after || (next != g->c && next != g->d))
            *mid = fmax(*mid, rm_midpoint_distance(p, x, rm_pos(p, next)));
    }
}

bool rm_distances_within(rm_pass *p, double new_c, double new_m)
{
    rm_collapse_bounds_need(p);
    return new_c <= p->centroid_bound && new_m <= p->midpoint_low;
}

bool rm_merge_distance_ok(rm_pass *p, const rm_merge *g)
{
    double new_c, new_m, old_c, old_m;
    fan_distances(p, g, true, &new_c, &new_m);
    if (rm_distances_within(p, new_c, new_m))
        return true; /* within the mesh's before: the fan's own need not be asked */
    fan_distances(p, g, false, &old_c, &old_m);
    return rm_distances_ok(p, new_c, new_m, old_c, old_m);
}

bool rm_distances_ok(rm_pass *p, double new_c, double new_m, double old_c, double old_m)
{
    rm_collapse_bounds_need(p);
    if (!(new_c <= p->centroid_bound || new_c <= old_c))
        return false;
    if (new_m <= old_m)
        return true;
    /* the found mesh's midpoints (rm_midpoint_within, its scan stopped at max_error) asked
       last, along a crease and for a junction's collapse too: the verdict is the found
       mesh's, not the history's (a merge along a crease once passed here only after some
       earlier merge off the creases had measured them, midpoint_known, and best_merge skips
       the second direction's distances once the first passes: revE 1) */
    return rm_midpoint_within(p, new_m);
}

/* What merge_shape_ok asks of v's fan as it is, without measuring it afresh
 * (rm_fan_measure, 12M of the cube's pass): its smallest sine from the sines the pass keeps
 * (rm_tri_sine, rm_fan_measure's bit for bit), how many of its triangles are under poor,
 * and, with normal, the fan's normal (rm_fan_normal, as rm_fan_measure has it). */
static double fan_before(rm_pass *p, uint32_t v, double poor, int *poor_before,
                         double *normal)
{
    const rm_mesh *r = &p->r;
    double least = INFINITY;
    *poor_before = 0;
    for (uint32_t i = 0; i < r->count[v]; i++) {
        double s = rm_tri_sine(p, rm_slot(r, v, i));
        least = s < least ? s : least;
        *poor_before += s < poor;
    }
    if (normal)
        rm_fan_normal(p, v, normal);
    return least;
}

/* Every test of merging g->v into g->w but the distances (rm_merge_distance_ok); g->after
 * gets the new fan's smallest sine. The smallest angle must grow, and no more triangles be
 * poor (under ISM_RM_COLLAPSE_DEG) than before: a needle traded for two thin triangles is no
 * gain. The link condition is asked last (every test here is a reading of the mesh as it
 * is, and most tries fail on their shapes). */
static bool merge_shape_ok(rm_pass *p, rm_merge *g)
{
    const rm_mesh *r = &p->r;
    double poor = rm_collapse_poor(), normal[3];
    int poor_before, poor_after = 0;
    /* the fan's mean normal only where a merge is held to it (not along a crease) */
    double min_sine = fan_before(p, g->v, poor, &poor_before, g->along ? NULL : normal);
    /* a new sine at or under this fails both rules below (the smallest sine must grow, or,
       along a crease at a crease vertex, stay over ISM_RM_CROWD_SINE_FLOOR of it) */
    bool crease_vertex = g->along && r->locked[g->v];
    double least = crease_vertex ? ISM_RM_CROWD_SINE_FLOOR * min_sine : min_sine;
    g->after = INFINITY;
    for (uint32_t i = 0; i < r->count[g->v]; i++) {
        uint32_t t = rm_slot(r, g->v, i);
        double s;
        if (t == g->t1 || t == g->t2)
            continue;
        if (!new_triangle_ok(p, g, t, normal, least, &s))
            return false;
        poor_after += s < poor;
        g->after = fmin(g->after, s);
    }
    /* along a crease the needles come in strips: a merge that leaves fewer poor triangles
       is a gain even where the strip's next needle keeps the fan's smallest angle, as long
       as no angle falls below ISM_RM_CROWD_SINE_FLOOR of it (a crease vertex: locked; a
       free crowding pair, best_merge's crowd retry, must raise the smallest angle) */
    bool fewer = crease_vertex && poor_after < poor_before &&
                 g->after > ISM_RM_CROWD_SINE_FLOOR * min_sine;
    return (fewer || (g->after > min_sine && poor_after <= poor_before)) &&
           rm_merge_link_ok(r, g);
}

/* Every test of merging g->v into g->w (g->after as merge_shape_ok). */
static bool merge_ok(rm_pass *p, rm_merge *g)
{
    return merge_shape_ok(p, g) && rm_merge_distance_ok(p, g);
}

bool rm_merge_do(rm_pass *p, const rm_merge *g, uint32_t *fan, uint32_t *nfan)
{
    uint32_t n;
    if (!rm_merge_apply(&p->r, g, fan, &n))
        return false;
    *nfan = n;
    for (uint32_t i = 0; i < n; i++) {
        const uint32_t *c = p->r.m->tri + 3 * fan[i];
        rm_shape_changed(p, fan[i]);
        for (int k = 0; k < 3; k++)
            p->active[c[k]] = 1, p->touched[c[k]] = 2;
    }
    p->active[g->v] = p->slide[g->v] = 0;
    return true;
}

static double mean_edge(const rm_pass *p, uint32_t v, const uint32_t *nb, uint32_t n)
{
    double sum = 0;
    for (uint32_t j = 0; j < n; j++)
        sum += rm_dist(rm_pos(p, v), rm_pos(p, nb[j]));
    return n ? sum / n : 0;
}

/* v's distinct neighbours into nb (*nnb of them; room for 2 × ISM_RM_MERGE_MAX_DEGREE), and
 * whether vw is shorter than ISM_RM_CROWD × v's mean edge: a pair that crowds. */
static bool crowds(const rm_pass *p, uint32_t v, uint32_t w, uint32_t *nb, uint32_t *nnb)
{
    *nnb = (uint32_t)rm_merge_neighbours(&p->r, v, nb);
    return rm_dist(rm_pos(p, v), rm_pos(p, w)) <= ISM_RM_CROWD * mean_edge(p, v, nb, *nnb);
}

/* For merging v into w along the short edge vw of a crease: v is locked but no given
 * point's vertex or segment end, its triangles are one closed fan of manifold edges with one
 * label, none on the caller's locked list — so what holds v is the bend of some edge as a
 * crease, or ∇f vanishing at v and at w, on a curve of zeros (rm_locks.c) — and vw is
 * shorter than ISM_RM_CROWD × v's mean edge: where the polygoniser's crease points crowd, the
 * needles' own edges read as creases too, and the crease moves by a hair. v keeps no place of
 * its own (w's stands), so a vanishing ∇f at v asks nothing of the merge: Taubin's heart is
 * f = q³ - z³(x² + 9/80 y²), whose ∇f vanishes along q = 0 on its smooth sheet at z = 0; in
 * its own box the polygoniser puts vertices on that curve 2e-4 apart, and refusing them left
 * 31 triangles under 10° (0.39°) there, none after. No edge's crease test is asked (its
 * Hessians made the pass 17% dearer on the gyroid ball, for 3 needles fewer of 240). A
 * junction's vertex (rm_junction_vertex: three sheets or more meet there) is not v. */
static bool crease_merge_find(const rm_pass *p, uint32_t v, uint32_t w, uint32_t deg,
                              rm_merge *g)
{
    const rm_mesh *r = &p->r;
    if (r->locked[v] == RM_PINNED || (rm_normal_zero(p, v) && !rm_normal_zero(p, w)) ||
        !rm_merge_find_any(r, v, w, deg, g))
        return false; /* a lone zero of ∇f (an unlisted singular point) keeps its place */
    uint32_t nb[2 * ISM_RM_MERGE_MAX_DEGREE], nnb;
    if (!crowds(p, v, w, nb, &nnb) ||
        nnb != r->count[v]) /* one closed fan: as many neighbours as triangles */
        return false;
    for (uint32_t j = 0; j < nnb; j++) {
        uint32_t two[2];
        int k;
        if (!rm_edge_triangles(r, v, nb[j], two, &k) || rm_edge_locked(r, v, nb[j]) ||
            rm_label(r, two[0]) != rm_label(r, two[1]))
            return false;
    }
    if (rm_junction_vertex(p, v))
        return false; /* the junction's vertex stays: w may merge into it */
    g->along = true;
    return true;
}

/* The better of merging a into b and b into a, when either passes every test (along a
 * crease when both are locked; a free pair much closer than its edges, as a crowd when the
 * plain merge fails both ways). */
static bool best_merge(rm_pass *p, uint32_t a, uint32_t b, rm_merge *best)
{
    rm_merge g[2];
    bool have[2], found = false, crease = p->r.locked[a] && p->r.locked[b];
    uint32_t deg = ISM_RM_COLLAPSE_MAX_DEGREE;
    bool shaped[2];
    for (int k = 0; k < 2; k++) {
        uint32_t v = k ? b : a, w = k ? a : b;
        have[k] = crease ? crease_merge_find(p, v, w, deg, &g[k])
                         : rm_merge_find(&p->r, v, w, deg, &g[k]);
        shaped[k] = have[k] && merge_shape_ok(p, &g[k]);
    }
    /* the better-shaped of the two first (the first on a tie, as before): when its distances
       pass the other cannot be better, and its distances are not measured (the dearest test:
       rm_merge_distance_ok was 17M of the cube's 345M-instruction pass) */
    int first = shaped[1] && (!shaped[0] || g[1].after > g[0].after) ? 1 : 0;
    for (int i = 0; i < 2 && !found; i++) {
        int k = i ? 1 - first : first;
        if (shaped[k] && rm_merge_distance_ok(p, &g[k]))
            *best = g[k], found = true;
    }
    if (found || crease || p->may_crease)
        return found; /* where f may crease, crease_merge_find has the crowds (free pairs
                         as a crowd too: gyroid-ball 1 / 4 / 6 needles -> 3 / 0 / 7) */
    /* For merging free v into w, on a surface without creases (may_crease false), when vw is
     * shorter than ISM_RM_CROWD × v's mean edge: v's triangles then move by a hair, and each is
     * held to its own normal before as along a crease (rm_crease_tri_ok) instead of the fan's
     * mean normal, which says nothing where the fan is folded. Kummer-16's conformance rims leave
     * such pairs 1e-4 apart in folded fans (new triangles 70°-160° from the fan's normal); while
     * the bends there locked them as creases crease_merge_find took them, and once kink-free
     * surfaces had no creases (rm_locks.c) they stayed: smallest angle 2.79° -> 0.25° in the
     * preset's own box. */
    for (int k = 0; k < 2; k++) {
        uint32_t nb[2 * ISM_RM_MERGE_MAX_DEGREE], nnb;
        if (have[k] && crowds(p, g[k].v, g[k].w, nb, &nnb)) {
            g[k].along = true; /* merge_ok wrote only g[k].after: the plain find's g stands */
            if (merge_ok(p, &g[k]) && (!found || g[k].after > best->after))
                *best = g[k], found = true;
        }
    }
    return found;
}

/* Tries t's edges, shortest first; true when one was collapsed, the corners of the merged
 * fan then stamped now in stamp (NULL: none kept). *ok false when out of memory. */
static bool collapse_triangle(rm_pass *p, uint32_t t, uint32_t *stamp, uint32_t now, bool *ok)
{
    const uint32_t *c = p->r.m->tri + 3 * t;
    uint32_t v[3] = {c[0], c[1], c[2]};
    double len[3];
    int order[3] = {0, 1, 2};
    for (int k = 0; k < 3; k++)
        len[k] = rm_dist(rm_pos(p, v[k]), rm_pos(p, v[(k + 1) % 3]));
    for (int i = 1; i < 3; i++) /* edges by length: three elements */
        for (int j = i; j > 0 && len[order[j]] < len[order[j - 1]]; j--) {
            int s = order[j];
            order[j] = order[j - 1], order[j - 1] = s;
        }
    for (int i = 0; i < 3; i++) {
        int k = order[i];
        rm_merge g;
        if (best_merge(p, v[k], v[(k + 1) % 3], &g)) {
            uint32_t fan[ISM_RM_MERGE_MAX_DEGREE], nfan;
            *ok = rm_merge_do(p, &g, fan, &nfan);
            for (uint32_t j = 0; *ok && stamp && j < nfan; j++)
                for (int c = 0; c < 3; c++)
                    stamp[p->r.m->tri[3 * (size_t)fan[j] + c]] = now;
            return *ok;
        }
    }
    return false;
}

/* Triangles whose edge midpoints give midpoint_low: those with the farthest centroids, where
 * the mesh's farthest midpoints lie too (gyroid-ball: along its crease). 16 were too few
 * once merges along the crease came: a collapse beside them asked past midpoint_low and the
 * found mesh's 141,276 midpoints were measured (177M instructions, 9% of the pass); with
 * 256 none asks, for the same mesh (midpoint_low only decides sooner what the bound would). */
#define ISM_RM_MIDPOINT_LOW_TRIS 256

/* Triangle t with centroid distance d into the short list top (distances topd), farthest
 * first, an earlier triangle before a later one at the same distance; the last one drops off
 * a full list. */
static void top_insert(int64_t *top, double *topd, size_t t, double d)
{
    int i = ISM_RM_MIDPOINT_LOW_TRIS;
    while (i > 0 && d > topd[i - 1]) {
        if (i < ISM_RM_MIDPOINT_LOW_TRIS)
            top[i] = top[i - 1], topd[i] = topd[i - 1];
        i--;
    }
    if (i < ISM_RM_MIDPOINT_LOW_TRIS)
        top[i] = (int64_t)t, topd[i] = d;
}

/* The short list (top_insert) of the n triangles whose distances are d (NaN: a degenerate
 * one, left out), as inserting every one in order would leave it: only those at or above the
 * list's length-th farthest are inserted — one nearer ends below a full list whatever came
 * before it, and inserting it moves nothing that stays. (pretzel-genus2 irrational box,
 * callgrind, --quality good, default bound, 1 thread: farthest 4.69M instructions inserting
 * all, ~2.5M so; the pass 72.1M -> 70.38M.) */
static void top_list(const double *d, size_t n, int64_t *top)
{
    double topd[ISM_RM_MIDPOINT_LOW_TRIS], least = -INFINITY;
    for (int i = 0; i < ISM_RM_MIDPOINT_LOW_TRIS; i++)
        top[i] = -1, topd[i] = -1;
    double *live = malloc((n ? n : 1) * sizeof *live);
    size_t nlive = 0;
    for (size_t t = 0; live && t < n; t++)
        if (!isnan(d[t]))
            live[nlive++] = d[t];
    if (live && nlive > ISM_RM_MIDPOINT_LOW_TRIS) /* (out of memory: every one inserted) */
        least = ism_an_select_double(live, nlive, nlive - ISM_RM_MIDPOINT_LOW_TRIS);
    free(live);
    for (size_t t = 0; t < n; t++)
        if (!isnan(d[t]) && d[t] >= least)
            top_insert(top, topd, t, d[t]);
}

/* Whether triangle v has a repeated corner. */
static inline bool repeats_corner(const uint32_t *v)
{
    return v[0] == v[1] || v[1] == v[2] || v[0] == v[2];
}

/* The edges a -> b with a < b of the ntris triangles tri (none with a repeated corner), by a:
 * a's are (*to)[first[a] .. first[a + 1]) for a < nv (one past the largest corner). False
 * when out of memory (nothing kept). Counted, then placed: two passes over tri, no sort
 * (sorting the keys and searching them was 5M instructions of chmutov-quartic's pass). */
static bool edges_up(const uint32_t *tri, size_t ntris, uint32_t **first, uint32_t **to,
                     size_t *nv)
{
    *nv = 0;
    for (size_t i = 0; i < 3 * ntris; i++)
        *nv = tri[i] >= *nv ? (size_t)tri[i] + 1 : *nv;
    *first = calloc(*nv + 1, sizeof **first);
    *to = malloc((ntris ? 3 * ntris : 1) * sizeof **to);
    if (!*first || !*to) {
        free(*first);
        free(*to);
        return false;
    }
    for (int pass = 0; pass < 2; pass++) {
        for (size_t t = 0; t < ntris; t++) {
            const uint32_t *v = tri + 3 * t;
            for (int k = 0; k < 3 && !repeats_corner(v); k++)
                if (v[k] < v[(k + 1) % 3]) {
                    if (pass)
                        (*to)[(*first)[v[k]]++] = v[(k + 1) % 3];
                    else
                        (*first)[v[k] + 1]++;
                }
        }
        if (pass) /* each first[a] has moved to first[a + 1]: back by one place */
            memmove(*first + 1, *first, *nv * sizeof **first), (*first)[0] = 0;
        else
            for (size_t a = 0; a < *nv; a++)
                (*first)[a + 1] += (*first)[a];
    }
    return true;
}

/* The farthest from f = 0 of the midpoints of the edges a -> b with a > b of the ntris
 * triangles tri (none with a repeated corner) that no triangle runs b -> a: what farthest's
 * scan of the edges a < b leaves out, an open found mesh's boundary edges listed larger index
 * first (a surface the box clips; revE 2). Every such edge when the edges cannot be listed. */
static double boundary_midpoints(rm_pass *p, const double *pos, const uint32_t *tri,
                                 size_t ntris)
{
    uint32_t *first = NULL, *to = NULL;
    size_t nv;
    bool listed = edges_up(tri, ntris, &first, &to, &nv);
    double far = 0;
    for (size_t t = 0; t < ntris; t++) {
        const uint32_t *v = tri + 3 * t;
        if (repeats_corner(v))
            continue;
        for (int k = 0; k < 3; k++) {
            uint32_t a = v[k], b = v[(k + 1) % 3];
            if (a < b)
                continue;
            bool twin = false;
            for (uint32_t i = listed ? first[b] : 0; listed && !twin && i < first[b + 1]; i++)
                twin = to[i] == a;
            if (!twin)
                far = fmax(far, rm_midpoint_distance(p, pos + 3 * (size_t)a,
                                                     pos + 3 * (size_t)b));
        }
    }
    free(first);
    free(to);
    return far;
}

/* Points farthest measures at a time: one chunk of rm_bound_distances, so every call but the
 * last fills the batched evaluator's lanes, and the midpoints' cap (farthest) is looked at
 * every this many points. A triangle adds up to three midpoints, so the gathering array has
 * room for two beyond it: those wait for the next chunk. */
#define RM_FAR_CHUNK RM_DISTANCES_CHUNK

/* The midpoints' figure has reached max_error, its cap: the rest cannot change it (cube,
 * 0.37-cell box: a midpoint at max_error, and the found mesh's 50,000 midpoints were 18M of
 * the pass's 742M instructions). */
static bool far_capped(const rm_pass *p, bool midpoints, double far)
{
    return midpoints && p->max_error > 0 && far >= p->max_error;
}

/* The points farthest has gathered: each one's triangle (centroids), measured together. */
typedef struct far_points {
    double q[RM_FAR_CHUNK + 2][3], d[RM_FAR_CHUNK + 2], gn[RM_FAR_CHUNK + 2];
    size_t tri[RM_FAR_CHUNK + 2], n;
} far_points;

/* The first k gathered points measured (the rest moved to the front, to wait); returns far
 * raised to the farthest of them. Each centroid's distance is kept (rm_cbound_set) and goes
 * into ds, or without ds (top) into the short list, in the triangles' order, as measuring
 * them one by one did. */
static double far_flush(rm_pass *p, far_points *b, size_t k, bool midpoints, double far,
                        double *ds, int64_t *top, double *topd)
{
    rm_bound_distances(p, (const double (*)[3])b->q, k, b->d, b->gn);
    for (size_t i = 0; i < k; i++) {
        double d = b->d[i];
        far = fmax(far, d);
        if (midpoints)
            continue;
        rm_cbound_set(p, (uint32_t)b->tri[i], b->q[i], d, b->gn[i]);
        if (ds)
            ds[b->tri[i]] = d;
        else if (top)
            top_insert(top, topd, b->tri[i], d);
    }
    b->n -= k;
    memmove(b->q, b->q + k, b->n * sizeof *b->q);
    memmove(b->tri, b->tri + k, b->n * sizeof *b->tri);
    return far;
}

/* The farthest from f = 0 of the centroids (or, with midpoints, of the edge midpoints) of
 * the ntris triangles tri over the places pos, at most max_error when there is one. With
 * top (centroids only; ISM_RM_MIDPOINT_LOW_TRIS entries, -1 where none), the triangles with
 * the farthest centroids, farthest first (top_list); each centroid's distance is kept
 * (rm_cbound.h). The points are measured RM_FAR_CHUNK at a time through the batched
 * evaluator (rm_bound_distances: rm_distance's figures bit for bit, one pass over the tape
 * for a chunk's first steps and one for its second; chmutov-quartic, own box, callgrind
 * --quality good --threads 1: farthest 44.7M -> 26.8M instructions for 12,768 centroids and
 * 19,152 midpoints, the pass 352.4M -> 334.1M; gathered 64 at a time rather than 126, every
 * chunk full, 26.45M -> 26.39M). */
static double farthest(rm_pass *p, const double *pos, const uint32_t *tri, size_t ntris,
                       bool midpoints, int64_t *top)
{
    double far = 0, *ds = top ? malloc((ntris ? ntris : 1) * sizeof *ds) : NULL;
    double topd[ISM_RM_MIDPOINT_LOW_TRIS];
    for (int i = 0; top && !ds && i < ISM_RM_MIDPOINT_LOW_TRIS; i++)
        top[i] = -1, topd[i] = -1;
    far_points pts, *b = &pts;
    b->n = 0;
    for (size_t t = 0; t < ntris; t++) {
        const uint32_t *v = tri + 3 * t;
        const double *q[3] = {pos + 3 * (size_t)v[0], pos + 3 * (size_t)v[1],
                              pos + 3 * (size_t)v[2]};
        if (ds)
            ds[t] = NAN;
        if (repeats_corner(v))
            continue;
        if (!midpoints)
            rm_centroid(q[0], q[1], q[2], b->q[b->n]), b->tri[b->n++] = t;
        for (int k = 0; midpoints && k < 3; k++)
            if (v[k] < v[(k + 1) % 3]) /* an oriented edge with its twin: once (the rest
                                          after the loop, boundary_midpoints) */
                rm_midpoint(q[k], q[(k + 1) % 3], b->q[b->n++]);
        if (b->n < RM_FAR_CHUNK)
            continue;
        far = far_flush(p, b, RM_FAR_CHUNK, midpoints, far, ds, top, topd);
        if (far_capped(p, midpoints, far)) /* looked at a chunk at a time: fewer than
                                             RM_FAR_CHUNK points measured past the cap */
            break;
    }
    if (!far_capped(p, midpoints, far))
        far = far_flush(p, b, b->n, midpoints, far, ds, top, topd);
    if (midpoints && !far_capped(p, midpoints, far))
        far = fmax(far, boundary_midpoints(p, pos, tri, ntris));
    if (ds)
        top_list(ds, ntris, top);
    free(ds);
    return fmin(far, p->max_error > 0 ? p->max_error : INFINITY);
}

void rm_collapse_bounds(rm_pass *p, const double *pos, const uint32_t *tri, size_t ntris)
{
    p->found_pos = pos;
    p->found_tri = tri;
    p->found_ntris = ntris;
    p->midpoint_known = false;
    p->bounds_known = false;
    if (!p->bounded) /* flips and moves keep to centroid_bound, through farthest's records */
        rm_collapse_bounds_need(p);
}

void rm_collapse_bounds_need(rm_pass *p)
{
    if (p->bounds_known)
        return;
    int64_t top[ISM_RM_MIDPOINT_LOW_TRIS];
    const double *pos = p->found_pos;
    const uint32_t *tri = p->found_tri;
    p->bounds_known = true;
    p->centroid_bound = farthest(p, pos, tri, p->found_ntris, false, top);
    double low = 0, m[3 * ISM_RM_MIDPOINT_LOW_TRIS][3], d[3 * ISM_RM_MIDPOINT_LOW_TRIS];
    size_t n = 0;
    for (int i = 0; i < ISM_RM_MIDPOINT_LOW_TRIS && top[i] >= 0; i++) {
        const uint32_t *v = tri + 3 * top[i];
        for (int k = 0; k < 3; k++)
            rm_midpoint(pos + 3 * (size_t)v[k], pos + 3 * (size_t)v[(k + 1) % 3], m[n++]);
    }
    rm_bound_distances(p, (const double (*)[3])m, n, d, NULL);
    for (size_t i = 0; i < n; i++)
        low = fmax(low, d[i]);
    p->midpoint_low = fmin(low, p->max_error > 0 ? p->max_error : INFINITY);
}

bool rm_midpoint_within(rm_pass *p, double d)
{
    rm_collapse_bounds_need(p);
    if (d <= p->midpoint_low)
        return true;
    if (!p->midpoint_known) {
        p->midpoint_bound = farthest(p, p->found_pos, p->found_tri, p->found_ntris, true, NULL);
        p->midpoint_known = true;
    }
    return d <= p->midpoint_bound;
}

/* Whether triangle t is tried in a sweep after the first: a collapse came near it (stamped
 * one of its corners) since it was last tried (tried; 0: not in this call). A heuristic, not
 * exact: t's try also reads the triangles across its corners' fans' outer edges
 * (new_triangle_ok, rm_crease_tri_ok: rm_merge_across), two rings out, which a collapse
 * there changes without stamping t (the code before these stamps, retrying every triangle
 * beside a collapse of the sweep before, missed them too unless a collapse came beside t in
 * that sweep as well). Measured, not proved:
 * mesh_identity.py found the same meshes as that code, and stamping w's two rings instead
 * (exact) changed cube-minus-ball's quality mesh (own box: 1,787 collapses for 1,786,
 * 11,772 triangles for 11,774, smallest angle 18.07° either way). Cost: cube, --quality
 * good, own box, the second and third sweeps of round 2 tried 2,669 triangles for 63
 * collapses when every triangle beside a collapse of the sweep before was tried again.
 * Without the stamps (out of memory), every triangle beside one (touched). */
static bool near_new_collapse(const rm_pass *p, const uint32_t *v, const uint32_t *stamp,
                              uint32_t tried)
{
    if (!stamp)
        return p->touched[v[0]] | p->touched[v[1]] | p->touched[v[2]];
    return stamp[v[0]] > tried || stamp[v[1]] > tried || stamp[v[2]] > tried;
}

size_t rm_collapse_active(rm_pass *p, bool *ok)
{
    const ism_mesh *m = p->r.m;
    double poor = rm_collapse_poor();
    size_t total = 0;
    *ok = true;
    memset(p->touched, 1, m->nverts);
    /* per vertex the collapses made (this call) when one last came near it, per triangle
       the collapses made when it was last tried; the first sweep tries every poor one */
    uint32_t *stamp = calloc(m->nverts ? m->nverts : 1, sizeof *stamp);
    uint32_t *tried = calloc(m->ntris ? m->ntris : 1, sizeof *tried);
    if (!stamp || !tried) {
        free(stamp);
        free(tried);
        stamp = tried = NULL;
    }
    uint32_t now = 0; /* collapses made so far, plus one */
    for (int sweep = 0; sweep < ISM_RM_COLLAPSE_SWEEPS && *ok; sweep++) {
        size_t made = 0;
        for (size_t t = 0; t < m->ntris && *ok; t++) {
            const uint32_t *v = m->tri + 3 * t;
            if (p->r.dead[t] || (sweep && !near_new_collapse(p, v, stamp, tried[t])) ||
                !(rm_tri_sine(p, (uint32_t)t) < poor))
                continue;
            if (tried)
                tried[t] = now;
            if (collapse_triangle(p, (uint32_t)t, stamp, now + 1, ok))
                made++, now++;
        }
        for (size_t v = 0; v < m->nverts; v++) /* 2: touched in this sweep */
            p->touched[v] = p->touched[v] == 2;
        total += made;
        if (!made)
            break;
    }
    free(stamp);
    free(tried);
    p->collapses += total;
    return total;
}
