/* rm_horn.c — thin tubes that end at a given point, merged into the point's vertex tip first
 * (rm_horn_tips, the quality pass's last step). Near the horn cyclide's point (a, 0, 0) its
 * two horns are tubes of radius about y²/96 at y from the point, far thinner than E there;
 * the polygoniser meshes such a tube as rings a few hundredths apart along it whose
 * circumference is far below that (a flat ribbon 0.1 E thick at y = 0.9), and no flip, move,
 * insertion or shape-raising collapse can make a good triangle of it: the pass left 105-115
 * triangles under 10° within 1.06 (19 E) of the point in each of the preset's three boxes.
 * Merging the tube's vertices into the point's vertex, nearest first, leaves a cone from the
 * point to the ring where the merges stop; every triangle a merge makes has the point as a
 * corner (v's fan is re-fanned to it), so the needles are gone or touch the singular point
 * (issue 15's exception), and nothing else changes. A cone from the point to a ring of
 * radius ρ lies within about ρ of a horn (the straight cone against a tube whose axis bends
 * like y²: ρ/4 on a straight one): each merge is measured as a collapse is (new centroids and
 * edge midpoints within the bound, rm_merge_distance_ok) and keeps the topology (the link
 * condition, counted over both cones at the point).
 *
 * What is a thin tube is measured: from each cone at the point (its fan, one sheet) the mesh
 * is walked in rings (breadth first); a ring is thin while its vertices lie within E of the
 * line from the point through the ring's centroid (its radius), and the walk stops at the
 * first ring that is not. Merges are made only up to the farthest corner of a needle (under
 * 10°, no corner at a given point or a segment's end) lying wholly in those thin rings: a
 * mesh without such needles is left as it was. The test is of thinness, not of a tube's
 * shape: near the apex of a conical point (Kummer's nodes, a pinch point, a cusp) the rings
 * within E / tan θ of it are thin too, and a needle there is merged the same way, on purpose
 * (revB 5): the cone left from the point is measured as the horn's is (its new centroids
 * and midpoints within the bound, the link condition, the end's rules), and its triangles
 * touch the point. In the gallery at the default bound only horn-cyclide's cones merge, in
 * each of cusp22's five boxes (cusp-a2's 1e-3 box did until bdac44a; under lower bounds
 * more of its boxes do).
 *
 * A cone's merges stand only while the point keeps the thinnest angle they take or make
 * (cone_settle, with the end's rules): its triangles and those of the cone's vertices within
 * reach, measured before (an over-approximation of what the merges take: cone_floor). The
 * horn's ribbon is thinner than any cone (0.003-0.03° against 0.17-0.84° left, every box of
 * the sweep); near a cusp the tube's needles are mild and the cone may not be: cusp-a2 at
 * half the default bound, irrational box, took a 4.36° fan with its needles to a 3.27° cone
 * (5.02° with the rule); under f3bfebb's far step 8.27° needles to 1.66°. Under a user's
 * bound below the default the rule undoes merges in more runs (revK 3's probe, cusp-a2,
 * merges undone: 0.7 x irr 2, 0.25 x own 11, 0.35 x own 12, 0.25 x irr 3), so --quality good
 * meshes there change with it; at the default bound it undoes none in the gallery. */
#include "core/remesh/rm_merge.h"
#include "core/remesh/rm_pass.h"
#include "core/util/vec3.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

/* A ring of more vertices than this is no thin tube's (the horn's have 3 to 10 in its three
 * boxes; a disc around a point grows by about 6 per ring): the walk stops there. */
#define RM_HORN_RING_MAX 64
/* A ring is thin while its radius is at most this × E: a cone to it then lies within about
 * E of the tube (rm_merge_distance_ok measures each merge anyway). The horn's walk stops
 * 1.8-2.0 from the point (radius y²/96 reaches E = 0.0554 at y = 2.3), its needles end at
 * 0.63-1.06. */
#define RM_HORN_THIN 1.0
/* A merge may make no triangle whose smallest angle's sine is under this (0.057°): the cone's
 * triangles, as thin as the ring's edges are short against its distance from the point
 * (the horn's: 0.17° and more), keep an area that float32 positions hold. What a cone may
 * leave above it is cone_settle's floor. */
#define RM_HORN_MIN_SINE 1e-3
/* A cone takes at most this many merges (revB 4), each asking the link condition over c's
 * fan, which may grow by RM_HORN_RING_MAX triangles at most (a thin ring's size): the horn's
 * cones take 112 / 119, 32 / 90, 39 / 42 in its own / 1e-3 / irr boxes; a tube thin within E
 * over 8 times that many merges is no horn's. It also sizes the log cone_settle undoes. */
#define RM_HORN_MERGES_MAX 1024

/* The tag of a vertex the walk saw and left out of the thin rings (or merged), and of one
 * refused since the cone's last merge. */
#define RM_HORN_OUT UINT32_MAX
#define RM_HORN_REFUSED (UINT32_MAX - 1)

/* The walk's state: per vertex the cone it was reached from (0: not seen), the thin rings'
 * vertices in order, and the current ring. */
/* One merge of a cone, as cone_settle needs it to ask the end's rules again or undo it. */
typedef struct horn_step {
    rm_merge m;
    uint32_t fan[ISM_RM_MERGE_MAX_DEGREE], nfan; /* the triangles it made */
    double floor;                                /* v's thinnest triangle before */
    uint8_t active, slide;                       /* v's marks before */
} horn_step;

typedef struct horn_walk {
    uint32_t *tag;
    uint32_t *seen; /* the point's walks' vertices in the order seen (a cone's from its start) */
    size_t nseen;
    uint32_t *refused; /* the cone's vertices refused since its last merge */
    size_t nrefused;
    horn_step *log; /* the cone's merges (RM_HORN_MERGES_MAX) */
} horn_walk;

/* A needle the merges are for: under 10°, no corner at a given point or a segment's end. */
static bool is_needle(rm_pass *p, uint32_t t)
{
    const uint32_t *c = p->r.m->tri + 3 * (size_t)t;
    return !p->r.dead[t] && rm_tri_sine(p, t) < rm_insert_poor() &&
           p->r.locked[c[0]] != RM_PINNED && p->r.locked[c[1]] != RM_PINNED &&
           p->r.locked[c[2]] != RM_PINNED;
}

/* The largest distance of the n vertices ring[] from the line from x through their
 * centroid (from x itself when the centroid is there). */
static double ring_radius(const rm_pass *p, const double *x, const uint32_t *ring, size_t n)
{
    double c[3] = {0, 0, 0}, a[3], rad = 0;
    for (size_t i = 0; i < n; i++)
        for (int k = 0; k < 3; k++)
            c[k] += rm_pos(p, ring[i])[k] / (double)n;
    for (int k = 0; k < 3; k++)
        a[k] = c[k] - x[k];
    double la = ism_norm3(a);
    for (size_t i = 0; i < n; i++) {
        double d[3], q[3];
        for (int k = 0; k < 3; k++)
            d[k] = rm_pos(p, ring[i])[k] - x[k];
        ism_cross3(d, a, q);
        rad = fmax(rad, la > 0 ? ism_norm3(q) / la : ism_norm3(d));
    }
    return rad;
}

/* Adds w's neighbours not seen yet (but the point c) to the walk under tag g. */
static void see_neighbours(const rm_pass *p, horn_walk *h, uint32_t w, uint32_t c, uint32_t g)
{
    const rm_mesh *r = &p->r;
    for (uint32_t i = 0; i < r->count[w]; i++) {
        const uint32_t *t = r->m->tri + 3 * (size_t)rm_slot(r, w, i);
        for (int k = 0; k < 3; k++)
            if (t[k] != c && !h->tag[t[k]]) {
                h->tag[t[k]] = g;
                h->seen[h->nseen++] = t[k];
            }
    }
}

/* Walks from the cone of c's triangles containing triangle t0 (tag g) ring by ring while the
 * rings are thin (radius at most thin); the thin rings' vertices keep tag g, the first ring
 * that is not (or too large) gets RM_HORN_OUT. */
static void walk_cone(const rm_pass *p, horn_walk *h, uint32_t c, uint32_t t0, uint32_t g,
                      double thin)
{
    const rm_mesh *r = &p->r;
    size_t from = h->nseen;
    /* the cone's ring: the corners of the triangles at c reached from t0 across manifold
       edges at c */
    const uint32_t *tri = r->m->tri;
    uint32_t t = t0;
    for (uint32_t steps = 0; steps <= r->count[c]; steps++) {
        int k = rm_corner(r->m, t, c);
        uint32_t a = tri[3 * t + (k + 1) % 3], b = tri[3 * t + (k + 2) % 3], two[2];
        int n;
        for (int j = 0; j < 2; j++) {
            uint32_t x = j ? b : a;
            if (!h->tag[x]) {
                h->tag[x] = g;
                h->seen[h->nseen++] = x;
            }
        }
        if (!rm_edge_triangles(r, c, a, two, &n) || two[1] == t0)
            break; /* open or back at the start */
        t = two[1];
    }
    while (h->nseen > from) {
        size_t n = h->nseen - from;
        if (n > RM_HORN_RING_MAX || ring_radius(p, rm_pos(p, c), h->seen + from, n) > thin) {
            for (size_t i = from; i < h->nseen; i++) /* kept in seen: the next point clears */
                h->tag[h->seen[i]] = RM_HORN_OUT;
            return;
        }
        size_t end = h->nseen;
        for (size_t i = from; i < end; i++)
            see_neighbours(p, h, h->seen[i], c, g);
        from = end;
    }
}

/* x is a vertex of cone g within reach of c that a later merge may take into c: a triangle
 * of it the merges make now is re-fanned again then. */
static bool pending(const rm_pass *p, const horn_walk *h, uint32_t x, uint32_t c, uint32_t g,
                    double reach)
{
    return (h->tag[x] == g || h->tag[x] == RM_HORN_REFUSED) && !p->r.locked[x] &&
           rm_dist(rm_pos(p, x), rm_pos(p, c)) <= reach;
}

/* The cone's end rules for a triangle of corners q (its corner at c where v was) that had
 * corners o (v's at v's place), outer corners a and b: no flatter than RM_HORN_MIN_SINE (or
 * floor, v's thinnest before its merge), and facing ∇f's side at a and b where it did. */
static bool end_ok(const rm_pass *p, const double *q[3], const double *o[3], uint32_t a,
                   uint32_t b, double floor)
{
    double n[3], was[3];
    rm_cross(q[0], q[1], q[2], n);
    rm_cross(o[0], o[1], o[2], was);
    if (!(rm_min_sine(q[0], q[1], q[2]) >= fmin(RM_HORN_MIN_SINE, floor)))
        return false;
    for (int j = 0; j < 2; j++) {
        const double *gn = p->normal + 3 * (size_t)(j ? b : a);
        if (ism_dot3(was, gn) > 0 && !(ism_dot3(n, gn) > 0))
            return false;
    }
    return true;
}

/* The thinnest of v's triangles now. */
static double fan_floor(rm_pass *p, uint32_t v)
{
    double floor = INFINITY;
    for (uint32_t i = 0; i < p->r.count[v]; i++)
        floor = fmin(floor, rm_tri_sine(p, rm_slot(&p->r, v, i)));
    return floor;
}

/* The merge of v into c (cone g, reach) passes: c keeps at most deg triangles, the link
 * condition, each new triangle's centroid and new edge's midpoint stay within the bound, and
 * each new triangle whose two other corners no later merge takes (the cone's end) keeps the
 * end's rules (end_ok). On the way there the tip's triangles are as thin as the ribbon
 * (sines down to 5e-5) and stand edge-on, either way, to ∇f; held to the end's rules they
 * stopped the merges at 0.54 and 0.63 of the horn's 1.06. Whether a later merge does take
 * them is known only when the cone stops: cone_settle asks the rules again then. */
static bool horn_merge_ok(rm_pass *p, const horn_walk *h, uint32_t v, uint32_t c, uint32_t g,
                          double reach, uint32_t deg, rm_merge *m, double *floor)
{
    const rm_mesh *r = &p->r;
    *floor = fan_floor(p, v);
    if (!rm_merge_find_into(r, v, c, m) || r->count[c] + r->count[v] - 4 > deg ||
        !rm_merge_link_ok(r, m))
        return false;
    for (uint32_t i = 0; i < r->count[v]; i++) {
        uint32_t t = rm_slot(r, v, i);
        const uint32_t *k = r->m->tri + 3 * (size_t)t;
        int at = rm_corner(r->m, t, v);
        uint32_t a = k[(at + 1) % 3], b = k[(at + 2) % 3];
        if (t == m->t1 || t == m->t2 || pending(p, h, a, c, g, reach) ||
            pending(p, h, b, c, g, reach))
            continue;
        const double *q[3], *o[3];
        rm_merge_corners(r, t, v, rm_pos(p, c), q);
        rm_merge_corners(r, t, v, rm_pos(p, v), o);
        if (!end_ok(p, q, o, a, b, *floor))
            return false;
    }
    return rm_merge_distance_ok(p, m);
}

/* Every triangle step s's merge made (alive: a later merge of the cone may have removed it)
 * keeps the end's rules. */
static bool step_ends_ok(rm_pass *p, const horn_step *s)
{
    const rm_mesh *r = &p->r;
    uint32_t c = s->m.w;
    for (uint32_t i = 0; i < s->nfan; i++) {
        uint32_t t = s->fan[i];
        if (r->dead[t])
            continue;
        const uint32_t *k = r->m->tri + 3 * (size_t)t;
        int at = rm_corner(r->m, t, c);
        const double *q[3], *o[3];
        rm_merge_corners(r, t, c, rm_pos(p, c), q);
        rm_merge_corners(r, t, c, rm_pos(p, s->m.v), o);
        if (!end_ok(p, q, o, k[(at + 1) % 3], k[(at + 2) % 3], s->floor))
            return false;
    }
    return true;
}

/* Step s's merge undone (the cone's last standing), v's marks as they were. */
static void undo_step(rm_pass *p, const horn_step *s)
{
    rm_merge_unapply(&p->r, &s->m, s->fan, s->nfan);
    for (uint32_t j = 0; j < s->nfan; j++)
        rm_shape_changed(p, s->fan[j]);
    rm_shape_changed(p, s->m.t1);
    rm_shape_changed(p, s->m.t2);
    p->active[s->m.v] = s->active, p->slide[s->m.v] = s->slide;
}

/* The cone's merges undone, last first, until every triangle they made keeps the end's rules
 * and c's thinnest triangle is no thinner than `floor` (cone_floor before the merges: every
 * triangle a merge makes has c as a corner); returns how many were undone. Both are asked
 * after every undo (revB 1, revK 1): a triangle let pass for a corner a later merge was to
 * take comes back when that merge is undone, for either rule, and is asked again. Each
 * triangle a merge makes has c and two outer corners: a later merge of the cone either
 * removes it (taking an outer corner into c) or leaves it as made, so the rules are asked of
 * each as its own merge left it. Both hold with no merge standing, so the loop ends. */
static size_t cone_settle(rm_pass *p, horn_step *log, size_t n, uint32_t c, double floor)
{
    size_t undone = 0;
    for (;;) {
        size_t i = 0;
        while (i < n && step_ends_ok(p, log + i))
            i++;
        if (i == n && !(fan_floor(p, c) < floor))
            return undone;
        undo_step(p, log + --n);
        undone++;
    }
}

/* The thinnest triangle the cone's merges may take or make: c's, and every triangle at a
 * vertex of cone g (the walk's, from `from` on) within reach of c. It over-approximates what
 * they take (revK 2): c's whole fan (every cone at the point), and the fans of vertices no
 * merge took (locked, refused, undone), so a thin triangle no merge touched lowers the floor.
 * The floor is measured against c's whole fan after (cone_settle), so it must hold c's other
 * cones: narrowing one side alone would undo every merge beside a thinner cone. The horn's
 * floors are its ribbon's either way (0.003-0.03°). */
static double cone_floor(rm_pass *p, const horn_walk *h, size_t from, uint32_t c, uint32_t g,
                         double reach)
{
    double floor = fan_floor(p, c);
    for (size_t i = from; i < h->nseen; i++) {
        uint32_t v = h->seen[i];
        if (h->tag[v] == g && rm_dist(rm_pos(p, v), rm_pos(p, c)) <= reach)
            floor = fmin(floor, fan_floor(p, v));
    }
    return floor;
}

/* Merges cone g's thin vertices within reach of c into c, nearest first, at most
 * RM_HORN_MERGES_MAX of them with c keeping at most RM_HORN_RING_MAX triangles more than it
 * had; returns how many stand (cone_settle, against `floor`). */
static size_t merge_cone(rm_pass *p, horn_walk *h, uint32_t c, uint32_t g, double reach,
                         double floor, bool *ok)
{
    const rm_mesh *r = &p->r;
    size_t made = 0;
    uint32_t deg = r->count[c] + RM_HORN_RING_MAX;
    h->nrefused = 0;
    while (*ok && made < RM_HORN_MERGES_MAX) {
        uint32_t best = UINT32_MAX;
        double bd = INFINITY;
        for (uint32_t i = 0; i < r->count[c]; i++) {
            const uint32_t *t = r->m->tri + 3 * (size_t)rm_slot(r, c, i);
            for (int k = 0; k < 3; k++) {
                double d = rm_dist(rm_pos(p, t[k]), rm_pos(p, c));
                if (t[k] != c && h->tag[t[k]] == g && !r->locked[t[k]] && d <= reach &&
                    d < bd)
                    bd = d, best = t[k];
            }
        }
        if (best == UINT32_MAX)
            break;
        horn_step *s = h->log + made;
        if (!horn_merge_ok(p, h, best, c, g, reach, deg, &s->m, &s->floor)) {
            h->tag[best] = RM_HORN_REFUSED; /* until a merge changes the cone */
            h->refused[h->nrefused++] = best;
            continue;
        }
        s->active = p->active[best], s->slide = p->slide[best];
        if (!(*ok = rm_merge_do(p, &s->m, s->fan, &s->nfan)))
            break;
        h->tag[best] = RM_HORN_OUT;
        made++;
        /* a vertex refused for the link condition (a neighbour of c's across the ring, which
           the walk's order reaches from the other side) may pass once its neighbours have
           gone into c */
        while (h->nrefused)
            h->tag[h->refused[--h->nrefused]] = g;
    }
    while (h->nrefused)
        h->tag[h->refused[--h->nrefused]] = RM_HORN_OUT;
    if (!*ok)
        return made;
    return made - cone_settle(p, h->log, made, c, floor);
}

/* The farthest corner from c of the needles lying wholly in cone g's thin rings (0: none). */
static double needle_reach(rm_pass *p, const horn_walk *h, size_t from, uint32_t c, uint32_t g)
{
    const rm_mesh *r = &p->r;
    double reach = 0;
    for (size_t i = from; i < h->nseen; i++) {
        uint32_t v = h->seen[i];
        if (h->tag[v] != g)
            continue;
        for (uint32_t j = 0; j < r->count[v]; j++) {
            uint32_t t = rm_slot(r, v, j);
            const uint32_t *k = r->m->tri + 3 * (size_t)t;
            if (h->tag[k[0]] == g && h->tag[k[1]] == g && h->tag[k[2]] == g &&
                is_needle(p, t))
                for (int e = 0; e < 3; e++)
                    reach = fmax(reach, rm_dist(rm_pos(p, k[e]), rm_pos(p, c)));
        }
    }
    return reach;
}

/* A triangle at c whose cone has not been walked (its corners not seen), or UINT32_MAX: asked
 * afresh after each cone, whose merges reorder c's triangles. */
static uint32_t unwalked(const rm_mesh *r, const horn_walk *h, uint32_t c)
{
    for (uint32_t j = 0; j < r->count[c]; j++) {
        uint32_t t = rm_slot(r, c, j);
        const uint32_t *k = r->m->tri + 3 * (size_t)t;
        if (!h->tag[k[(rm_corner(r->m, t, c) + 1) % 3]])
            return t;
    }
    return UINT32_MAX;
}

size_t rm_horn_tips(rm_pass *p, const ism_remesh_options *o, bool *ok)
{
    const rm_mesh *r = &p->r;
    size_t needles = 0, made = 0;
    for (size_t t = 0; o->nlocked_points && t < r->m->ntris && !needles; t++)
        needles += is_needle(p, (uint32_t)t);
    if (!needles)
        return 0;
    /* without a bound the mesh's own farthest centroid is the scale a tube is thin against */
    rm_collapse_bounds_need(p);
    double thin = RM_HORN_THIN * (p->max_error > 0 ? p->max_error : p->centroid_bound);
    size_t nv = r->m->nverts ? r->m->nverts : 1;
    horn_walk h = {calloc(nv, sizeof *h.tag), malloc(nv * sizeof *h.seen), 0,
                   malloc(nv * sizeof *h.refused), 0, malloc(RM_HORN_MERGES_MAX * sizeof *h.log)};
    uint32_t g = 0, prev = UINT32_MAX; /* the last point's vertex */
    for (size_t i = 0; h.tag && h.seen && h.refused && h.log && i < o->nlocked_points && *ok;
         i++) {
        uint32_t c = rm_point_vertex(r, o->locked_points + 3 * i);
        if (c == UINT32_MAX || r->locked[c] != RM_PINNED)
            continue;
        /* each point's walk starts afresh (revB 6): the last point's tags would keep a tube
           it saw, thin or not, from this one; the walks cost the vertices they see, at most
           the mesh's per point */
        while (h.nseen)
            h.tag[h.seen[--h.nseen]] = 0;
        if (prev != UINT32_MAX)
            h.tag[prev] = 0;
        h.tag[prev = c] = RM_HORN_OUT;
        uint32_t t0;
        while (*ok && (t0 = unwalked(r, &h, c)) != UINT32_MAX) {
            size_t from = h.nseen;
            walk_cone(p, &h, c, t0, ++g, thin);
            double reach = needle_reach(p, &h, from, c, g);
            if (reach > 0)
                made += merge_cone(p, &h, c, g, reach, cone_floor(p, &h, from, c, g, reach),
                                   ok);
        }
    }
    if (!h.tag || !h.seen || !h.refused || !h.log)
        *ok = false;
    free(h.log);
    free(h.tag);
    free(h.seen);
    free(h.refused);
    p->collapses += made;
    return made;
}
