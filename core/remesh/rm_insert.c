/* rm_insert.c — a vertex inserted beside the short edge of a needle that no collapse can
 * mend: both ends of the short edge are locked (a double line's consecutive vertices,
 * steiner-roman: 0.0005 beside 0.005), so the needle's apex is the nearest vertex there is;
 * or the collapse of the short edge was refused (rm_collapse.c runs first on every needle
 * this sees) because a merge would turn a triangle over where the surface folds within a
 * cell (beside the cross-cap's pinch points, the fold's radius ~1/8 cell) or would merge a
 * free vertex into a feature's.
 * The new vertex goes where an equilateral triangle on the short edge would have its apex
 * (closer to the edge where the needle's angle at one end is under 120°, so it stays inside),
 * put on f = 0 by Newton along the needle's normal; the needle becomes three triangles, the
 * first well shaped, the two thin ones next to the apex left to the Lawson flips that follow
 * (their long sides are free edges, so the flips can replace them). Where the needle across
 * a long side has the same apex and its short edge continues this one's (a fan of needles
 * from one sheet vertex to a row of a double curve's vertices), that shared side is split
 * instead, at a vertex beside the chord of both short edges (split_pair): each round of
 * splits halves the row, so a fan of k needles is gone in about log2 k rounds. The new
 * triangles keep the needle's origin (its label, its place in a range of triangles); χ is
 * kept (one vertex, three edges, two triangles more, either way). */
#include "core/remesh/rm_cbound.h"
#include "core/remesh/rm_pass.h"
#include "core/util/vec3.h"

#include <math.h>
#include <string.h>

/* The thin halves' Lawson test must pass by this much (radians): rm_flip.c's margin keeps
 * four points of a circle from flipping, and the flip must happen for the split to pay. */
#define ISM_RM_INSERT_FLIP_MARGIN 1e-6
/* The apex lies at least this many equilateral heights from the short edge (else the
 * triangle is no needle of a short edge: a cap, left to the flips). */
#define ISM_RM_INSERT_TALL 2.0
/* Newton may move the new vertex at most this × the short edge off its place in the needle
 * (farther, it found another sheet or a fold). */
#define ISM_RM_INSERT_PROJECT_MAX 0.25
/* Newton steps, and the step (× the short edge) that ends them: quadratic convergence from a
 * fraction of an edge (rm_relax.c's ISM_RM_NEWTON_STEPS and _REL). */
#define ISM_RM_INSERT_NEWTON_STEPS 8
#define ISM_RM_INSERT_NEWTON_REL 1e-6
/* Sweeps of splits per call, the flips between them, while the last sweep split a pair (a
 * needle alone needs no next level: gyroid-ball's crease needles, pass 1,248.3M with every
 * level swept, 1,240.7M so): a fan of k needles takes about log2 k
 * (coordinate-planes in the irrational box: fans of 12 to 40+ needles, 0.19 / 0.0078), but
 * the relaxation between the rounds' calls mends the rows' last needles with fewer vertices
 * (callgrind pass, default bound, coordinate-planes / crossing-planes irrational box, 1 to 6
 * and 10 levels: 341.7 / 346.6 / 304.7 / 312.7 / 325.1 / 331.9M, 119.0 / 102.7 / 95.7 /
 * 95.3 / 97.7 / 102.2M; Whitney's 1e-3 box 107.1M at 1, 104.0M from 3; 3 levels: 8,766
 * triangles, 6 levels 9,520, no needle off the box cut either way). */
#define ISM_RM_INSERT_LEVELS 3

/* The needle t as (a, b, c) in its winding, ab its shortest side; false when t is no needle
 * of a short edge with free long sides. The short edge's ends may be locked or free: the
 * collapses have had their try (cross-cap's own box, preset depth: needles under 10° away
 * from its points 10 -> 6 when free ends are taken too, 1e-3 box 12 -> 10; steiner-roman,
 * klein-bottle, kummer-16-nodes unchanged). */
static bool needle(const rm_pass *p, uint32_t t, uint32_t abc[3])
{
    const rm_mesh *r = &p->r;
    const uint32_t *v = r->m->tri + 3 * t;
    int k = 0;
    double best = INFINITY;
    for (int i = 0; i < 3; i++) {
        double l = rm_dist(rm_pos(p, v[i]), rm_pos(p, v[(i + 1) % 3]));
        if (l < best)
            best = l, k = i;
    }
    for (int i = 0; i < 3; i++)
        abc[i] = v[(k + i) % 3];
    double n[3], twice_area = rm_cross(rm_pos(p, abc[0]), rm_pos(p, abc[1]), rm_pos(p, abc[2]), n);
    double height = best > 0 ? twice_area / best : 0;
    return height >= ISM_RM_INSERT_TALL * sqrt(0.75) * best && rm_edge_free(p, abc[1], abc[2]) &&
           rm_edge_free(p, abc[2], abc[0]);
}

/* Newton along the line through x in direction n (unit) onto f = 0: beside a double line ∇f
 * leans toward the other sheet, while the needle's normal leads back to the needle's own.
 * g gets ∇f there; false when it does not converge within ISM_RM_INSERT_PROJECT_MAX × len. */
static bool project_along(rm_pass *p, double x[3], const double n[3], double len, double g[3])
{
    double s = 0, x0[3] = {x[0], x[1], x[2]};
    for (int i = 0; i < ISM_RM_INSERT_NEWTON_STEPS; i++) {
        double fv = ism_eval_gradient(p->f, p->ws, x[0], x[1], x[2], g), slope = ism_dot3(g, n);
        if (!isfinite(fv) || !(fabs(slope) > p->gthresh))
            return false;
        double step = fv / slope;
        s -= step;
        for (int k = 0; k < 3; k++)
            x[k] = x0[k] + s * n[k];
        if (!(fabs(s) <= ISM_RM_INSERT_PROJECT_MAX * len))
            return false;
        if (fabs(step) <= ISM_RM_INSERT_NEWTON_REL * len) {
            ism_eval_gradient(p->f, p->ws, x[0], x[1], x[2], g);
            return sqrt(ism_dot3(g, g)) > p->gthresh;
        }
    }
    return false;
}

/* The place of the new vertex, before projection: seen from a and b at half the needle's
 * angles there, at most 60° (the apex of the equilateral triangle on ab where both angles
 * allow), in the needle's plane; n gets the needle's unit normal. */
static bool place_in_needle(const rm_pass *p, const uint32_t abc[3], double x[3], double n[3])
{
    const double *a = rm_pos(p, abc[0]), *b = rm_pos(p, abc[1]), *c = rm_pos(p, abc[2]);
    double ln = rm_cross(a, b, c, n), len = rm_dist(a, b);
    double alpha = fmin(M_PI / 3, 0.5 * rm_angle(a, b, c));
    double beta = fmin(M_PI / 3, 0.5 * rm_angle(b, c, a));
    if (!(ln > 0) || !(len > 0) || !(alpha > 0) || !(beta > 0))
        return false;
    double e1[3], e2[3];
    for (int k = 0; k < 3; k++) {
        n[k] /= ln;
        e1[k] = (b[k] - a[k]) / len;
    }
    /* e2 = n × e1: in the plane, perpendicular to ab, on c's side (the winding a, b, c) */
    ism_cross3(n, e1, e2);
    double s = len * sin(beta) / sin(alpha + beta);
    for (int k = 0; k < 3; k++)
        x[k] = a[k] + s * (cos(alpha) * e1[k] + sin(alpha) * e2[k]);
    return true;
}

/* The new vertex's place on f = 0 beside chord ab of triangle abc (a needle's short edge, or
 * the chord of two needles' short edges), along the triangle's normal n (unit); g gets ∇f
 * there. */
static bool new_place(rm_pass *p, const uint32_t abc[3], double x[3], double n[3], double g[3])
{
    return place_in_needle(p, abc, x, n) &&
           project_along(p, x, n, rm_dist(rm_pos(p, abc[0]), rm_pos(p, abc[1])), g);
}

/* The triangles (ring[k], ring[k + 1], x) round the ring of n corners (a needle's three, a
 * split edge's quad's four) face the way of normal n0. */
static bool faces_kept(const rm_pass *p, const uint32_t *ring, int n, const double n0[3],
                       const double *x)
{
    double m[3];
    for (int k = 0; k < n; k++) {
        rm_cross(rm_pos(p, ring[k]), rm_pos(p, ring[(k + 1) % n]), x, m);
        if (!(ism_dot3(n0, m) > 0))
            return false;
    }
    return true;
}

/* No centroid of the triangles round x (faces_kept's) farther from f = 0 than the farthest
 * centroid own of the triangles they replace, or than the mesh's farthest before the pass
 * (centroid_bound, as collapses keep); under a bound (bounded), no midpoint of the new edges
 * from x farther than own or the mesh's farthest midpoint (midpoint_bound) either. */
static bool centroids_ok(rm_pass *p, const uint32_t *ring, int n, double own, const double *x)
{
    rm_collapse_bounds_need(p);
    double bound = fmax(own, p->centroid_bound);
    for (int k = 0; k < n; k++)
        if (!(rm_centroid_distance(p, rm_pos(p, ring[k]), rm_pos(p, ring[(k + 1) % n]), x) <=
              bound))
            return false;
    if (!p->bounded)
        return true;
    for (int k = 0; k < n; k++) {
        double d = rm_midpoint_distance(p, rm_pos(p, ring[k]), x);
        if (!(d <= own || rm_midpoint_within(p, d)))
            return false;
    }
    return true;
}

/* The thin triangle (a, b, x) of a split (ab a long side of the needle) will be flipped
 * away, so the split is not left with two needles where it had one: the angles at x and at
 * the vertex y across ab sum above π (the Lawson test), and when no relaxation follows
 * (last), the flip of ab to xy passes every test of a flip now (rm_flip.c). Rounds that
 * relax after the split get their flips later (steiner-roman's own box: 2 needles left
 * with the Lawson test alone, 17 with the whole test in every round), but after the last
 * mending a thin half stays: near Steiner's pinch points its quad bends too much to flip
 * (0.37-cell box: 24 of the 45 needles left were such halves). */
static bool flippable(rm_pass *p, uint32_t a, uint32_t b, const double *x, bool last)
{
    uint32_t two[2];
    int n;
    if (!rm_edge_triangles(&p->r, a, b, two, &n))
        return false;
    const uint32_t *o = p->r.m->tri + 3 * two[1]; /* runs b -> a */
    const double *y = rm_pos(p, o[(rm_corner(p->r.m, two[1], a) + 1) % 3]);
    if (last)
        return rm_flip_would_pass(p, rm_pos(p, a), rm_pos(p, b), x, y);
    return rm_angle(x, rm_pos(p, a), rm_pos(p, b)) + rm_angle(y, rm_pos(p, a), rm_pos(p, b)) >
           M_PI + ISM_RM_INSERT_FLIP_MARGIN;
}

/* A split's new vertex x (∇f there g) beside the chord of place (new_place), the triangles
 * round it over the ring of n corners (the needle's three, the pair's four) facing as
 * place's (faces_kept). */
static bool place_kept(rm_pass *p, const uint32_t place[3], const uint32_t *ring, int n,
                       double x[3], double g[3])
{
    double nrm[3];
    return new_place(p, place, x, nrm, g) && faces_kept(p, ring, n, nrm, x);
}

/* ... and x fits: centroids_ok against own (the replaced triangles' farthest centroid), and
 * the ring's two sides into its apex ring[n - 1] flippable. */
static bool place_fits(rm_pass *p, const uint32_t *ring, int n, double own, const double *x,
                       bool last)
{
    return centroids_ok(p, ring, n, own, x) && flippable(p, ring[n - 2], ring[n - 1], x, last) &&
           flippable(p, ring[n - 1], ring[0], x, last);
}

/* Appends triangle (a, b, c) cut from triangle t (its origin); its index. */
static uint32_t add_triangle(rm_pass *p, uint32_t t, uint32_t a, uint32_t b, uint32_t c)
{
    rm_mesh *r = &p->r;
    uint32_t s = (uint32_t)r->m->ntris;
    ism_mesh_add_triangle(r->m, a, b, c); /* within the room reserved at the start */
    r->origin[s] = r->origin[t];
    r->dead[s] = 0;
    return s;
}

/* The new vertex *v at x (∇f there g) with room for slots triangles, its normal's side from
 * vertex like's (the apex's normal says which side of ∇f the mesh's normals take here). False
 * when out of memory. */
static bool new_vertex(rm_pass *p, const double *x, const double *g, uint32_t like,
                       uint32_t slots, uint32_t *v)
{
    rm_mesh *r = &p->r;
    *v = ism_mesh_add_vertex(r->m, x, NULL);
    r->start[*v] = r->room[*v] = r->count[*v] = 0;
    r->locked[*v] = r->gone[*v] = 0;
    p->slide[*v] = 0;
    if (!rm_slot_reserve(r, *v, slots))
        return false;
    memcpy(r->m->normal + 3 * *v, r->m->normal + 3 * like, 3 * sizeof *r->m->normal);
    rm_commit_move(p, *v, x, g);
    return true;
}

/* The n corners of a split, active and touched. */
static void mark_corners(rm_pass *p, const uint32_t *v, int n)
{
    for (int k = 0; k < n; k++)
        p->active[v[k]] = p->touched[v[k]] = 1;
}

/* Splits needle t = (a, b, c) at the new vertex x. False when out of memory. */
static bool split(rm_pass *p, uint32_t t, const uint32_t abc[3], const double *x, const double *g)
{
    rm_mesh *r = &p->r;
    uint32_t a = abc[0], b = abc[1], c = abc[2], v;
    if (!rm_slot_reserve(r, a, 1) || !rm_slot_reserve(r, b, 1) || !rm_slot_reserve(r, c, 1) ||
        !new_vertex(p, x, g, c, 3, &v))
        return false;
    uint32_t *tri = r->m->tri + 3 * t;
    tri[0] = a, tri[1] = b, tri[2] = v;
    uint32_t t1 = add_triangle(p, t, b, c, v), t2 = add_triangle(p, t, c, a, v);
    rm_shape_changed(p, t);
    rm_shape_changed(p, t1);
    rm_shape_changed(p, t2);
    rm_cbound_copy(p, t1, t); /* within the needle: near its centroid */
    rm_cbound_copy(p, t2, t);
    rm_slot_remove(r, c, t);
    rm_slot_add(r, b, t1);
    rm_slot_add(r, c, t1);
    rm_slot_add(r, c, t2);
    rm_slot_add(r, a, t2);
    rm_slot_add(r, v, t);
    rm_slot_add(r, v, t1);
    rm_slot_add(r, v, t2);
    const uint32_t corners[4] = {a, b, c, v};
    mark_corners(p, corners, 4);
    return true;
}

/* Splits the long side bc shared by needle t = (a, b, c) and needle u = (c, b, d) (abcd the
 * quad's corners in t's winding: a, b, d, c) at the new vertex x: t becomes (a, b, x), u
 * (b, d, x), and the thin halves (d, c, x), (c, a, x) are new. False when out of memory. */
static bool split_edge(rm_pass *p, uint32_t t, uint32_t u, const uint32_t abdc[4],
                       const double *x, const double *g)
{
    rm_mesh *r = &p->r;
    uint32_t a = abdc[0], b = abdc[1], d = abdc[2], c = abdc[3], v;
    if (!rm_slot_reserve(r, a, 1) || !rm_slot_reserve(r, d, 1) || !new_vertex(p, x, g, c, 4, &v))
        return false;
    uint32_t *tt = r->m->tri + 3 * t, *tu = r->m->tri + 3 * u;
    tt[0] = a, tt[1] = b, tt[2] = v;
    tu[0] = b, tu[1] = d, tu[2] = v;
    uint32_t t1 = add_triangle(p, u, d, c, v), t2 = add_triangle(p, t, c, a, v);
    uint32_t all[4] = {t, u, t1, t2};
    for (int k = 0; k < 4; k++)
        rm_shape_changed(p, all[k]);
    rm_cbound_copy(p, t1, u);
    rm_cbound_copy(p, t2, t);
    rm_slot_remove(r, c, t);
    rm_slot_remove(r, c, u);
    rm_slot_add(r, a, t2);
    rm_slot_add(r, d, t1);
    rm_slot_add(r, c, t1);
    rm_slot_add(r, c, t2);
    for (int k = 0; k < 4; k++)
        rm_slot_add(r, v, all[k]);
    const uint32_t corners[5] = {a, b, c, d, v};
    mark_corners(p, corners, 5);
    return true;
}

/* The needle u beside needle t = (a, b, c) (as needle() reads it) across its long side bc
 * (near false: u = (c, b, d), its short edge bd) or ca (near true: u = (a, c, e), its short
 * edge ea), with the same apex c, so that the two short edges run on from each other:
 * quad gets the pair's corners in the winding, a, b, d, c or e, a, b, c; first and second
 * the needles in that order (t then u, or u then t). */
static bool partner(rm_pass *p, uint32_t t, const uint32_t abc[3], bool near, uint32_t quad[4],
                    uint32_t *first, uint32_t *second)
{
    uint32_t two[2], uabc[3], u, b = abc[near ? 0 : 1];
    int n;
    if (!rm_edge_triangles(&p->r, b, abc[2], two, &n))
        return false;
    u = two[near ? 0 : 1]; /* the triangle on the other side: runs c -> b, or a -> c */
    if (p->r.dead[u] || !(rm_tri_sine(p, u) < rm_insert_poor()) || !needle(p, u, uabc) ||
        uabc[2] != abc[2] || uabc[near ? 1 : 0] != b || uabc[near ? 0 : 1] == abc[near ? 1 : 0])
        return false;
    if (near) {
        quad[0] = uabc[0], quad[1] = abc[0], quad[2] = abc[1], quad[3] = abc[2];
        *first = u, *second = t;
    } else {
        quad[0] = abc[0], quad[1] = abc[1], quad[2] = uabc[1], quad[3] = abc[2];
        *first = t, *second = u;
    }
    return true;
}

/* Both needles t = (a, b, c) and u = (c, b, d), b between a and d on their short edges, split
 * at once at a vertex beside the chord ad (place_in_needle on (a, d, c)): the two triangles on
 * the short edges, (a, b, x) and (b, d, x), are no needles while b lies near the chord's
 * middle, and the thin halves toward c stand on a side twice as long. Beside a double curve
 * whose vertices lie much closer than the sheet's triangles are wide (coordinate-planes in the
 * irrational box: 0.0078 along the axes, apexes 0.19 away, 3,052 needles) each round of
 * splits then halves the row's vertices where one split per needle kept them all and left the
 * row's needles as thin as the first. True when split; false when the pair does not qualify
 * (t may still be split alone) or out of memory (*ok false). */
static bool split_pair(rm_pass *p, uint32_t t, uint32_t u, const uint32_t abdc[4], bool last,
                       bool *ok)
{
    const uint32_t adc[3] = {abdc[0], abdc[2], abdc[3]};
    double x[3], g[3];
    if (!place_kept(p, adc, abdc, 4, x, g))
        return false;
    /* the two triangles on the short edges get no angle under the collapses' poor level, so
     * the pair's split makes no new needle there (b at the chord's middle gives 30°; short
     * edges 1 : 2 about 19°) */
    double pair = rm_collapse_poor();
    if (!(rm_min_sine(rm_pos(p, abdc[0]), rm_pos(p, abdc[1]), x) >= pair) ||
        !(rm_min_sine(rm_pos(p, abdc[1]), rm_pos(p, abdc[2]), x) >= pair))
        return false;
    const double *c[4] = {rm_pos(p, abdc[0]), rm_pos(p, abdc[1]), rm_pos(p, abdc[2]),
                          rm_pos(p, abdc[3])};
    double own = fmax(rm_centroid_distance(p, c[0], c[1], c[3]),
                      rm_centroid_distance(p, c[3], c[1], c[2]));
    if (!place_fits(p, abdc, 4, own, x, last))
        return false;
    *ok = split_edge(p, t, u, abdc, x, g);
    return *ok;
}

/* Splits needle t (abc as needle() reads it) alone, as the header says. */
static bool split_alone(rm_pass *p, uint32_t t, const uint32_t abc[3], bool last, bool *ok)
{
    double x[3], g[3];
    if (!place_kept(p, abc, abc, 3, x, g))
        return false;
    double own = rm_centroid_distance(p, rm_pos(p, abc[0]), rm_pos(p, abc[1]), rm_pos(p, abc[2]));
    if (!place_fits(p, abc, 3, own, x, last))
        return false;
    *ok = split(p, t, abc, x, g);
    return *ok;
}

/* One sweep over the first nt triangles: each needle split with its partner, else alone;
 * *pairs gets how many pairs were split. */
static size_t insert_sweep(rm_pass *p, size_t nt, bool last, bool *ok, size_t *pairs)
{
    rm_mesh *r = &p->r;
    double poor = rm_insert_poor();
    size_t made = 0;
    *pairs = 0;
    for (size_t t = 0; t < nt && *ok; t++) {
        uint32_t abc[3];
        if (r->dead[t] || r->m->nverts >= r->cap_verts || r->m->ntris + 2 > r->cap_tris ||
            !(rm_tri_sine(p, (uint32_t)t) < poor) || !needle(p, (uint32_t)t, abc))
            continue;
        /* paired with the needle across its long side bc, else across ca, else alone */
        bool split = false;
        for (int near = 0; near < 2 && !split && *ok; near++) {
            uint32_t quad[4], first, second;
            split = partner(p, (uint32_t)t, abc, near, quad, &first, &second) &&
                    split_pair(p, first, second, quad, last, ok);
        }
        *pairs += split;
        if (split || (*ok && split_alone(p, (uint32_t)t, abc, last, ok)))
            made++;
    }
    return made;
}

size_t rm_insert_active(rm_pass *p, bool last, bool *ok)
{
    size_t made = 0, level = 0, nt = p->r.m->ntris;
    *ok = true;
    memset(p->touched, 0, p->r.cap_verts);
    for (;;) {
        size_t pairs, now = insert_sweep(p, nt, last, ok, &pairs);
        made += now;
        if (!pairs || !*ok || ++level == ISM_RM_INSERT_LEVELS)
            break;
        /* the thin halves flipped away from this level's splits (their corners, touched),
           then the next level on every triangle there is now: the pairs' rows stand over
           the last ones'; the caller flips from the last level's corners */
        rm_flip_from(p, p->touched, ok);
        if (!*ok)
            break;
        memset(p->touched, 0, p->r.cap_verts);
        nt = p->r.m->ntris;
    }
    p->inserts += made;
    return made;
}
