/* sp_collapse.c — the simplification's edge collapses (sp_collapse.h). An edge with a free
 * end is tried in order of length: two free ends merge at the edge's midpoint put on f = 0
 * by Newton, then moved to its balancing offset (sp_place.h); a free end merges into a
 * locked one, which keeps its place, so feature vertices never move. A merge is taken only when
 * every test passes, cheapest first: the link condition, orientation, shape, then the
 * distances to f = 0 measured at every new centroid and edge midpoint. */
#include "core/remesh/sp_collapse.h"
#include "core/remesh/rm_bound.h"
#include "core/remesh/rm_merge.h"
#include "core/remesh/sp_place.h"
#include "core/remesh/sp_trial.h"
#include "core/util/vec3.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

/* The merged fan has at most this many triangles: valence far above the ideal 6 only comes
 * with poor angles, which the shape test refuses anyway. */
#define ISM_SP_MAX_DEGREE 16
/* A merge may not leave a triangle whose smallest angle is under both this (degrees) and the
 * smallest of the two fans before: the pass never makes the mesh's shape worse than the
 * polygoniser's, and big triangles with poor angles would block the next rounds' merges. */
#define ISM_SP_MIN_DEG 25.0
/* A new triangle turned more than this (degrees) from its old self is a fold in the making. */
#define ISM_SP_MAX_TURN_DEG 45.0
/* A new triangle's normal may differ from ∇f's at a free corner by at most this (degrees):
 * triangles within a small error of a smooth surface tilt a few degrees, a flipped or folded
 * one by far more. Locked corners are not asked (a crease's vertex carries one side's ∇f). */
#define ISM_SP_MAX_TILT_DEG 30.0
/* The merged vertex may land at most this × the edge's length from the edge's midpoint when
 * projected onto f = 0 (farther: Newton found another sheet). */
#define ISM_SP_PROJECT_MAX_REL 0.5
/* A merge measuring up to this × max_error on its own is tried with its ring settled
 * (sp_trial.h). Sphere at E = 7.9e-4 (marching cubes' 64³ error, 17,192 triangles): 4720
 * triangles without trials, 4314 / 4136 / 4024 with reach 1.15 / 1.25 / 1.4. Not 1.4: the
 * trials measuring 1.3 to 1.4 × E merged 86 of 484 times on that sphere (41 of 355 on the
 * torus at 2.4e-3) for 172K of its 1.18M evaluations of f; with the ring settled as now,
 * 1.4 -> 1.3 took the sphere's simplification from 4,072 to 4,098 triangles, the torus's
 * from 2,310 to 2,294 (callgrind bench_error mesh S E 10). */
#define ISM_SP_TRIAL_REACH 1.3
/* Edges between polls of the cancel flag. */
#define ISM_SP_POLL_EDGES 512

typedef struct edge {
    double len;
    uint32_t a, b, corner; /* corner: 3 t + k, a the triangle's corner k and b its next */
} edge;

/* e goes before f: shorter, or as long with the smaller first end. */
static bool before(const edge *e, const edge *f)
{
    return e->len < f->len || (e->len == f->len && e->a < f->a);
}

/* Sorts e[0..n) by before(), keeping the order of equal edges (as libc's merge sort did),
 * bottom-up with tmp (n edges) as the other buffer: the comparison inlined, a third of
 * qsort's instructions. Returns the buffer that holds the result. */
static edge *sort_edges(edge *e, edge *tmp, size_t n)
{
    edge *from = e, *to = tmp;
    for (size_t width = 1; width < n; width *= 2) {
        for (size_t lo = 0; lo < n; lo += 2 * width) {
            size_t mid = lo + width < n ? lo + width : n;
            size_t hi = lo + 2 * width < n ? lo + 2 * width : n;
            size_t i = lo, j = mid, k = lo;
            while (i < mid && j < hi)
                to[k++] = before(&from[j], &from[i]) ? from[j++] : from[i++];
            while (i < mid)
                to[k++] = from[i++];
            while (j < hi)
                to[k++] = from[j++];
        }
        edge *t = from;
        from = to;
        to = t;
    }
    return from;
}

bool sp_history_open(sp_history *h, const rm_pass *p)
{
    h->clock = 0;
    h->changed = calloc(p->r.cap_verts ? p->r.cap_verts : 1, sizeof *h->changed);
    h->refused = calloc(p->r.cap_tris ? 3 * p->r.cap_tris : 1, sizeof *h->refused);
    h->flipped = calloc(p->r.cap_verts ? p->r.cap_verts : 1, 1);
    return h->changed && h->refused && h->flipped;
}

void sp_history_free(sp_history *h)
{
    free(h->changed);
    free(h->refused);
    free(h->flipped);
    memset(h, 0, sizeof *h);
}

void sp_history_flips(sp_history *h, size_t nverts)
{
    h->clock++;
    for (size_t v = 0; v < nverts; v++)
        if (h->flipped[v]) {
            h->changed[v] = h->clock;
            h->flipped[v] = 0;
        }
}

/* Stamps w's fan, just made by a merge (its corners are every vertex whose fan changed). */
static void stamp_fan(const rm_pass *p, sp_history *h, uint32_t w)
{
    const rm_mesh *r = &p->r;
    h->clock++;
    for (uint32_t i = 0; i < r->count[w]; i++) {
        const uint32_t *c = r->m->tri + 3 * r->vt[r->start[w] + i];
        h->changed[c[0]] = h->changed[c[1]] = h->changed[c[2]] = h->clock;
    }
}

/* True when the edge of corner `corner` was refused and no fan at a vertex of its ends'
 * fans has changed since. */
static bool refused_still(const rm_pass *p, const sp_history *h, uint32_t corner, uint32_t a,
                          uint32_t b)
{
    const rm_mesh *r = &p->r;
    uint32_t when = h->refused[corner];
    if (!when)
        return false;
    const uint32_t ends[2] = {a, b};
    for (int e = 0; e < 2; e++)
        for (uint32_t i = 0; i < r->count[ends[e]]; i++) {
            const uint32_t *c = r->m->tri + 3 * r->vt[r->start[ends[e]] + i];
            if (h->changed[c[0]] > when || h->changed[c[1]] > when || h->changed[c[2]] > when)
                return false;
        }
    return true;
}

/* The edges with a free end and an active one (each once), not refused with nothing changed
 * around them since, shortest first; *n gets how many. NULL when out of memory. */
static edge *candidate_edges(const rm_pass *p, const sp_history *h, size_t *n)
{
    const ism_mesh *m = p->r.m;
    edge *e = malloc((3 * m->ntris + 1) * sizeof *e);
    *n = 0;
    for (size_t t = 0; e && t < m->ntris; t++) {
        const uint32_t *c = m->tri + 3 * t;
        for (int k = 0; e && !p->r.dead[t] && k < 3; k++) {
            uint32_t a = c[k], b = c[(k + 1) % 3], corner = (uint32_t)(3 * t + k);
            if (a < b && !(p->r.locked[a] && p->r.locked[b]) &&
                (p->active[a] || p->active[b]) && !refused_still(p, h, corner, a, b))
                e[(*n)++] = (edge){rm_dist(rm_pos(p, a), rm_pos(p, b)), a, b, corner};
        }
    }
    edge *tmp = e ? malloc((*n + 1) * sizeof *tmp) : NULL;
    if (tmp) {
        edge *sorted = sort_edges(e, tmp, *n);
        if (sorted != e)
            memcpy(e, sorted, *n * sizeof *e);
    } else {
        free(e);
        e = NULL;
    }
    free(tmp);
    return e;
}

/* The sine of the smallest angle of triangle t of the merged fan (g->v and g->w both read at
 * x), or -1 when it fails the orientation tests: turned from its old self, or tilted from
 * ∇f at a free corner. */
static double fan_sine(const rm_pass *p, const rm_merge *g, uint32_t t, const double *x)
{
    const uint32_t *c = p->r.m->tri + 3 * t;
    const double *q[3], *o[3];
    for (int k = 0; k < 3; k++) {
        o[k] = rm_pos(p, c[k]);
        q[k] = c[k] == g->v || c[k] == g->w ? x : o[k];
    }
    double n[3], m[3], ln = rm_cross(q[0], q[1], q[2], n), lo = rm_cross(o[0], o[1], o[2], m);
    if (!(ln > 0) || !(ism_dot3(n, m) > cos(ISM_SP_MAX_TURN_DEG * M_PI / 180) * ln * lo))
        return -1;
    for (int k = 0; k < 3; k++) {
        uint32_t u = c[k] == g->v ? g->w : c[k];
        const float *s = p->r.m->normal + 3 * (size_t)u;
        double side[3] = {s[0], s[1], s[2]}, ls = sqrt(ism_dot3(side, side));
        double sign = ism_dot3(m, side) < 0 ? -1 : 1; /* the side the old triangle faced */
        if (!p->r.locked[u] && ls > 0 &&
            !(sign * ism_dot3(n, side) > cos(ISM_SP_MAX_TILT_DEG * M_PI / 180) * ln * ls))
            return -1;
    }
    return rm_min_sine(q[0], q[1], q[2]);
}

/* The triangles the merge changes: v's (and w's when w moves), without t1 and t2. */
static uint32_t merged_fan(const rm_pass *p, const rm_merge *g, bool w_moves, uint32_t *fan)
{
    const rm_mesh *r = &p->r;
    uint32_t n = 0;
    for (int side = 0; side < 1 + w_moves; side++) {
        uint32_t u = side ? g->w : g->v;
        for (uint32_t i = 0; i < r->count[u]; i++) {
            uint32_t t = r->vt[r->start[u] + i];
            if (t != g->t1 && t != g->t2)
                fan[n++] = t;
        }
    }
    return n;
}

/* The smallest sine over the triangles of v and w before the merge. */
static double fans_min_sine(const rm_pass *p, const rm_merge *g)
{
    const rm_mesh *r = &p->r;
    double s = INFINITY;
    for (int side = 0; side < 2; side++) {
        uint32_t u = side ? g->w : g->v;
        for (uint32_t i = 0; i < r->count[u]; i++) {
            const uint32_t *c = r->m->tri + 3 * r->vt[r->start[u] + i];
            s = fmin(s, rm_min_sine(rm_pos(p, c[0]), rm_pos(p, c[1]), rm_pos(p, c[2])));
        }
    }
    return s;
}

/* Every new centroid and every edge at x within max_error. */
static bool distances_ok(rm_pass *p, const rm_merge *g, const uint32_t *fan, uint32_t n,
                         const double *x)
{
    uint32_t seen[2 * ISM_RM_MERGE_MAX_DEGREE + 2];
    uint32_t nseen = 0;
    for (uint32_t i = 0; i < n; i++) {
        const uint32_t *c = p->r.m->tri + 3 * fan[i];
        const double *q[3];
        for (int k = 0; k < 3; k++)
            q[k] = c[k] == g->v || c[k] == g->w ? x : rm_pos(p, c[k]);
        if (!rm_bound_triangle(p, q[0], q[1], q[2]))
            return false;
        for (int k = 0; k < 3; k++) {
            uint32_t u = c[k], j = 0;
            if (u == g->v || u == g->w)
                continue;
            while (j < nseen && seen[j] != u)
                j++;
            if (j < nseen)
                continue;
            seen[nseen++] = u;
            if (!rm_bound_edge(p, x, rm_pos(p, u)))
                return false;
        }
    }
    return true;
}

/* What the tests say of a merge: refused, within the bound, or a little beyond it on its own
 * (worth a trial with the ring settled, sp_trial.h). */
enum verdict { REFUSED, WITHIN, NEAR };

/* The triangles a merge changes and the smallest sine they may end with (NAN until a
 * triangle below ISM_SP_MIN_DEG asks for it). */
typedef struct merged {
    uint32_t fan[2 * ISM_RM_MERGE_MAX_DEGREE], n;
    double floor_sine;
} merged;

/* Every triangle of the merged fan with g->w at x passes orientation, and none ends with a
 * smallest angle below both ISM_SP_MIN_DEG and the smallest of v's and w's fans before —
 * those fans are measured only when a triangle is below ISM_SP_MIN_DEG (most merges refused
 * fail orientation; most taken have no angle that small). */
static bool fan_shapes_ok(const rm_pass *p, const rm_merge *g, merged *mg, const double *x)
{
    double least = INFINITY, comfort = sin(ISM_SP_MIN_DEG * M_PI / 180);
    for (uint32_t i = 0; i < mg->n; i++) {
        double s = fan_sine(p, g, mg->fan[i], x);
        if (s < 0)
            return false;
        least = fmin(least, s);
    }
    if (least >= comfort)
        return true;
    if (isnan(mg->floor_sine))
        mg->floor_sine = fmin(fans_min_sine(p, g), comfort);
    return least >= mg->floor_sine;
}

/* The shape tests of every triangle of the merged fan with g->w at x (w_moves: w's own
 * triangles change too), then the merge's link condition; *mg gets the fan. */
static bool shapes_ok(const rm_pass *p, const rm_merge *g, const double *x, bool w_moves,
                      merged *mg)
{
    mg->n = merged_fan(p, g, w_moves, mg->fan);
    mg->floor_sine = NAN;
    return fan_shapes_ok(p, g, mg, x) && rm_merge_link_ok(&p->r, g);
}

/* The distance tests of merging g->v into g->w at x, which moves to its balancing offset
 * (sp_place.h; gx gets ∇f where it lands), after shapes_ok passed near x. */
static enum verdict placed_verdict(rm_pass *p, const rm_merge *g, merged *mg, double *x,
                                   double *gx)
{
    sp_stencil s[SP_MAX_STENCILS];
    int ns = sp_stencils(p, mg->fan, mg->n, g->v, g->w, s);
    double before, after, near = ISM_SP_TRIAL_REACH * p->max_error;
    if (!ns || !sp_place(p, s, ns, near, x, gx, &before))
        return REFUSED;
    if (!fan_shapes_ok(p, g, mg, x)) /* where x ends: shape again, unmeasured */
        return REFUSED;
    if (!((after = sp_measure(p, s, ns, x, near)) <= near))
        return REFUSED;
    return after <= p->max_error ? WITHIN : NEAR;
}

/* Merges g->v into g->w, w put at x (∇f there gx, NULL when w stays); marks the new fan's
 * corners active and w busy for the rest of the round. False when out of memory. */
static bool apply(rm_pass *p, const rm_merge *g, const double *x, const double *gx)
{
    uint32_t fan[ISM_RM_MERGE_MAX_DEGREE], n;
    if (!rm_merge_apply(&p->r, g, fan, &n))
        return false;
    if (gx)
        rm_commit_move(p, g->w, x, gx);
    for (uint32_t i = 0; i < p->r.count[g->w]; i++) {
        const uint32_t *c = p->r.m->tri + 3 * p->r.vt[p->r.start[g->w] + i];
        for (int k = 0; k < 3; k++)
            p->active[c[k]] = 1;
    }
    p->touched[g->w] = 1;
    p->active[g->v] = p->slide[g->v] = 0;
    p->collapses++;
    return true;
}

/* Merges g->v into g->w at x as the verdict allows: within the bound at once; near it, only
 * when the ring settles within it (else everything is put back). True when merged. */
static bool merge(rm_pass *p, const rm_merge *g, enum verdict verdict, const double *x,
                  const double *gx, bool *ok)
{
    if (verdict == WITHIN)
        return *ok = apply(p, g, x, gx);
    sp_snapshot s;
    if (verdict != NEAR || !sp_snapshot_take(p, g, &s))
        return false;
    if (!(*ok = apply(p, g, x, gx)))
        return false;
    if (sp_ring_settle(p, &s, g->w))
        return true;
    sp_snapshot_restore(p, &s);
    return false;
}

/* Free v into locked w, which keeps its place, when every test passes. */
static bool into(rm_pass *p, uint32_t v, uint32_t w, bool *ok)
{
    rm_merge g;
    if (!rm_merge_find(&p->r, v, w, ISM_SP_MAX_DEGREE, &g))
        return false;
    double x[3] = {rm_pos(p, w)[0], rm_pos(p, w)[1], rm_pos(p, w)[2]};
    merged mg;
    enum verdict vd = shapes_ok(p, &g, x, false, &mg) && distances_ok(p, &g, mg.fan, mg.n, x)
                          ? WITHIN
                          : REFUSED;
    return merge(p, &g, vd, x, NULL, ok);
}

/* Both ends free: merged at the midpoint put on f = 0, then placed from there. The shapes
 * are tested at the midpoint, before Newton evaluates anything (gyroid-ball: 3 merges in 4
 * fail them), and again where the merged vertex ends. */
static bool at_middle(rm_pass *p, uint32_t a, uint32_t b, bool *ok)
{
    rm_merge g;
    merged mg;
    const double *A = rm_pos(p, a), *B = rm_pos(p, b);
    double len = rm_dist(A, B), x[3], mid[3], gx[3];
    for (int k = 0; k < 3; k++)
        x[k] = mid[k] = 0.5 * (A[k] + B[k]);
    if (!rm_merge_find(&p->r, a, b, ISM_SP_MAX_DEGREE, &g) || p->r.locked[b] ||
        !shapes_ok(p, &g, mid, true, &mg) || !rm_project(p, x, len, -1, gx) ||
        !(rm_dist(x, mid) <= ISM_SP_PROJECT_MAX_REL * len))
        return false;
    return merge(p, &g, placed_verdict(p, &g, &mg, x, gx), x, gx, ok);
}

static bool collapse_edge(rm_pass *p, uint32_t a, uint32_t b, bool *ok)
{
    const uint8_t *locked = p->r.locked;
    if (!locked[a] && !locked[b]) /* into either end's place: 0.8% fewer merges, 15% more work */
        return at_middle(p, a, b, ok);
    return locked[a] ? into(p, b, a, ok) : into(p, a, b, ok);
}

size_t sp_collapse_round(rm_pass *p, sp_history *h, const volatile int *cancel, bool *ok)
{
    size_t n, made = 0;
    edge *e = candidate_edges(p, h, &n);
    *ok = e != NULL;
    memset(p->touched, 0, p->r.cap_verts);
    memset(p->active, 0, p->r.cap_verts);
    for (size_t i = 0; *ok && i < n; i++) {
        if (i % ISM_SP_POLL_EDGES == 0 && cancel && *cancel)
            break;
        uint32_t a = e[i].a, b = e[i].b;
        if (p->r.gone[a] || p->r.gone[b] || p->touched[a] || p->touched[b])
            continue;
        if (collapse_edge(p, a, b, ok)) {
            made++;
            stamp_fan(p, h, p->r.gone[a] ? b : a);
        } else {
            h->refused[e[i].corner] = h->clock;
        }
    }
    free(e);
    return made;
}
