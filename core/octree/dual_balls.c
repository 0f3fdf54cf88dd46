/* dual_balls.c — the holes, the clip and the apex fans of the dual mesh round isolated
 * singular points (the design and its figure: dual_balls.h). */
#include "core/octree/dual_balls.h"
#include "core/octree/edge_keys.h"
#include "core/octree/dual_crease.h"
#include "core/octree/sample_dist.h"
#include "core/util/grow.h"
#include "core/util/vec3.h"

#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

/* The clip sphere stays below this share of the point's clearance (two balls then never
 * meet: 2 × 0.45 < 1) and below this share of its distance to the box (the clip never
 * reaches the box's faces, where the dual mesher checks the surface apart). */
#define LIMIT_CLEAR 0.45
#define LIMIT_BOX 0.9
/* Nodes meeting the hole are split while larger than r0 / HOLE_LEAVES, and so are those
 * meeting the grading ball of GRADE r0: the hole's neighbours are then no larger than a
 * hole leaf, so a rim vertex lies within r0 + 2 √3 r0 / HOLE_LEAVES = 2.73 r0 of the point
 * and the clip sphere (just beyond the rim) within RIM_REACH r0 of it. */
#define HOLE_LEAVES 2.0
#define GRADE 2.0
#define RIM_REACH 2.8
/* A fan triangle's sag is its rim chord's: a chord of a leaf (r0 / 2) on the nappe's
 * section (radius ~ 0.7 × 2.5 r0 on a right cone) sags r0 / 57, the triangle's centroid
 * about two thirds of that, and the nappes bend off their rulings on top: r0 starts at
 * FAN_E × E (a miss halves the ball). Kummer's quartic (mu2 = 2/3, 4 nodes) at E 1e-3 missed
 * at 48 E in every ball and met it at 24 E. */
#define FAN_E 24.0
/* The clip sphere lies this much beyond the farthest rim vertex (relative), so no rim
 * vertex sits on it. */
#define RIM_MARGIN 1e-3
/* A chord between two vertices just outside a clip sphere dips into it (by L² / 8 r1 for a
 * chord of length L): the sphere then grows to the farther end's distance, at most this
 * many times (each a scan of the triangles), before the ball counts as bad and shrinks.
 * (kummer-4-nodes off the lattice still makes one or two meshes again at 1e-2 / 3e-3 /
 * 1e-3: there the rim itself reaches the limit, the nappes a cell apart along the nodes'
 * flat directions up to 0.2 from them; half the ball then fits.) */
#define SETTLE_STEPS 8
/* Rings between a rim and its apex the fans may take (fan_ball) before the ball halves: each
 * ring shortens the rulings' pieces to 1 / (rings + 1). */
#define FAN_RINGS 2
/* Newton steps moving a cut point onto f = 0 (a cut lies on a chord within E of f = 0:
 * two steps reach far below E; more only where ∇f is small). */
#define CUT_NEWTON 4
/* A triangle whose normal makes an angle past 90° with ∇f at its centroid is turned over:
 * it misses like a triangle beyond E (ism_dual_centroid_within; the dual mesh then splits
 * its leaves, a fan shrinks its ball). */
#define TURNED_COS 0.0

void ism_dual_ball_make(ism_dual_ball *b, const double pt[5], const double box[6],
                        double max_error, int shrink)
{
    double to_box = INFINITY;
    for (int a = 0; a < 3; a++)
        to_box = fmin(to_box, fmin(pt[a] - box[a], box[a + 3] - pt[a]));
    memcpy(b->p, pt, sizeof b->p);
    b->limit = fmin(LIMIT_CLEAR * pt[3], LIMIT_BOX * to_box);
    b->r0 = ldexp(fmin(b->limit / RIM_REACH, FAN_E * max_error), -shrink);
    b->leaf = b->r0 / HOLE_LEAVES;
    b->nappes = (int)pt[4];
}

/* The cover's cells: at most this many along an axis (the balls' limits set the side; a
 * tiny limit would make the grid huge for no gain: a cell then lists one ball or none). */
#define COVER_MAX_DIM 64
/* A limit's bounding box is filed this much larger (relative): the tests compare squared
 * distances, the filing coordinates; rounding differs by ulps. */
#define COVER_ROUNDING 1e-9

/* The cell along axis a holding coordinate x, clamped to the grid: the one map from
 * coordinates to cells (filing and asking agree, monotone in x). */
static inline int32_t cover_index(const ism_dual_ball_cover *c, int a, double x)
{
    double t = (x - c->lo[a]) * c->inv;
    return t >= 0 ? (t < c->dim[a] ? (int32_t)t : c->dim[a] - 1) : 0;
}

void ism_dual_ball_cover_init(ism_dual_ball_cover *c, const ism_dual_ball *b, size_t n)
{
    memset(c, 0, sizeof *c);
    double reach = 0, width = 0, box[6] = {INFINITY, INFINITY, INFINITY, -INFINITY, -INFINITY,
                                           -INFINITY};
    for (size_t k = 0; k < n; k++) { /* the node tests reach GRADE r0 < limit (RIM_REACH) */
        reach = reach > b[k].limit ? reach : b[k].limit;
        for (int a = 0; a < 3; a++) {
            box[a] = fmin(box[a], b[k].p[a] - 2 * b[k].limit);
            box[a + 3] = fmax(box[a + 3], b[k].p[a] + 2 * b[k].limit);
        }
    }
    for (int a = 0; a < 3; a++)
        width = width > box[a + 3] - box[a] ? width : box[a + 3] - box[a];
    if (!n || !(reach > 0) || !isfinite(reach) || !(width > 0) || !isfinite(width) ||
        n > UINT32_MAX)
        return; /* no grid: every ball asked */
    double cell = fmax(reach, width / COVER_MAX_DIM); /* > 0 and finite: reach and width are */
    size_t cells = 1;
    for (int a = 0; a < 3; a++) {
        c->lo[a] = box[a];
        c->dim[a] = (int32_t)ceil((box[a + 3] - box[a]) / cell);
        c->dim[a] = c->dim[a] < 1 ? 1 : c->dim[a] > COVER_MAX_DIM ? COVER_MAX_DIM : c->dim[a];
        cells *= (size_t)c->dim[a];
    }
    c->start = calloc(cells + 1, sizeof *c->start);
    if (!c->start) {
        ism_dual_ball_cover_free(c);
        return;
    }
    c->cell = cell;
    c->inv = 1 / cell;
    size_t total = 0;
    for (int pass = 0; pass < 2; pass++) {
        for (size_t k = 0; k < n; k++) {
            int32_t s0[3], s1[3];
            double r = b[k].limit * (1 + COVER_ROUNDING);
            for (int a = 0; a < 3; a++) { /* the cells the limit's bounding box meets */
                s0[a] = cover_index(c, a, b[k].p[a] - r);
                s1[a] = cover_index(c, a, b[k].p[a] + r);
            }
            for (int32_t z = s0[2]; z <= s1[2]; z++)
                for (int32_t y = s0[1]; y <= s1[1]; y++)
                    for (int32_t x = s0[0]; x <= s1[0]; x++) {
                        size_t at = ((size_t)z * c->dim[1] + y) * c->dim[0] + x;
                        if (pass)
                            c->idx[c->start[at]++] = (uint32_t)k; /* ascending k */
                        else
                            c->start[at + 1]++, total++;
                    }
        }
        if (pass)
            break;
        for (size_t i = 0; i < cells; i++) /* counts -> starts (shifted: filled by pass 1) */
            c->start[i + 1] += c->start[i];
        c->idx = malloc((total ? total : 1) * sizeof *c->idx);
        if (!c->idx) {
            ism_dual_ball_cover_free(c);
            return;
        }
    }
    for (size_t i = cells; i > 0; i--) /* pass 1 moved each start to its cell's end */
        c->start[i] = c->start[i - 1];
    c->start[0] = 0;
}

void ism_dual_ball_cover_free(ism_dual_ball_cover *c)
{
    free(c->start);
    free(c->idx);
    memset(c, 0, sizeof *c);
}

/* The balls box lo..hi asks: the list of the one cell holding it into *first (length into
 * *len; none when the box lies off the grid, which holds every limit), or false when it
 * spans cells, reaches off the grid or there is none (ask all). */
static bool cover_cell(const ism_dual_ball_cover *c, const double lo[3], const double hi[3],
                       const uint32_t **first, size_t *len)
{
    if (!c || !(c->cell > 0))
        return false;
    size_t at = 0;
    bool off = false, span = false;
    for (int a = 2; a >= 0; a--) {
        double l = (lo[a] - c->lo[a]) * c->inv, h = (hi[a] - c->lo[a]) * c->inv;
        off |= h < 0 || l >= c->dim[a];
        span |= !(l >= 0 && h < c->dim[a]) || (int32_t)l != (int32_t)h;
        at = at * (size_t)c->dim[a] + (size_t)cover_index(c, a, lo[a]);
    }
    if (!off && span)
        return false;
    *first = c->idx + (off ? 0 : c->start[at]);
    *len = off ? 0 : c->start[at + 1] - c->start[at];
    return true;
}

/* Ball k of the n asked for box lo..hi: the cover's list when it has one, else all. */
typedef struct ball_scan {
    const uint32_t *list;
    size_t n;
    bool listed;
} ball_scan;

static ball_scan scan_of(const ism_dual_ball_cover *c, size_t n, const double lo[3],
                         const double hi[3])
{
    ball_scan s = {NULL, n, false};
    s.listed = cover_cell(c, lo, hi, &s.list, &s.n);
    return s;
}

static inline size_t scan_at(const ball_scan *s, size_t i)
{
    return s->listed ? s->list[i] : i;
}

int ism_dual_balls_node(const ism_dual_ball *b, size_t n, const ism_dual_ball_cover *cv,
                        const double lo[3], const double hi[3], double size, bool at_max)
{
    ball_scan sc = scan_of(cv, n, lo, hi);
    for (size_t i = 0; i < sc.n; i++) {
        size_t k = scan_at(&sc, i);
        double d2 = ism_sqdist_box3(b[k].p, lo, hi);
        if (d2 <= b[k].r0 * b[k].r0)
            return size <= b[k].leaf || at_max ? 1 : 0;
        if (d2 <= GRADE * GRADE * b[k].r0 * b[k].r0 && size > b[k].leaf && !at_max)
            return 0;
    }
    return -1;
}

bool ism_dual_balls_near(const ism_dual_ball *b, size_t n, const ism_dual_ball_cover *cv,
                         const double lo[3], const double hi[3], double size)
{
    ball_scan sc = scan_of(cv, n, lo, hi);
    for (size_t i = 0; i < sc.n; i++) {
        size_t k = scan_at(&sc, i);
        if (size <= b[k].leaf && ism_sqdist_box3(b[k].p, lo, hi) < b[k].limit * b[k].limit)
            return true;
    }
    return false;
}

/* ---- edges of the mesh, by sorting ------------------------------------------------------ */

/* The first ball whose limit holds p, or n when none does. */
static size_t limit_ball(const ism_dual_ball *b, size_t n, const ism_dual_ball_cover *cv,
                         const double p[3])
{
    ball_scan sc = scan_of(cv, n, p, p);
    for (size_t i = 0; i < sc.n; i++) {
        size_t k = scan_at(&sc, i);
        if (ism_sqdist3(p, b[k].p) < b[k].limit * b[k].limit)
            return k;
    }
    return n;
}

/* The mesh's edges with an end within a ball's limit, sorted, into *e (*ne of them); false
 * when out of memory. Every such edge's triangles share that end, so each is counted with
 * all its triangles; the edges farther off are the dual mesh's own, closed (dual.h), and
 * the clip never touches them (the rims lie within the limits: clip_radii). Sorting only
 * these, not the whole mesh: kummer-4-nodes 1e-3, 117M -> M instructions for the clip and
 * fans. */
static bool sorted_edges(const ism_mesh *m, const ism_dual_ball *b, size_t n,
                         const ism_dual_ball_cover *cv, ism_edge_ref **e, size_t *ne)
{
    uint8_t *near = malloc(m->nverts + 1);
    *e = malloc((3 * m->ntris + 1) * sizeof **e);
    *ne = 0;
    if (!near || !*e) {
        free(near);
        free(*e);
        *e = NULL;
        return false;
    }
    for (size_t v = 0; v < m->nverts; v++)
        near[v] = limit_ball(b, n, cv, m->pos + 3 * v) < n;
    for (size_t t = 0; t < m->ntris; t++)
        for (int k = 0; k < 3; k++) {
            uint32_t u = m->tri[3 * t + k], w = m->tri[3 * t + (k + 1) % 3];
            if (near[u] || near[w])
                (*e)[(*ne)++] = (ism_edge_ref){ism_edge_key(u, w), (uint32_t)(3 * t + k)};
        }
    free(near);
    qsort(*e, *ne, sizeof **e, ism_edge_ref_order);
    return true;
}

/* ---- the clip --------------------------------------------------------------------------- */

typedef struct clip {
    ism_mesh *m;
    ism_sampler *s;
    const ism_dual_ball *b;
    size_t n;
    double *r1;        /* per ball: the clip sphere's radius (0: nothing to clip) */
    uint32_t *ball;    /* per vertex of the dual mesh: the ball whose sphere holds it, or n */
    uint8_t *shrink;   /* per ball: 1 when it is to be halved (the caller's) */
    bool marked;       /* a ball was marked in shrink */
    uint64_t *cut;     /* sorted undirected edges cut by a sphere */
    uint32_t *cutv;    /* their cut points' vertices */
    size_t ncut, capcut;
    const ism_dual_ball_cover *cover; /* the caller's: the balls by their limits (every r1
                                         stays below: marked) */
    uint32_t *tri;     /* the triangles kept or made */
    size_t nt, capt;
    uint32_t *rim;     /* directed rim edges (from, to, ball) */
    size_t nrim, caprim;
    size_t nv0;        /* the dual mesh's own vertices: 0..nv0, then the cut points */
    double *chord;     /* per cut point: where its edge crosses the sphere (before Newton) */
    bool nomem;
} clip;

/* Appends k records of 3 words (triangles, rim edges) to *a holding *n of them. */
static bool push(uint32_t **a, size_t *n, size_t *cap, const uint32_t *v, size_t k)
{
    if (!ism_grow((void **)a, cap, *n + k, 3 * sizeof **a, 256))
        return false;
    memcpy(*a + 3 * *n, v, 3 * k * sizeof *v);
    *n += k;
    return true;
}

/* c->ball for the dual mesh's vertices; false when out of memory. */
static bool find_balls(clip *c)
{
    c->ball = malloc((c->m->nverts + 1) * sizeof *c->ball);
    if (!c->ball)
        return false;
    for (size_t v = 0; v < c->m->nverts; v++) {
        const double *p = c->m->pos + 3 * v;
        ball_scan sc = scan_of(c->cover, c->n, p, p);
        size_t k = c->n;
        for (size_t i = 0; i < sc.n && k == c->n; i++) {
            size_t j = scan_at(&sc, i);
            if (c->r1[j] > 0 && ism_sqdist3(p, c->b[j].p) < c->r1[j] * c->r1[j])
                k = j;
        }
        c->ball[v] = (uint32_t)k;
    }
    return true;
}

/* Does segment a-b, both ends at least r from p, come within r of p (a chord dipping into
 * the sphere)? An edge with an end within r is not one: during a scan the end lies in the
 * sphere grown so far, and the next scan cuts its edges. Counting such edges made each
 * growth swallow the next ring of vertices within one scan (the spindle torus at E 1e-2 in
 * the irrational box: r1 0.18 -> 0.83 across the outer nappe, beyond the ball's limit, the
 * ball halved to where the mesh misses E at depth.max: error_at_max_depth). */
static bool segment_dips(const double a[3], const double b[3], const double p[3], double r)
{
    if (ism_sqdist3(a, p) < r * r || ism_sqdist3(b, p) < r * r)
        return false;
    double d[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]};
    double w[3] = {p[0] - a[0], p[1] - a[1], p[2] - a[2]};
    double dd = ism_dot3(d, d), t = dd > 0 ? fmin(1, fmax(0, ism_dot3(w, d) / dd)) : 0;
    double q[3] = {a[0] + t * d[0], a[1] + t * d[1], a[2] + t * d[2]};
    return ism_sqdist3(q, p) < r * r;
}

/* Ball k marked to be halved. */
static void mark(clip *c, size_t k)
{
    c->shrink[k] = 1;
    c->marked = true;
}

/* The clip spheres grown until no edge with both ends outside one dips into it (up to
 * SETTLE_STEPS scans; never to a ball's limit: such balls, and those still growing after
 * the last scan, are marked), and c->ball found for them. */
static enum ism_fan_status settle_radii(clip *c)
{
    const ism_mesh *m = c->m;
    uint8_t *grew = malloc(c->n + 1);
    if (!grew)
        return ISM_FAN_NO_MEMORY;
    for (int step = 0;; step++) {
        free(c->ball);
        if (!find_balls(c)) {
            free(grew);
            return ISM_FAN_NO_MEMORY;
        }
        bool grown = false;
        memset(grew, 0, c->n);
        for (size_t t = 0; t < m->ntris; t++)
            for (int j = 0; j < 3; j++) {
                uint32_t a = m->tri[3 * t + j], b = m->tri[3 * t + (j + 1) % 3];
                if (c->ball[a] < c->n || c->ball[b] < c->n)
                    continue;
                const double *pa = m->pos + 3 * (size_t)a, *pb = m->pos + 3 * (size_t)b;
                double lo[3], hi[3];
                for (int q = 0; q < 3; q++) {
                    lo[q] = pa[q] < pb[q] ? pa[q] : pb[q];
                    hi[q] = pa[q] < pb[q] ? pb[q] : pa[q];
                }
                ball_scan sc = scan_of(c->cover, c->n, lo, hi);
                for (size_t i = 0; i < sc.n; i++) {
                    size_t k = scan_at(&sc, i);
                    if (c->r1[k] > 0 && !c->shrink[k] &&
                        segment_dips(pa, pb, c->b[k].p, c->r1[k])) {
                        double far = fmax(ism_sqdist3(pa, c->b[k].p), ism_sqdist3(pb, c->b[k].p));
                        c->r1[k] = fmax(c->r1[k], sqrt(far) * (1 + RIM_MARGIN));
                        grown = true;
                        grew[k] = 1;
                        if (!(c->r1[k] < c->b[k].limit))
                            mark(c, k);
                    }
                }
            }
        if (!grown || step == SETTLE_STEPS || c->marked) {
            for (size_t k = 0; grown && step == SETTLE_STEPS && k < c->n; k++)
                if (grew[k])
                    mark(c, k);
            free(grew);
            return c->marked ? ISM_FAN_BAD : ISM_FAN_OK;
        }
    }
}


/* x moved onto f = 0 by Newton (CUT_NEWTON steps at most; it stays where ∇f vanishes). */
static void onto_surface(ism_sampler *s, double x[3])
{
    for (int it = 0; it < CUT_NEWTON; it++) {
        double g[3], f = ism_sample_grad(s, x, g), gg = ism_dot3(g, g);
        if (!isfinite(f) || !(gg > 0))
            break;
        for (int j = 0; j < 3; j++)
            x[j] -= f * g[j] / gg;
    }
}

/* The point where edge a (inside ball k's sphere) - b (outside) crosses it into chord, and
 * into out moved onto f = 0 by Newton. */
static void cut_point(clip *c, size_t k, uint32_t a, uint32_t b, double chord[3], double out[3])
{
    const double *pa = c->m->pos + 3 * (size_t)a, *pb = c->m->pos + 3 * (size_t)b;
    const double *p = c->b[k].p;
    double d[3] = {pb[0] - pa[0], pb[1] - pa[1], pb[2] - pa[2]};
    double w[3] = {pa[0] - p[0], pa[1] - p[1], pa[2] - p[2]};
    /* |w + t d|² = r1²: the root in (0, 1) */
    double A = ism_dot3(d, d), B = ism_dot3(w, d), C = ism_dot3(w, w) - c->r1[k] * c->r1[k];
    double t = (-B + sqrt(fmax(0, B * B - A * C))) / A;
    t = fmin(1, fmax(0, t));
    for (int j = 0; j < 3; j++)
        chord[j] = out[j] = pa[j] + t * d[j];
    onto_surface(c->s, out);
}

/* The vertex at the cut of edge a-b (made in collect_cuts). */
static uint32_t cut_vertex(const clip *c, uint32_t a, uint32_t b)
{
    return ism_edge_key_vertex(c->cut, c->cutv, c->ncut, a, b);
}

/* Every edge with one end inside a sphere and one outside gets its cut vertex (once). */
static enum ism_fan_status collect_cuts(clip *c)
{
    ism_mesh *m = c->m;
    for (size_t t = 0; t < m->ntris; t++)
        for (int j = 0; j < 3; j++) {
            uint32_t a = m->tri[3 * t + j], b = m->tri[3 * t + (j + 1) % 3];
            size_t ka = c->ball[a], kb = c->ball[b];
            if (ka == kb)
                continue;
            if (ka < c->n && kb < c->n) { /* an edge from one ball into another */
                mark(c, ka);
                mark(c, kb);
                continue;
            }
            if (!ism_grow((void **)&c->cut, &c->capcut, c->ncut + 1, sizeof *c->cut, 256))
                return ISM_FAN_NO_MEMORY;
            c->cut[c->ncut++] = ism_edge_key(a, b);
        }
    if (c->marked)
        return ISM_FAN_BAD;
    /* an isolated point alone cuts nothing: c->cut is NULL */
    size_t u = c->ncut = ism_edge_keys_unique(c->cut, c->ncut);
    c->cutv = malloc((u ? u : 1) * sizeof *c->cutv);
    c->chord = malloc((u ? u : 1) * 3 * sizeof *c->chord);
    if (!c->cutv || !c->chord)
        return ISM_FAN_NO_MEMORY;
    for (size_t i = 0; i < u; i++) {
        uint32_t a = (uint32_t)(c->cut[i] >> 32), b = (uint32_t)c->cut[i];
        size_t ka = c->ball[a];
        double q[3], g[3];
        if (ka < c->n)
            cut_point(c, ka, a, b, &c->chord[3 * i], q);
        else
            cut_point(c, c->ball[b], b, a, &c->chord[3 * i], q);
        ism_sample_grad(c->s, q, g);
        ism_normalise3(g);
        float nrm[3] = {(float)g[0], (float)g[1], (float)g[2]};
        c->cutv[i] = ism_mesh_add_vertex(m, q, nrm); /* nv0 + i */
        if (c->cutv[i] == UINT32_MAX)
            return ISM_FAN_NO_MEMORY;
    }
    return ISM_FAN_OK;
}

/* Triangle t kept, dropped or cut; its edges on a sphere into the rim. */
static enum ism_fan_status clip_triangle(clip *c, size_t t)
{
    const uint32_t *v = c->m->tri + 3 * t;
    size_t kb[3];
    int in = 0;
    for (int j = 0; j < 3; j++) {
        kb[j] = c->ball[v[j]];
        in += kb[j] < c->n;
    }
    if (in == 0) /* no edge of it dips into a sphere (settle_radii) */
        return push(&c->tri, &c->nt, &c->capt, v, 1) ? ISM_FAN_OK : ISM_FAN_NO_MEMORY;
    if (in == 3)
        return ISM_FAN_OK;
    /* rotate so that corner 0 is the odd one out (inside when in = 1, outside when 2) */
    int r = 0;
    for (int j = 0; j < 3; j++)
        if ((kb[j] < c->n) == (in == 1))
            r = j;
    uint32_t a = v[r], b = v[(r + 1) % 3], d = v[(r + 2) % 3];
    size_t k = kb[r] < c->n ? kb[r] : kb[(r + 1) % 3];
    uint32_t xab = cut_vertex(c, a, b), xda = cut_vertex(c, d, a);
    bool ok;
    if (in == 1) { /* b, d outside: the quad b d xda xab */
        uint32_t q[6] = {b, d, xda, b, xda, xab}, e[3] = {xda, xab, (uint32_t)k};
        ok = push(&c->tri, &c->nt, &c->capt, q, 2) && push(&c->rim, &c->nrim, &c->caprim, e, 1);
    } else { /* a outside: the triangle a xab xda */
        uint32_t q[3] = {a, xab, xda}, e[3] = {xab, xda, (uint32_t)k};
        ok = push(&c->tri, &c->nt, &c->capt, q, 1) && push(&c->rim, &c->nrim, &c->caprim, e, 1);
    }
    return ok ? ISM_FAN_OK : ISM_FAN_NO_MEMORY;
}

/* The clip spheres: just beyond each ball's farthest rim vertex (the ends of the mesh's
 * boundary edges round it); BAD when a boundary vertex is near no ball (nothing marked:
 * no ball can help) or a rim reaches past its ball's limit (marked). */
static enum ism_fan_status clip_radii(clip *c, const ism_edge_ref *e, size_t ne)
{
    for (size_t i = 0; i < ne;) {
        size_t j = ism_edge_run_end(e, ne, i);
        if (j - i == 1) { /* a boundary edge: the rim of a hole */
            uint32_t ends[2] = {(uint32_t)(e[i].key >> 32), (uint32_t)e[i].key};
            for (int h = 0; h < 2; h++) {
                const double *p = c->m->pos + 3 * (size_t)ends[h];
                size_t k = limit_ball(c->b, c->n, c->cover, p);
                if (k == c->n)
                    return ISM_FAN_BAD;
                c->r1[k] = fmax(c->r1[k], sqrt(ism_sqdist3(p, c->b[k].p)) * (1 + RIM_MARGIN));
                if (!(c->r1[k] < c->b[k].limit))
                    mark(c, k);
            }
        }
        i = j;
    }
    return c->marked ? ISM_FAN_BAD : ISM_FAN_OK;
}

/* Rim edges of ball k chained into loops: each rim vertex starts one edge and ends one.
 * Returns the loops, or -1 when the rim is not a union of loops. */
static long count_loops(const clip *c, size_t k, const uint32_t *next_of, uint8_t *seen)
{
    long loops = 0;
    for (size_t i = 0; i < c->nrim; i++) {
        if (c->rim[3 * i + 2] != k || seen[i])
            continue;
        size_t at = i, steps = 0;
        while (!seen[at] && steps <= c->nrim) {
            seen[at] = 1;
            steps++;
            uint32_t to = c->rim[3 * at + 1];
            at = next_of[to];
            if (at == UINT32_MAX)
                return -1;
        }
        if (at != i)
            return -1; /* a chain that closes on another edge than it started from */
        loops++;
    }
    return loops;
}

void ism_dual_centroid(const double *p[3], double c[3])
{
#pragma GCC unroll 3
    for (int a = 0; a < 3; a++)
        c[a] = (p[0][a] + p[1][a] + p[2][a]) / 3;
}

bool ism_dual_centroid_within(ism_sampler *s, const double *p[3], double e)
{
    double c[3], g[3];
    ism_dual_centroid(p, c);
    double f = ism_sample_grad(s, c, g);
    return ism_dual_centroid_within_at(s, p, c, f, g, ism_plain_dist(s, c, f, g, e), e);
}

bool ism_dual_centroid_within_at(ism_sampler *s, const double *p[3], const double c[3],
                                 double f, const double g[3], double plain, double e)
{
    double u[3], v[3], nrm[3];
    for (int a = 0; a < 3; a++) {
        u[a] = p[1][a] - p[0][a];
        v[a] = p[2][a] - p[0][a];
    }
    double gl = ism_norm3(g);
    if (!isfinite(f) || !(gl > 0) ||
        !(ism_dual_kink_dist(s, c, plain, e) <= e))
        return false;
    ism_cross3(u, v, nrm);
    if (ism_dot3(nrm, g) > TURNED_COS * ism_norm3(nrm) * gl)
        return true;
    double reach = fmax(ism_norm3(u), ism_norm3(v)); /* beside a crease: either branch */
    return ism_dual_kink_faces(s, c, nrm, reach, TURNED_COS);
}

bool ism_dual_triangle_within(ism_sampler *s, const ism_mesh *m, const uint32_t *v, double e)
{
    const double *p[3] = {m->pos + 3 * (size_t)v[0], m->pos + 3 * (size_t)v[1],
                          m->pos + 3 * (size_t)v[2]};
    if (!ism_dual_centroid_within(s, p, e))
        return false;
    for (int j = 0; j < 3; j++) {
        double q[3];
        for (int a = 0; a < 3; a++)
            q[a] = 0.5 * (p[j][a] + p[(j + 1) % 3][a]);
        if (!(ism_dual_dist(s, q, e) <= e))
            return false;
    }
    return true;
}

/* Ball k's rim loops fanned to its apex through `rings` rings of vertices between (ring j of
 * R at the share 1 - j / (R + 1) of each rim vertex's ruling from the apex, moved onto f = 0
 * by Newton): the triangles pushed after c->tri's, each measured; MISS when one is beyond E
 * or turned. next_of: the rim edge leaving each vertex. A ruling lies on a quadratic cone
 * but a node's surface bends off it by O(r^2 |D^3 f| / |H|): Kummer's 16 nodes sit where
 * folds of radius ~0.3 x the distance to the node meet, and rims held 0.16 out by the
 * leaves the proofs cannot make plain there missed E at 3e-3 (up to 1.4 E) however far the
 * ball was halved (kummer-16-nodes, +1e-3 box, depth.max 9: point_fan). */
static enum ism_fan_status fan_ball(clip *c, size_t k, uint32_t apex, int rings,
                                    const uint32_t *next_of, double max_error)
{
    ism_mesh *m = c->m;
    uint32_t *ring = NULL; /* per rim edge i of ball k: the rings' vertices of its start */
    if (rings && !(ring = malloc(c->nrim * (size_t)rings * sizeof *ring)))
        return ISM_FAN_NO_MEMORY;
    const double *p = c->b[k].p;
    for (size_t i = 0; i < c->nrim && rings; i++) {
        if (c->rim[3 * i + 2] != k)
            continue;
        for (int j = 1; j <= rings; j++) {
            double share = 1 - (double)j / (rings + 1), x[3], g[3];
            const double *v = m->pos + 3 * (size_t)c->rim[3 * i];
            for (int a = 0; a < 3; a++)
                x[a] = p[a] + share * (v[a] - p[a]);
            onto_surface(c->s, x);
            ism_sample_grad(c->s, x, g);
            ism_normalise3(g);
            float nrm[3] = {(float)g[0], (float)g[1], (float)g[2]};
            uint32_t id = ism_mesh_add_vertex(m, x, nrm);
            if (id == UINT32_MAX) {
                free(ring);
                return ISM_FAN_NO_MEMORY;
            }
            ring[i * (size_t)rings + (size_t)(j - 1)] = id;
        }
    }
    size_t from = c->nt;
    for (size_t i = 0; i < c->nrim; i++) {
        if (c->rim[3 * i + 2] != k)
            continue;
        uint32_t a = c->rim[3 * i + 1], b = c->rim[3 * i]; /* to, from */
        size_t ia = next_of[a];
        for (int j = 0; j <= rings; j++) {
            uint32_t a2 = j < rings ? ring[ia * (size_t)rings + (size_t)j] : apex;
            uint32_t b2 = j < rings ? ring[i * (size_t)rings + (size_t)j] : apex;
            uint32_t t[6] = {a, b, b2, a, b2, a2};
            if (!push(&c->tri, &c->nt, &c->capt, t, j < rings ? 2 : 1)) {
                free(ring);
                return ISM_FAN_NO_MEMORY;
            }
            a = a2;
            b = b2;
        }
    }
    free(ring);
    for (size_t t = from; t < c->nt; t++)
        if (!ism_dual_triangle_within(c->s, m, c->tri + 3 * t, max_error))
            return ISM_FAN_MISS;
    return ISM_FAN_OK;
}

/* The rims fanned to their points (after the kept and cut triangles in c->tri), each new
 * triangle measured; BAD marks the balls whose rims are not their nappes' loops, MISS
 * those whose fans or cuts miss E or face against ∇f. */
static enum ism_fan_status fan_rims(clip *c, size_t kept, double max_error)
{
    ism_mesh *m = c->m;
    size_t nv = m->nverts;
    uint32_t *next_of = malloc((nv + 1) * sizeof *next_of);
    uint8_t *seen = calloc(c->nrim + 1, 1);
    enum ism_fan_status st = next_of && seen ? ISM_FAN_OK : ISM_FAN_NO_MEMORY;
    if (st == ISM_FAN_OK) {
        memset(next_of, 0xff, (nv + 1) * sizeof *next_of);
        for (size_t i = 0; i < c->nrim; i++) {
            if (next_of[c->rim[3 * i]] != UINT32_MAX) /* two rim edges leave one vertex */
                mark(c, c->rim[3 * i + 2]);
            next_of[c->rim[3 * i]] = (uint32_t)i;
        }
    }
    for (size_t k = 0; k < c->n && st == ISM_FAN_OK; k++)
        if (!c->shrink[k] && count_loops(c, k, next_of, seen) != c->b[k].nappes)
            mark(c, k);
    if (st == ISM_FAN_OK && c->marked)
        st = ISM_FAN_BAD;
    /* the cut triangles (after the kept ones) against E; every ball with a miss is marked */
    size_t cuts_end = c->nt;
    for (size_t t = kept; t < cuts_end && (st == ISM_FAN_OK || st == ISM_FAN_MISS); t++)
        if (!ism_dual_triangle_within(c->s, m, c->tri + 3 * t, max_error)) {
            size_t k = c->n; /* the ball whose clip sphere is nearest a corner */
            double best = INFINITY;
            for (int j = 0; j < 3; j++)
                for (size_t b = 0; b < c->n; b++) {
                    double d = sqrt(ism_sqdist3(m->pos + 3 * (size_t)c->tri[3 * t + j],
                                                c->b[b].p)) - c->r1[b];
                    if (c->r1[b] > 0 && d < best) {
                        best = d;
                        k = b;
                    }
                }
            mark(c, k < c->n ? k : 0);
            st = ISM_FAN_MISS;
        }
    /* each node's fans: straight to the apex first, then through more rings until they
     * meet E (then the ball halves) */
    for (size_t k = 0; k < c->n && (st == ISM_FAN_OK || st == ISM_FAN_MISS); k++) {
        if (!c->b[k].nappes)
            continue;
        float none[3] = {0, 0, 0}; /* ∇f = 0 at the point: no normal */
        uint32_t apex = ism_mesh_add_vertex(m, c->b[k].p, none);
        if (apex == UINT32_MAX) {
            st = ISM_FAN_NO_MEMORY;
            break;
        }
        size_t start = c->nt;
        enum ism_fan_status f = ISM_FAN_MISS;
        for (int rings = 0; rings <= FAN_RINGS && f == ISM_FAN_MISS; rings++) {
            c->nt = start;
            f = fan_ball(c, k, apex, rings, next_of, max_error);
        }
        if (f == ISM_FAN_NO_MEMORY)
            st = f;
        else if (f == ISM_FAN_MISS) {
            mark(c, k);
            st = ISM_FAN_MISS;
        }
    }
    free(next_of);
    free(seen);
    return st;
}

/* Cut triangles (c->tri from `kept` on, before the fans) turned against ∇f at their centroid
 * have their cut points put back where their edges cross the sphere: a piece is then a part
 * of its triangle, in its plane, facing as it faced. Newton moves a cut point up to ~E, and
 * where the sphere cuts a thin triangle near its long sides' ends the two cut points lie
 * closer than that: the piece between them turned over however small the ball (kummer-16-
 * nodes 1e-2, +1e-3 box: a node's ball halved 5 times, point_fan, cut slivers cos -0.04 to
 * -0.37). Both triangles sharing a cut edge see the point moved back; the fans from it are
 * measured as before. */
static void unturn_cuts(clip *c, size_t kept)
{
    ism_mesh *m = c->m;
    for (size_t t = kept; t < c->nt; t++) {
        const uint32_t *v = c->tri + 3 * t;
        const double *p[3] = {m->pos + 3 * (size_t)v[0], m->pos + 3 * (size_t)v[1],
                              m->pos + 3 * (size_t)v[2]};
        if (ism_dual_centroid_within(c->s, p, INFINITY))
            continue;
        for (int j = 0; j < 3; j++)
            if (v[j] >= c->nv0)
                memcpy(m->pos + 3 * (size_t)v[j], &c->chord[3 * (v[j] - c->nv0)],
                       3 * sizeof *c->chord);
    }
}

/* Every edge of m near a ball in exactly two triangles (the fans closed every hole). */
static enum ism_fan_status closed(const ism_mesh *m, const ism_dual_ball *b, size_t n,
                                   const ism_dual_ball_cover *cv)
{
    ism_edge_ref *e;
    size_t ne;
    if (!sorted_edges(m, b, n, cv, &e, &ne))
        return ISM_FAN_NO_MEMORY;
    enum ism_fan_status st = ISM_FAN_OK;
    for (size_t i = 0; i < ne && st == ISM_FAN_OK;) {
        size_t j = ism_edge_run_end(e, ne, i);
        if (j - i != 2)
            st = ISM_FAN_BAD;
        i = j;
    }
    free(e);
    return st;
}

enum ism_fan_status ism_dual_balls_fan(ism_mesh *m, ism_sampler *s, const ism_dual_ball *b,
                                       size_t n, const ism_dual_ball_cover *cv,
                                       double max_error, uint8_t *shrink, double *rim)
{
    memset(shrink, 0, n);
    clip c = {.m = m, .s = s, .b = b, .n = n, .shrink = shrink, .cover = cv};
    c.r1 = calloc(n ? n : 1, sizeof *c.r1);
    ism_edge_ref *e = NULL;
    size_t ne = 0;
    enum ism_fan_status st =
        c.r1 && sorted_edges(m, b, n, cv, &e, &ne) ? ISM_FAN_OK : ISM_FAN_NO_MEMORY;
    if (st == ISM_FAN_OK)
        st = clip_radii(&c, e, ne);
    free(e);
    size_t nv0 = c.nv0 = m->nverts, nt0 = m->ntris; /* the dual mesh's own */
    if (st == ISM_FAN_OK)
        st = settle_radii(&c);
    if (st == ISM_FAN_OK)
        st = collect_cuts(&c);
    for (size_t t = 0; t < nt0 && st == ISM_FAN_OK; t++)
        st = clip_triangle(&c, t);
    /* the triangles kept whole first, then the cut ones (a cut vertex among their corners):
     * fan_rims measures from `kept` on */
    size_t kept = 0, placed = 0;
    uint32_t *order = st == ISM_FAN_OK ? malloc((3 * c.nt + 1) * sizeof *order) : NULL;
    if (st == ISM_FAN_OK && !order)
        st = ISM_FAN_NO_MEMORY;
    for (int pass = 0; order && pass < 2; pass++) {
        for (size_t t = 0; t < c.nt; t++) {
            const uint32_t *v = c.tri + 3 * t;
            bool whole = v[0] < nv0 && v[1] < nv0 && v[2] < nv0;
            if (whole == (pass == 0))
                memcpy(order + 3 * placed++, v, 3 * sizeof *v);
        }
        if (pass == 0)
            kept = placed;
    }
    if (order) {
        if (c.nt) /* none kept: c.tri is NULL (memcpy's is nonnull) */
            memcpy(c.tri, order, 3 * c.nt * sizeof *order);
        free(order);
    }
    if (st == ISM_FAN_OK) {
        unturn_cuts(&c, kept);
        st = fan_rims(&c, kept, max_error);
    }
    if (st == ISM_FAN_OK) {
        if (!ism_mesh_reserve(m, m->nverts, c.nt))
            st = ISM_FAN_NO_MEMORY;
        else {
            if (c.nt)
                memcpy(m->tri, c.tri, 3 * c.nt * sizeof *c.tri);
            m->ntris = c.nt;
            uint32_t *used = calloc(m->nverts + 1, sizeof *used);
            if (!used)
                st = ISM_FAN_NO_MEMORY;
            else {
                ism_mesh_compact(m, used);
                free(used);
                st = closed(m, b, n, cv);
            }
        }
    }
    if (c.r1)
        memcpy(rim, c.r1, n * sizeof *rim);
    else
        memset(rim, 0, n * sizeof *rim); /* out of memory: nothing clipped */
    free(c.r1);
    free(c.ball);
    free(c.cut);
    free(c.cutv);
    free(c.chord);
    free(c.tri);
    free(c.rim);
    return st;
}
