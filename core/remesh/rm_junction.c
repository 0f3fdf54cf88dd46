/* rm_junction.c — needles among crowded crease vertices where two or more crease sheets meet
 * (beside a junction of three: a cube's corner, the triple points of three balls, and the
 * junction itself), collapsed as one cluster (rm_junction_collapse, after the quality
 * pass's last mending). The polygoniser puts a locked vertex on such a point and others on
 * each crease around it, as close as 6e-5 where the cells are 6e-3; the needles between them
 * survive every single merge (each re-fans neighbours that are themselves 1e-4 triangles, or
 * fails the link condition across a corner's three-triangle cap): junction22's trial on the
 * pass's output found that only collapsing the whole cluster into one of its vertices leaves
 * good triangles (17.8°-23.4°, none under 10°).
 *
 * A cluster grows from a needle's edge between two locked vertices, the vertex nearest that
 * edge's middle joining first: a neighbour of the cluster (locked, or free: nearest_member), or
 * a vertex off it that its rim passes twice or not at all (the cluster wraps round it), within
 * ISM_RM_JUNCTION_REACH of the longest edge at the seed's ends; each cluster so grown, up to
 * ISM_RM_JUNCTION_MAX vertices, is tried when the ∇f normals at its rim fall into two sheets or
 * more (rm_sheets, rm_sheets.c, which also owns rm_junction_vertex, the crease merges' test).
 * Two are enough: beside the junction the crowd runs on along each crease (three-balls' own
 * box: a 6.89° needle from the lower triple point's crowd to two locked vertices 2.9e-3 apart
 * astride the first two balls' crease, 1.6e-2 out, which single merges refused too, and whose
 * collapse lets the triple point's own then keep its vertex); with three or more the member
 * nearest where the sheets meet, the junction's vertex, is the target whenever it leaves no
 * needle (it keeps the point; junction22's trial found the best target elsewhere at times), and
 * the only one when it lies on that point (ISM_RM_JUNCTION_AT). A collapse renames every
 * cluster vertex to one locked target among them (it keeps its place, on its creases) and drops
 * the triangles with two corners or more in the cluster; it is taken only when the triangles
 * touching the cluster were a disc of one label, its inner edges on no caller's locked list
 * (the curves stage's creases stay as cut), whose rim is one cycle that each new triangle spans
 * once (a disc for a disc: χ, components, cones and boundaries kept exactly), every new
 * triangle lies within ISM_RM_CREASE_FACE_DEG of its own sheet's normal (∇f at one of its outer
 * corners, not its old normal: the cluster's triangles are 1e-4 across and their normals
 * noise), bends against its outer neighbour no more than the crease angle, than it did plus
 * ISM_RM_CROWD_BEND_DEG, or than f's curvature explains (rm_bend_is_curvature), makes no crease
 * through a free vertex, raises the star's smallest angle, and puts no new centroid or midpoint
 * farther from f = 0 than the farthest there before or in the mesh as found
 * (rm_merge_distance_ok's rule). Of the clusters and targets that pass, the one with the
 * largest smallest angle is taken. */
#include "core/remesh/rm_merge.h"
#include "core/remesh/rm_pass.h"
#include "core/util/vec3.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

/* A cluster reaches at most this × the longest edge at the needle's short edge's ends from
 * that edge's middle: those edges run out of the crowd to the ring around the junction, about
 * a cell (6e-3 on three-balls, 1e-2 on the cube), where the clusters measured 7.4e-4 and
 * 2.4e-3 across (junction22); a locked vertex farther out is a crease point of the ring,
 * which the ring's triangles need. */
#define ISM_RM_JUNCTION_REACH 0.5
/* At most this many vertices in a cluster (three-balls' measured 7, the cube's corner 4). */
#define ISM_RM_JUNCTION_MAX 12
/* The triangles touching a cluster, at most this many: ISM_RM_JUNCTION_MAX vertices of
 * degree up to 8 sharing no triangle (a crowded crease vertex has 6 to 8; the fans of a
 * cluster share most of theirs). A cluster whose star is larger is grown no further (its
 * star only grows); the cone after has its own limit, ISM_RM_COLLAPSE_MAX_DEGREE. */
#define ISM_RM_JUNCTION_STAR 96

/* A cluster, its star (the triangles with a corner in it) and what a collapse into a target
 * would make of it. */
typedef struct junction {
    uint32_t v[ISM_RM_JUNCTION_MAX];
    int n;
    uint32_t star[ISM_RM_JUNCTION_STAR];
    int nstar;
    uint32_t keep[ISM_RM_COLLAPSE_MAX_DEGREE]; /* the star's triangles with one corner in it */
    int nkeep;
    rm_sheets sheet; /* the sheets of the ∇f normals at the rim (sheets()) */
} junction;

static bool in_cluster(const junction *j, uint32_t x)
{
    for (int i = 0; i < j->n; i++)
        if (j->v[i] == x)
            return true;
    return false;
}

/* Corners of triangle t in the cluster. */
static int inside(const rm_pass *p, const junction *j, uint32_t t)
{
    const uint32_t *c = p->r.m->tri + 3 * (size_t)t;
    return in_cluster(j, c[0]) + in_cluster(j, c[1]) + in_cluster(j, c[2]);
}

/* The star of the cluster into j (false when larger than ISM_RM_JUNCTION_STAR). */
static bool gather_star(const rm_pass *p, junction *j)
{
    const rm_mesh *r = &p->r;
    j->nstar = 0;
    for (int i = 0; i < j->n; i++)
        for (uint32_t s = 0; s < r->count[j->v[i]]; s++) {
            uint32_t t = rm_slot(r, j->v[i], s);
            bool have = false;
            for (int k = 0; k < j->nstar && !have; k++)
                have = j->star[k] == t;
            if (have)
                continue;
            if (j->nstar == ISM_RM_JUNCTION_STAR)
                return false;
            j->star[j->nstar++] = t;
        }
    return true;
}

/* The corner after / before x in triangle t. */
static uint32_t next_of(const ism_mesh *m, uint32_t t, uint32_t x)
{
    return m->tri[3 * (size_t)t + (rm_corner(m, t, x) + 1) % 3];
}

/* The triangles touching the cluster (its star) are one disc of one label: its inner edges
 * oriented manifold and on no locked list, χ a disc's (its vertices: the cluster's and the
 * rim's) and every vertex off the cluster on the rim, one per cone triangle. j->keep gets
 * the cone's triangles (one corner in the cluster). */
static bool star_is_disc(const rm_pass *p, junction *j)
{
    const rm_mesh *r = &p->r;
    const ism_mesh *m = r->m;
    j->nkeep = 0;
    uint32_t label = rm_label(r, j->star[0]);
    uint64_t edge[3 * ISM_RM_JUNCTION_STAR];
    uint32_t rim[3 * ISM_RM_JUNCTION_STAR];
    int ne = 0, nrim = 0;
    for (int i = 0; i < j->nstar; i++) {
        uint32_t t = j->star[i];
        const uint32_t *c = m->tri + 3 * (size_t)t;
        if (rm_label(r, t) != label)
            return false;
        if (inside(p, j, t) == 1) {
            if (j->nkeep == ISM_RM_COLLAPSE_MAX_DEGREE)
                return false;
            j->keep[j->nkeep++] = t;
        }
        for (int k = 0; k < 3; k++) {
            uint32_t a = c[k], b = c[(k + 1) % 3], two[2];
            int n, h = 0;
            if (in_cluster(j, a) || in_cluster(j, b)) { /* an inner edge */
                if (!rm_edge_triangles(r, a, b, two, &n) || rm_edge_locked(r, a, b))
                    return false;
            }
            uint64_t key = rm_edge_key(a, b);
            while (h < ne && edge[h] != key)
                h++;
            if (h == ne)
                edge[ne++] = key;
            h = 0;
            while (!in_cluster(j, a) && h < nrim && rim[h] != a)
                h++;
            if (!in_cluster(j, a) && h == nrim)
                rim[nrim++] = a;
        }
    }
    return j->n + nrim - ne + j->nstar == 1 && nrim == j->nkeep && j->nkeep >= 3;
}

/* The rim, each cone triangle's outer edge a -> b, is one cycle through j->nkeep distinct
 * vertices. */
static bool rim_is_cycle(const rm_pass *p, const junction *j)
{
    const ism_mesh *m = p->r.m;
    uint32_t from[ISM_RM_COLLAPSE_MAX_DEGREE], to[ISM_RM_COLLAPSE_MAX_DEGREE];
    for (int i = 0; i < j->nkeep; i++) {
        uint32_t t = j->keep[i], s = UINT32_MAX;
        const uint32_t *c = m->tri + 3 * (size_t)t;
        for (int k = 0; k < 3; k++)
            if (in_cluster(j, c[k]))
                s = c[k];
        from[i] = next_of(m, t, s);
        to[i] = next_of(m, t, from[i]);
        for (int k = 0; k < i; k++)
            if (from[k] == from[i] || to[k] == to[i])
                return false;
    }
    int i = 0, steps = 0;
    do {
        int k = 0;
        while (k < j->nkeep && from[k] != to[i])
            k++;
        if (k == j->nkeep)
            return false;
        i = k;
        steps++;
    } while (i != 0 && steps <= j->nkeep);
    return steps == j->nkeep;
}

/* Renaming the cluster to one vertex gives a cone over the rim, a disc for a disc: the star
 * is a disc and its rim a single cycle. j->keep gets the cone's triangles. */
static bool disc_ok(const rm_pass *p, junction *j)
{
    return star_is_disc(p, j) && rim_is_cycle(p, j);
}

/* How many sheets the ∇f normals at the rim fall into (rm_sheets_add: on a single crease
 * two, at a junction three or more); with three or more, x gets the point where the first
 * three's tangent planes meet (rm_sheets_meet): the junction, up to the sheets' curvature
 * over the rim's reach (three-balls: about 3e-5 against the cluster's 7e-4); NAN where there
 * is none. */
static int sheets(const rm_pass *p, junction *j, double x[3])
{
    j->sheet.n = 0;
    for (int i = 0; i < j->nkeep; i++) {
        const uint32_t *c = p->r.m->tri + 3 * (size_t)j->keep[i];
        for (int k = 0; k < 3; k++)
            if (!in_cluster(j, c[k]))
                rm_sheets_add(p, &j->sheet, c[k]);
    }
    if (j->sheet.n >= 3 && !rm_sheets_meet(p, &j->sheet, x))
        x[0] = x[1] = x[2] = NAN;
    return j->sheet.n;
}

/* Cone triangle t (its cluster corner s read at w's place: corners q; at s's own: o, outer
 * corners a -> b) faces its own sheet (∇f at a or b within ISM_RM_CREASE_FACE_DEG) and
 * bends against the triangle across ab no more than the crease angle, than it did plus
 * ISM_RM_CROWD_BEND_DEG, or than f's curvature explains. n gets its normal (length *ln). */
static bool cone_tri_ok(const rm_pass *p, uint32_t t, uint32_t a, uint32_t b,
                        const double *q[3], const double *o[3], double n[3], double *ln)
{
    double m[3];
    *ln = rm_cross(q[0], q[1], q[2], n);
    double lo = rm_cross(o[0], o[1], o[2], m);
    const double *ga = p->normal + 3 * (size_t)a, *gb = p->normal + 3 * (size_t)b;
    double turn = cos(ISM_RM_CREASE_FACE_DEG * M_PI / 180);
    if (!(*ln > 0) || !(fmax(rm_cos_bend(n, *ln, ga, 1), rm_cos_bend(n, *ln, gb, 1)) > turn))
        return false;
    return rm_crease_bend_ok(p, t, a, b, n, *ln, m, lo, true);
}

/* The sheet (sheets()) whose normal is nearest normal n: the one a cone triangle faces. */
static int sheet_of(const junction *j, const double *n)
{
    const double *const *g = j->sheet.normal;
    int best = 0;
    for (int h = 1; h < j->sheet.n; h++)
        if (ism_dot3(g[h], n) > ism_dot3(g[best], n))
            best = h;
    return best;
}

/* The cluster corner of cone triangle t. */
static uint32_t cluster_corner(const rm_pass *p, const junction *j, uint32_t t)
{
    const uint32_t *c = p->r.m->tri + 3 * (size_t)t;
    return in_cluster(j, c[0]) ? c[0] : in_cluster(j, c[1]) ? c[1] : c[2];
}

/* The cone over the rim with apex w (at x): the smallest sine of its triangles, or -1 when
 * one fails cone_tri_ok; n / ln get each cone triangle's normal and its length, from its
 * outer edge's first corner, *new_c / *new_m the farthest new centroid / midpoint of w's
 * edges from f = 0. */
static double cone_shape(rm_pass *p, const junction *j, const double *x,
                         double n[][3], double *ln, uint32_t *from, double *new_c,
                         double *new_m)
{
    const ism_mesh *m = p->r.m;
    double score = INFINITY;
    *new_c = *new_m = 0;
    for (int i = 0; i < j->nkeep; i++) {
        uint32_t t = j->keep[i], s = cluster_corner(p, j, t);
        uint32_t a = next_of(m, t, s), b = next_of(m, t, a);
        const double *q[3], *o[3];
        rm_merge_corners(&p->r, t, s, x, q);
        rm_merge_corners(&p->r, t, s, rm_pos(p, s), o);
        if (!cone_tri_ok(p, t, a, b, q, o, n[i], &ln[i]))
            return -1;
        score = fmin(score, rm_min_sine(q[0], q[1], q[2]));
        from[i] = a;
        *new_c = fmax(*new_c, rm_centroid_distance(p, q[0], q[1], q[2]));
        *new_m = fmax(*new_m, rm_midpoint_distance(p, x, rm_pos(p, a)));
    }
    return score;
}

/* The edges w -> x of the cone (between the cone triangle leaving x, from, and the one
 * arriving) bend at most the crease angle, or what f's curvature explains, where x is free
 * or the triangles on either side face one sheet. */
static bool spokes_ok(rm_pass *p, const junction *j, uint32_t w, const double n[][3],
                      const double *ln, const uint32_t *from)
{
    const ism_mesh *m = p->r.m;
    const double *x = rm_pos(p, w);
    for (int i = 0; i < j->nkeep; i++) {
        uint32_t t = j->keep[i], s = cluster_corner(p, j, t);
        uint32_t b = next_of(m, t, next_of(m, t, s));
        int k = 0;
        while (k < j->nkeep && from[k] != b)
            k++;
        /* a crease leaves w toward a locked x where the triangles on either side face
           different sheets: it bends as it must; a vertex locked otherwise (the box cut, a
           bend read as curvature, a crease not through w) gets the free vertex's test */
        if (k == j->nkeep ||
            (p->r.locked[b] && sheet_of(j, n[i]) != sheet_of(j, n[k])))
            continue;
        double c = rm_cos_bend(n[i], ln[i], n[k], ln[k]);
        double wb = rm_dist(x, rm_pos(p, b));
        if (!(c >= rm_crease_cos()) &&
            !(wb > 0 && rm_bend_is_curvature(p, w, b, acos(fmax(-1, fmin(1, c))),
                                             (ln[i] + ln[k]) / wb, NULL)))
            return false;
    }
    return true;
}

/* The new centroids and midpoints (farthest new_c, new_m) within what rm_distances_ok allows
 * a merge: the star's farthest before, or the mesh's as found. */
static bool cone_distances_ok(rm_pass *p, const junction *j, double new_c, double new_m)
{
    const ism_mesh *m = p->r.m;
    if (rm_distances_within(p, new_c, new_m))
        return true;
    double old_c = 0, old_m = 0;
    for (int i = 0; i < j->nstar; i++) {
        const uint32_t *c = m->tri + 3 * (size_t)j->star[i];
        const double *q[3] = {rm_pos(p, c[0]), rm_pos(p, c[1]), rm_pos(p, c[2])};
        old_c = fmax(old_c, rm_centroid_distance(p, q[0], q[1], q[2]));
        for (int k = 0; k < 3; k++)
            if (in_cluster(j, c[k]))
                old_m = fmax(old_m, rm_midpoint_distance(p, q[k], q[(k + 1) % 3]));
    }
    /* a collapse merges along creases: rm_merge_distance_ok's rule */
    return rm_distances_ok(p, new_c, new_m, old_c, old_m);
}

/* The smallest sine of the cone over the rim with apex w (a cluster vertex), or -1 when it
 * fails cone_shape, spokes_ok or cone_distances_ok. */
static double cone_score(rm_pass *p, const junction *j, uint32_t w)
{
    double n[ISM_RM_COLLAPSE_MAX_DEGREE][3], ln[ISM_RM_COLLAPSE_MAX_DEGREE];
    uint32_t from[ISM_RM_COLLAPSE_MAX_DEGREE];
    double new_c, new_m;
    double score = cone_shape(p, j, rm_pos(p, w), n, ln, from, &new_c, &new_m);
    if (score < 0 || !spokes_ok(p, j, w, (const double(*)[3])n, ln, from))
        return -1;
    return cone_distances_ok(p, j, new_c, new_m) ? score : -1;
}

/* The smallest sine of the star's triangles now. */
static double star_sine(rm_pass *p, const junction *j)
{
    double s = INFINITY;
    for (int i = 0; i < j->nstar; i++)
        s = fmin(s, rm_tri_sine(p, j->star[i]));
    return s;
}

/* Renames the cluster to w: the star's triangles with two corners or more in it die, the
 * cone's take w, the others are gone. False when out of memory (nothing changed). */
static bool collapse(rm_pass *p, const junction *j, uint32_t w)
{
    rm_mesh *r = &p->r;
    if (!rm_slot_reserve(r, w, (uint32_t)j->nkeep))
        return false;
    for (int i = 0; i < j->nstar; i++) {
        uint32_t t = j->star[i];
        uint32_t *c = r->m->tri + 3 * (size_t)t;
        for (int k = 0; k < 3; k++)
            if (!in_cluster(j, c[k]) && inside(p, j, t) > 1)
                rm_slot_remove(r, c[k], t);
        if (inside(p, j, t) > 1)
            r->dead[t] = 1;
    }
    for (int i = 0; i < j->n; i++)
        r->count[j->v[i]] = 0;
    for (int i = 0; i < j->nkeep; i++) {
        uint32_t t = j->keep[i], *c = r->m->tri + 3 * (size_t)t;
        c[rm_corner(r->m, t, cluster_corner(p, j, t))] = w;
        rm_slot_add(r, w, t);
        rm_shape_changed(p, t);
        for (int k = 0; k < 3; k++)
            p->active[c[k]] = 1, p->touched[c[k]] = 2;
    }
    for (int i = 0; i < j->n; i++) {
        uint32_t v = j->v[i];
        if (v != w)
            r->gone[v] = r->locked[v] = 1, p->active[v] = p->slide[v] = 0;
    }
    if (p->crease_tried)
        p->crease_tried[w] = NAN;
    return true;
}

/* The vertex off the cluster nearest c that the rim does not pass exactly once (the cluster
 * wraps round it, and a collapse would pinch the surface there or leave it inside), or
 * UINT32_MAX. */
static uint32_t pinched(const rm_pass *p, const junction *j, const double *c)
{
    const ism_mesh *m = p->r.m;
    uint32_t x[3 * ISM_RM_JUNCTION_STAR], best = UINT32_MAX;
    int times[3 * ISM_RM_JUNCTION_STAR], n = 0;
    for (int i = 0; i < j->nstar; i++) {
        uint32_t t = j->star[i];
        for (int k = 0; k < 3; k++) {
            uint32_t y = m->tri[3 * (size_t)t + k];
            if (in_cluster(j, y))
                continue;
            int h = 0;
            while (h < n && x[h] != y)
                h++;
            if (h == n)
                x[n] = y, times[n++] = 0;
            /* the rim leaves y in a triangle with one corner in the cluster, after it */
            times[h] += inside(p, j, t) == 1 && next_of(m, t, cluster_corner(p, j, t)) == y;
        }
    }
    for (int h = 0; h < n; h++)
        if (times[h] != 1 &&
            (best == UINT32_MAX || rm_dist(rm_pos(p, x[h]), c) < rm_dist(rm_pos(p, best), c)))
            best = x[h];
    return best;
}

/* The nearest unpinned neighbour of the cluster to c within reach, locked or free, or
 * UINT32_MAX. Free ones too: the insertions (rm_insert.c) split the needles beside a
 * junction at free vertices, and one left on the rim makes the cone's triangles there as
 * thin as before (three-balls at depth.max 5, own box: a free vertex 0.002 from the upper
 * triple point, beside its fan of 0.001-0.002 edges, every cone over the rest of its crowd
 * 0.69°-0.71° or failing; the crowd collapsed whole (the free ones simply go), none under
 * 10° there). */
static uint32_t nearest_member(const rm_pass *p, const junction *j, const double *c,
                               double reach)
{
    const rm_mesh *r = &p->r;
    uint32_t best = UINT32_MAX;
    double bd = reach;
    for (int i = 0; i < j->n; i++)
        for (uint32_t s = 0; s < r->count[j->v[i]]; s++) {
            const uint32_t *t = r->m->tri + 3 * (size_t)rm_slot(r, j->v[i], s);
            for (int k = 0; k < 3; k++) {
                uint32_t x = t[k];
                double d = rm_dist(rm_pos(p, x), c);
                if (r->locked[x] != RM_PINNED && !r->gone[x] && !in_cluster(j, x) && d <= bd)
                    bd = d, best = x;
            }
        }
    return best;
}

/* The longest edge at v: out of a crowd at a junction to the ring around it, about a cell. */
static double longest_edge(const rm_pass *p, uint32_t v)
{
    double l = 0;
    for (uint32_t i = 0; i < p->r.count[v]; i++) {
        const uint32_t *t = p->r.m->tri + 3 * (size_t)rm_slot(&p->r, v, i);
        for (int k = 0; k < 3; k++)
            l = fmax(l, rm_dist(rm_pos(p, v), rm_pos(p, t[k])));
    }
    return l;
}

/* The best collapse found so far: its cluster, target and key (choose_target). */
typedef struct choice {
    junction j;
    uint32_t target;
    double key;
} choice;

/* Scores every locked member of cluster j (ns sheets at its rim, meeting at x when three or
 * more; mid, reach: the seed's middle and the cluster's reach) as a target and keeps the
 * best in *best: the largest smallest angle over the star's now, the junction's vertex (the
 * member nearest where the sheets meet, when they meet at a point within reach) before any
 * other whenever it leaves no needle. */
static void choose_target(rm_pass *p, const junction *j, int ns, const double x[3],
                          const double mid[3], double reach, choice *best)
{
    double floor = star_sine(p, j), needle = rm_insert_poor();
    int at = ns >= 3 && rm_dist(x, mid) <= reach ? 0 : -1;
    for (int i = 1; at >= 0 && i < j->n; i++)
        if (rm_dist(rm_pos(p, j->v[i]), x) < rm_dist(rm_pos(p, j->v[at]), x))
            at = i;
    bool own = at >= 0 && rm_dist(rm_pos(p, j->v[at]), x) <= ISM_RM_JUNCTION_AT * reach;
    for (int i = 0; i < j->n; i++) {
        if (!p->r.locked[j->v[i]] || (own && i != at))
            continue; /* a free vertex is on no crease; the junction's own vertex stays */
        double s = cone_score(p, j, j->v[i]);
        /* the junction's vertex keeps the point where the sheets meet: taken whenever it
           leaves no needle, otherwise the best target */
        double key = s + (i == at && s >= needle ? 2 : 0);
        if (s > floor && key > best->key)
            best->key = key, best->j = *j, best->target = j->v[i];
    }
}

/* Grows clusters from needle t's shortest edge between two locked vertices and collapses
 * the best that passes (of at most `most` sheets: 2, or 3 for any) into its best target;
 * true when one was. *ok false when out of memory. */
static bool mend_junction(rm_pass *p, uint32_t t, int most, bool *ok)
{
    const rm_mesh *r = &p->r;
    const uint32_t *c = r->m->tri + 3 * (size_t)t;
    int e = -1;
    double shortest = INFINITY;
    for (int k = 0; k < 3; k++) {
        uint32_t a = c[k], b = c[(k + 1) % 3];
        double l = rm_dist(rm_pos(p, a), rm_pos(p, b));
        if (r->locked[a] && r->locked[b] && r->locked[a] != RM_PINNED &&
            r->locked[b] != RM_PINNED && l < shortest)
            shortest = l, e = k;
    }
    if (e < 0)
        return false;
    junction j = {.v = {c[e], c[(e + 1) % 3]}, .n = 2};
    choice best = {.key = -1, .target = UINT32_MAX};
    double mid[3];
    double reach = ISM_RM_JUNCTION_REACH * fmax(longest_edge(p, j.v[0]), longest_edge(p, j.v[1]));
    for (int k = 0; k < 3; k++)
        mid[k] = (rm_pos(p, j.v[0])[k] + rm_pos(p, j.v[1])[k]) / 2;
    for (;;) {
        double x[3];
        if (!gather_star(p, &j))
            break; /* the star only grows with the cluster */
        int ns = disc_ok(p, &j) ? sheets(p, &j, x) : 0;
        if (ns >= 2 && (most > 2 || ns == 2))
            choose_target(p, &j, ns, x, mid, reach, &best);
        if (j.n == ISM_RM_JUNCTION_MAX)
            break;
        /* the nearer of a vertex the cluster wraps round (locked or not: it lies inside) and
           the nearest neighbour */
        uint32_t y = pinched(p, &j, mid);
        uint32_t z = nearest_member(p, &j, mid, reach);
        if (y == UINT32_MAX || r->locked[y] == RM_PINNED || rm_dist(rm_pos(p, y), mid) > reach ||
            (z != UINT32_MAX && rm_dist(rm_pos(p, z), mid) < rm_dist(rm_pos(p, y), mid)))
            y = z;
        if (y == UINT32_MAX)
            break;
        j.v[j.n++] = y;
    }
    if (best.target == UINT32_MAX)
        return false;
    *ok = collapse(p, &best.j, best.target);
    return *ok;
}

/* A needle and its smallest sine, to visit the worst first. */
typedef struct seed {
    double sine;
    uint32_t t;
} seed;

static int seed_cmp(const void *x, const void *y)
{
    const seed *a = x, *b = y;
    if (a->sine != b->sine)
        return a->sine < b->sine ? -1 : 1;
    return a->t < b->t ? -1 : a->t > b->t;
}

/* The needles under 10° now, worst first (ties by index), into *s (*n of them; NULL when
 * none); false when out of memory. */
static bool needles(rm_pass *p, seed **s, size_t *n)
{
    const ism_mesh *m = p->r.m;
    double needle = rm_insert_poor();
    size_t room = 0;
    *s = NULL;
    *n = 0;
    for (size_t t = 0; t < m->ntris; t++) {
        double sine = p->r.dead[t] ? INFINITY : rm_tri_sine(p, (uint32_t)t);
        if (!(sine < needle))
            continue;
        if (*n == room) {
            room = room ? 2 * room : 64;
            seed *more = realloc(*s, room * sizeof **s);
            if (!more) {
                free(*s);
                *s = NULL;
                return false;
            }
            *s = more;
        }
        (*s)[(*n)++] = (seed){sine, (uint32_t)t};
    }
    if (*n > 1)
        qsort(*s, *n, sizeof **s, seed_cmp);
    return true;
}

/* Two sweeps over the needles, each worst first: the first collapses only clusters of two
 * sheets (the crowds along each crease beside a junction), the second any. A junction's
 * cluster can keep the junction's vertex only once the crowds beside it are gone
 * (three-balls' own box: a 6.89° needle astride the first two balls' crease 1.6e-2 from the
 * lower triple point, whose collapse lets the triple point's cluster take its vertex); the
 * sweeps make that order the rule rather than a matter of the polygoniser's numbering, as
 * is which needle seeds first within a sweep. A needle a collapse mended or removed is
 * skipped. */
size_t rm_junction_collapse(rm_pass *p, bool *ok)
{
    double needle = rm_insert_poor();
    size_t made = 0;
    for (int most = 2; most <= 3 && *ok; most++) {
        seed *s;
        size_t n;
        if (!needles(p, &s, &n)) {
            *ok = false;
            break;
        }
        for (size_t i = 0; i < n && *ok; i++)
            if (!p->r.dead[s[i].t] && rm_tri_sine(p, s[i].t) < needle &&
                mend_junction(p, s[i].t, most, ok))
                made++;
        free(s);
    }
    p->collapses += made;
    return made;
}
