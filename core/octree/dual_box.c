/* dual_box.c — the grown box, the first look at the box's faces (after the faces' interval
 * proof, which may spare it) and the clip of the dual mesh by the request's box (the design
 * and its figure: dual_box.h). */
#include "core/octree/dual_box.h"
#include "core/octree/dual_balls.h"
#include "core/octree/edge_keys.h"
#include "core/util/grow.h"
#include "core/util/vec3.h"

#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

/* Newton steps moving a cut point onto f = 0 in its planes: it starts on a chord within E of
 * f = 0, so two or three steps reach rounding; more only where ∇f nearly leaves the planes. */
#define CUT_NEWTON 12
/* A step below this share of the box's diagonal ends Newton (rounding: |f| / |∇f| then far
 * below the tests' 1e-9 of the diagonal). */
#define CUT_STOP 1e-14
/* Where Newton does not settle (|f| / |∇f| above this share of the diagonal after its steps,
 * or a move longer than the cut edge: f = 0 nearly tangent to the plane there) the clip
 * declines. */
#define CUT_SETTLED 1e-11
/* A vertex nearer the plane than this many times the farthest move of a cut point on its
 * edges is snapped onto it (snap_to): the sliver beside it folds once the cut points' moves
 * reach its height. */
#define SNAP_MOVES 2.0
/* ... and settled onto f = 0 within this many E of where it was: a vertex of the dual mesh
 * lies up to 0.9 E off f = 0 by design (straddle.h), so a move in the plane onto the curve
 * f = 0 can be a few E (the sphere of radius 0.09 at 2e-3: 2.3e-3). */
#define SNAP_REACH 4.0

/* The margins in level cells beyond the first, low and high side per axis: fractions of the
 * golden ratio's powers, so that no lattice plane of the grown box lies at a simple
 * fraction of the given one: symmetric surfaces hold lines and points of f = 0 exactly on the
 * given box's centre planes (the helicoid's y = z = 0, the Clebsch cubic's x = 0, y = -1,
 * Scherk's x = ±y at z = 0), and a lattice edge in the surface is a leaf the tests cannot
 * make plain at any depth (not_plain: helicoid, Scherk and Clebsch in their own boxes at
 * 2e-3 of the box, with the margins a whole cell). */
static const double MARGIN_LO[3] = {0.381966011250105, 0.236067977499790, 0.145898033750315};
static const double MARGIN_HI[3] = {0.145898033750315, 0.381966011250105, 0.236067977499790};

void ism_dual_box_grow(const double box[6], int level, double grown[6])
{
    double cells = ldexp(1, level);
    for (int a = 0; a < 3; a++) {
        /* W' = W + (2 + lo + hi) W' / cells */
        double shares = 2 + MARGIN_LO[a] + MARGIN_HI[a];
        double cell = (box[a + 3] - box[a]) / (cells - shares);
        grown[a] = box[a] - (1 + MARGIN_LO[a]) * cell;
        grown[a + 3] = box[a + 3] + (1 + MARGIN_HI[a]) * cell;
    }
}

/* Points of the first look evaluated together (ism_eval_points: ism_eval_point's values,
 * lane by lane, for about a third of the instructions on the sphere's tape). A chunk past
 * the first sign change is evaluated whole: at most this many points more than one by one,
 * and the same answer. */
#define LOOK_CHUNK 64

/* The look's verdict on f at the next points v[0..n) in order (*first: the sign of the first
 * finite value so far, 0 before one): true at a zero or a change of sign. */
static bool look_sees_cut(const double *v, size_t n, int *first)
{
    for (size_t k = 0; k < n; k++) {
        if (v[k] == 0)
            return true;
        if (!isfinite(v[k]))
            continue;
        int sg = v[k] < 0 ? -1 : 1;
        if (*first && sg != *first)
            return true;
        *first = sg;
    }
    return false;
}

/* The faces' proof before the look (faces_free): each face whole, then the tiles whose
 * interval holds 0 quartered, down to the look's own cells (2^-level of a face's side: a
 * finer tile would be sampled by no look point), while a level's tiles number at most
 * FACE_TILES (then the look decides). The look's 1,734 points cost ~196K instructions on
 * the sphere's and the torus's tapes; a batch of 8 tiles ~900. The sphere's faces are shown
 * free whole, kummer-4-nodes' at level 3 (260 tiles), the torus's at level 4 beside its
 * outer equator (382 tiles: the natural interval of its quartic is wide there);
 * kummer-16-nodes, which its box cuts, stops at level 2 (126 tiles, +34K instructions before
 * the look sees the cut). The worst case, f near 0 along much of the faces (a sheet in a
 * face), evaluates at most 6 + 24 + 96 + 256 + 256 = 638 tiles at the look's level 4 (80
 * batches, ~72K instructions, a third of the whole look's) once per mesh, before a look
 * that may see the cut in its first chunk of 64 points. */
/* At most this many tiles a level: 32 batches, ~29K instructions, 15% of the whole look;
 * past it 0 is in the interval over so much of the faces that the look likely sees a cut. */
#define FACE_TILES 256

/* Coordinate i of n + 1 on the box's axis b: the look's points and the faces' tiles both
 * (a tile's bounds are look coordinates, so every look point lies in a closed tile). */
static double look_coord(const double box[6], int b, int i, int n)
{
    return box[b] + (box[b + 3] - box[b]) * i / n;
}

/* Tile (i, j) of 2^level a side on face a (side 0: box's low plane, 1: high) into x: the
 * look's own coordinates, the last tile stretched to the box's edge (the faces' tiles then
 * meet along the box's edges whatever look_coord rounds to). */
static void face_tile(const double box[6], int a, int side, int level, int i, int j,
                      ism_interval x[3])
{
    int n = 1 << level, u = (a + 1) % 3, v = (a + 2) % 3, at[2] = {i, j}, ax[2] = {u, v};
    x[a] = (ism_interval){box[a + 3 * side], box[a + 3 * side]};
    for (int k = 0; k < 2; k++) {
        int b = ax[k];
        double lo = at[k] ? look_coord(box, b, at[k], n) : box[b];
        double hi = look_coord(box, b, at[k] + 1, n);
        x[b] = (ism_interval){lo, at[k] + 1 == n ? fmax(hi, box[b + 3]) : hi};
    }
}

/* Is f free of 0 on the box's faces by its natural interval over tiles of them (each face
 * whole, then the tiles holding 0 quartered, to the look's level `last`)? Then f is finite
 * and of one sign over the whole boundary (the closed tiles cover it and meet along their
 * edges), so every point the look samples there has that sign and the look would answer
 * false, which is answered without its points. (Tiles of both signs can meet only where f
 * is not finite along their common edge, 0/0 say: the look, skipping such values, might
 * then see a cut and answer true; false is never a proof, and a cut it misses is found by
 * the tree, box_cut.) */
static bool faces_free(ism_sampler *s, const double box[6], int last)
{
    int16_t tile[FACE_TILES][4], next[FACE_TILES][4]; /* face a, side, i, j */
    ism_interval x[FACE_TILES], y[FACE_TILES], z[FACE_TILES], f[FACE_TILES];
    size_t n = 0;
    for (int a = 0; a < 3; a++)
        for (int side = 0; side < 2; side++, n++)
            memcpy(tile[n], (int16_t[4]){(int16_t)a, (int16_t)side, 0, 0}, sizeof tile[n]);
    for (int level = 0; n; level++) {
        for (size_t k = 0; k < n; k++) {
            ism_interval b[3];
            face_tile(box, tile[k][0], tile[k][1], level, tile[k][2], tile[k][3], b);
            x[k] = b[0], y[k] = b[1], z[k] = b[2];
        }
        s->n_interval += n;
        ism_eval_interval_batch(s->tape, s->ws, x, y, z, f, n);
        size_t m = 0;
        for (size_t k = 0; k < n; k++) {
            if (f[k].lo > 0 || f[k].hi < 0)
                continue; /* free of 0 (a NaN bound is not) */
            if (level == last || m + 4 > FACE_TILES)
                return false;
            for (int q = 0; q < 4; q++) {
                next[m][0] = tile[k][0], next[m][1] = tile[k][1];
                next[m][2] = (int16_t)(2 * tile[k][2] + (q & 1));
                next[m][3] = (int16_t)(2 * tile[k][3] + (q >> 1));
                m++;
            }
        }
        memcpy(tile, next, m * sizeof tile[0]);
        n = m;
    }
    return true;
}

bool ism_dual_box_seen_cut(ism_sampler *s, const double box[6], int level)
{
    if (!s->local && faces_free(s, box, level))
        return false;
    int n = 1 << level;
    int first = 0; /* the sign of the first finite value: -1 or 1 */
    double x[LOOK_CHUNK], y[LOOK_CHUNK], z[LOOK_CHUNK], f[LOOK_CHUNK];
    size_t m = 0;
    for (int a = 0; a < 3; a++)
        for (int side = 0; side < 2; side++)
            for (int i = 0; i <= n; i++)
                for (int j = 0; j <= n; j++) {
                    int u = (a + 1) % 3, v = (a + 2) % 3;
                    double p[3];
                    p[a] = box[a + 3 * side];
                    p[u] = look_coord(box, u, i, n);
                    p[v] = look_coord(box, v, j, n);
                    if (s->local) { /* another tape inside its box (sampler.h): one by one */
                        f[0] = ism_sample_f(s, p);
                        if (look_sees_cut(f, 1, &first))
                            return true;
                        continue;
                    }
                    x[m] = p[0], y[m] = p[1], z[m] = p[2];
                    bool last = a == 2 && side == 1 && i == n && j == n;
                    if (++m < LOOK_CHUNK && !last)
                        continue;
                    s->n_point += m;
                    ism_eval_points(s->tape, s->ws, x, y, z, f, m);
                    if (look_sees_cut(f, m, &first))
                        return true;
                    m = 0;
                }
    return false;
}

/* ---- the clip --------------------------------------------------------------------------- */

typedef struct bclip {
    ism_mesh *m;
    ism_sampler *s;
    const double *box;
    double diag, snap;
    uint8_t *on;      /* per vertex: bit p when it lies on plane p (2 axis + side) exactly */
    size_t capon;
    double *sd;       /* per vertex: its signed distance beyond this pass's plane */
    size_t capsd;
    double *need;     /* per vertex: the farthest a cut point on its edges moved (snap_to) */
    size_t capneed;
    uint64_t *cut;    /* sorted undirected edges crossing this pass's plane */
    uint32_t *cutv;   /* their cut points' vertices */
    size_t ncut, capcut, capcutv;
    uint32_t *tri;    /* this pass's triangles */
    size_t nt, capt;
    uint32_t *src, *nsrc; /* per triangle: the input triangle it was cut from (now, next) */
    size_t capsrc, capnsrc;
} bclip;

/* The vertex at the cut of edge a-b (made in cut_points). */
static uint32_t cut_vertex(const bclip *c, uint32_t a, uint32_t b)
{
    return ism_edge_key_vertex(c->cut, c->cutv, c->ncut, a, b);
}

/* Does edge a-b cross the plane strictly (one end inside, one outside)? */
static bool crosses(const bclip *c, uint32_t a, uint32_t b)
{
    return (c->sd[a] < 0 && c->sd[b] > 0) || (c->sd[a] > 0 && c->sd[b] < 0);
}

/* q moved onto f = 0 by Newton with the coordinates of every plane in `held` set to it;
 * false when it does not settle within `reach` of where it started (set). */
static bool settle(bclip *c, uint8_t held, double q[3], double reach)
{
    for (int p = 0; p < 6; p++)
        if (held >> p & 1)
            q[p / 2] = c->box[p / 2 + 3 * (p & 1)];
    double start[3] = {q[0], q[1], q[2]}, f = NAN, gl = 0;
    for (int it = 0; it < CUT_NEWTON; it++) {
        double g[3];
        f = ism_sample_grad(c->s, q, g);
        for (int p = 0; p < 6; p++)
            if (held >> p & 1)
                g[p / 2] = 0;
        double gg = ism_dot3(g, g);
        gl = sqrt(gg);
        if (!isfinite(f) || !(gg > 0) || !isfinite(gg))
            return false;
        if (f == 0)
            break;
        for (int j = 0; j < 3; j++)
            q[j] -= f * g[j] / gg;
        if (fabs(f) / gl < CUT_STOP * c->diag) {
            f = ism_sample_f(c->s, q);
            break;
        }
    }
    return isfinite(f) && fabs(f) <= CUT_SETTLED * c->diag * gl &&
           sqrt(ism_sqdist3(q, start)) <= reach;
}

/* The point where edge a-b crosses plane p, settled onto f = 0 in the planes its ends share
 * and p (*moved: how far from the edge); false when it does not settle within the edge's
 * length. */
static bool cut_point(bclip *c, int p, uint8_t held, uint32_t a, uint32_t b, double out[3],
                      double *moved)
{
    const double *pa = c->m->pos + 3 * (size_t)a, *pb = c->m->pos + 3 * (size_t)b;
    if (pb[0] < pa[0] || (pb[0] == pa[0] && (pb[1] < pa[1] || (pb[1] == pa[1] && pb[2] < pa[2])))) {
        /* from the end first in coordinate order: the same point whatever the numbering
         * (the rounds' probe and the final clip number the vertices differently) */
        uint32_t x = a;
        a = b;
        b = x;
        const double *px = pa;
        pa = pb;
        pb = px;
    }
    double t = c->sd[a] / (c->sd[a] - c->sd[b]), start[3];
    for (int j = 0; j < 3; j++)
        out[j] = start[j] = pa[j] + t * (pb[j] - pa[j]);
    bool ok = settle(c, (uint8_t)(held | 1u << p), out, sqrt(ism_sqdist3(pa, pb)));
    *moved = sqrt(ism_sqdist3(out, start));
    return ok;
}

/* Vertices nearer plane p (either side) than twice the farthest move of a cut point on their
 * edges, or whose pieces would turn against ∇f (mark_turned), and never farther than c->snap,
 * settled onto it and onto f = 0 (where that stays within SNAP_REACH E; else left), their sd
 * made 0. The reach follows the cut points' moves, not E: snapped whenever within E, a
 * vertex's own triangles, once split smaller than E, kept missing it (the unit sphere cut at
 * x = -0.5 at E 0.05: error_at_max_depth). */
static void snap_to(bclip *c, int p, size_t nv)
{
    ism_mesh *m = c->m;
    for (size_t v = 0; v < nv; v++) {
        double reach = fmin(c->snap, SNAP_MOVES * c->need[v]);
        if (!(fabs(c->sd[v]) < reach) || c->sd[v] == 0)
            continue;
        double q[3] = {m->pos[3 * v], m->pos[3 * v + 1], m->pos[3 * v + 2]}, g[3];
        if (!settle(c, (uint8_t)(c->on[v] | 1u << p), q, SNAP_REACH * c->snap))
            continue;
        memcpy(m->pos + 3 * v, q, sizeof q);
        c->on[v] |= (uint8_t)(1u << p);
        c->sd[v] = 0;
        ism_sample_grad(c->s, q, g);
        ism_normalise3(g);
        for (int j = 0; j < 3; j++)
            m->normal[3 * v + j] = (float)g[j];
    }
}

/* Every edge crossing plane p gets its cut vertex (once); BAD when one will not settle. */
static enum ism_box_clip_status cut_points(bclip *c, int p)
{
    ism_mesh *m = c->m;
    c->ncut = 0;
    for (size_t t = 0; t < m->ntris; t++)
        for (int j = 0; j < 3; j++) {
            uint32_t a = m->tri[3 * t + j], b = m->tri[3 * t + (j + 1) % 3];
            if (!crosses(c, a, b))
                continue;
            if (!ism_grow((void **)&c->cut, &c->capcut, c->ncut + 1, sizeof *c->cut, 256))
                return ISM_BOX_CLIP_NO_MEMORY;
            c->cut[c->ncut++] = ism_edge_key(a, b);
        }
    if (!c->ncut)
        return ISM_BOX_CLIP_OK;
    size_t u = c->ncut = ism_edge_keys_unique(c->cut, c->ncut);
    if (!ism_grow((void **)&c->cutv, &c->capcutv, u, sizeof *c->cutv, 256) ||
        !ism_grow((void **)&c->on, &c->capon, m->nverts + u, 1, 1024))
        return ISM_BOX_CLIP_NO_MEMORY;
    for (size_t i = 0; i < u; i++) {
        uint32_t a = (uint32_t)(c->cut[i] >> 32), b = (uint32_t)c->cut[i];
        uint8_t held = (uint8_t)(c->on[a] & c->on[b]);
        double q[3], g[3], moved;
        if (!cut_point(c, p, held, a, b, q, &moved))
            return ISM_BOX_CLIP_BAD;
        c->need[a] = fmax(c->need[a], moved);
        c->need[b] = fmax(c->need[b], moved);
        ism_sample_grad(c->s, q, g);
        ism_normalise3(g);
        float nrm[3] = {(float)g[0], (float)g[1], (float)g[2]};
        c->cutv[i] = ism_mesh_add_vertex(m, q, nrm);
        if (c->cutv[i] == UINT32_MAX)
            return ISM_BOX_CLIP_NO_MEMORY;
        c->on[c->cutv[i]] = (uint8_t)(held | 1u << p);
    }
    return ISM_BOX_CLIP_OK;
}

/* Appends triangle a b d, cut from input triangle `from`, to this pass's. */
static bool push(bclip *c, uint32_t a, uint32_t b, uint32_t d, uint32_t from)
{
    if (!ism_grow((void **)&c->tri, &c->capt, c->nt + 1, 3 * sizeof *c->tri, 256) ||
        !ism_grow((void **)&c->nsrc, &c->capnsrc, c->nt + 1, sizeof *c->nsrc, 256))
        return false;
    c->nsrc[c->nt] = from;
    uint32_t *t = c->tri + 3 * c->nt++;
    t[0] = a;
    t[1] = b;
    t[2] = d;
    return true;
}

/* |f| / |∇f| at the midpoint of a-b (the diagonal of a cut quad nearer f = 0 is taken). */
static double mid_dist(bclip *c, uint32_t a, uint32_t b)
{
    double q[3];
    for (int j = 0; j < 3; j++)
        q[j] = 0.5 * (c->m->pos[3 * (size_t)a + j] + c->m->pos[3 * (size_t)b + j]);
    return ism_sample_dist(c->s, q);
}

/* Triangle v clipped by this pass's plane (Sutherland-Hodgman) into out: its corners inside
 * or on the plane and the cut points of its crossing edges, in order; returns how many. */
static int clip_polygon(const bclip *c, const uint32_t *v, uint32_t out[4])
{
    int n = 0;
    for (int j = 0; j < 3; j++) {
        uint32_t a = v[j], b = v[(j + 1) % 3];
        if (c->sd[a] <= 0)
            out[n++] = a;
        if (crosses(c, a, b))
            out[n++] = cut_vertex(c, a, b);
    }
    return n;
}

/* Does triangle a b d face against ∇f at its centroid? */
static bool turned(bclip *c, uint32_t a, uint32_t b, uint32_t d)
{
    const double *p = c->m->pos + 3 * (size_t)a, *q = c->m->pos + 3 * (size_t)b,
                 *r = c->m->pos + 3 * (size_t)d;
    double u[3], w[3], n[3], m[3], g[3];
    for (int j = 0; j < 3; j++) {
        u[j] = q[j] - p[j];
        w[j] = r[j] - p[j];
        m[j] = (p[j] + q[j] + r[j]) / 3;
    }
    ism_cross3(u, w, n);
    ism_sample_grad(c->s, m, g);
    return !(ism_dot3(n, g) > 0);
}

/* The corner alone on its side of plane p of every crossing triangle whose pieces would turn
 * against ∇f (any three consecutive points of its clipped polygon) is to be snapped:
 * c->need set to the snap's limit. A corner a hair inside, with two cut points beside it
 * moved onto f = 0, or a hair outside, between two nearly coincident ones, makes such
 * slivers at any depth (a sphere of radius 0.09 poking through a face at E 2e-3 declined
 * error_at_max_depth in main's irrational box; 1e-3 in its own). */
static void mark_turned(bclip *c)
{
    ism_mesh *m = c->m;
    for (size_t t = 0; t < m->ntris; t++) {
        const uint32_t *v = m->tri + 3 * t;
        int in = (c->sd[v[0]] <= 0) + (c->sd[v[1]] <= 0) + (c->sd[v[2]] <= 0);
        if (!crosses(c, v[0], v[1]) && !crosses(c, v[1], v[2]) && !crosses(c, v[2], v[0]))
            continue;
        uint32_t out[4];
        int n = clip_polygon(c, v, out);
        bool bad = false;
        for (int k = 0; k < n && !bad && n >= 3; k++)
            bad = turned(c, out[k], out[(k + 1) % n], out[(k + 2) % n]);
        for (int j = 0; bad && j < 3; j++)
            if ((c->sd[v[j]] <= 0) == (in == 1))
                c->need[v[j]] = c->snap;
    }
}

/* Triangle t clipped by this pass's plane (clip_polygon); a quad is cut across its diagonal
 * nearer f = 0, fewer than 3 points make nothing (a corner or an edge on the plane). */
static bool clip_triangle(bclip *c, size_t t)
{
    const uint32_t *v = c->m->tri + 3 * t, from = c->src[t];
    uint32_t out[4];
    int n = clip_polygon(c, v, out);
    if (n == 3)
        return push(c, out[0], out[1], out[2], from);
    if (n == 4) {
        if (mid_dist(c, out[0], out[2]) <= mid_dist(c, out[1], out[3]))
            return push(c, out[0], out[1], out[2], from) && push(c, out[0], out[2], out[3], from);
        return push(c, out[1], out[2], out[3], from) && push(c, out[1], out[3], out[0], from);
    }
    return true;
}

/* One pass: m's triangles clipped by plane p (axis p / 2, the box's low side for even p). */
static enum ism_box_clip_status clip_plane(bclip *c, int p)
{
    ism_mesh *m = c->m;
    int a = p / 2;
    double at = c->box[a + 3 * (p & 1)];
    /* c->on covers m->nverts already: sized by ism_dual_box_clip, grown by cut_points */
    if (!ism_grow((void **)&c->sd, &c->capsd, m->nverts, sizeof *c->sd, 1024) ||
        !ism_grow((void **)&c->need, &c->capneed, m->nverts, sizeof *c->need, 1024))
        return ISM_BOX_CLIP_NO_MEMORY;
    size_t nv = m->nverts;
    for (size_t v = 0; v < nv; v++) { /* beyond the plane: > 0; on it (made so): 0 */
        c->sd[v] = c->on[v] >> p & 1 ? 0
                   : p & 1         ? m->pos[3 * v + a] - at
                                   : at - m->pos[3 * v + a];
        c->need[v] = 0;
    }
    enum ism_box_clip_status st = cut_points(c, p);
    if (st != ISM_BOX_CLIP_OK)
        return st;
    mark_turned(c);
    snap_to(c, p, nv); /* the cuts on a snapped vertex's edges are left unused */
    c->nt = 0;
    for (size_t t = 0; t < m->ntris; t++)
        if (!clip_triangle(c, t))
            return ISM_BOX_CLIP_NO_MEMORY;
    if (!ism_mesh_reserve(m, m->nverts, c->nt))
        return ISM_BOX_CLIP_NO_MEMORY;
    if (c->nt)
        memcpy(m->tri, c->tri, 3 * c->nt * sizeof *c->tri);
    m->ntris = c->nt;
    uint32_t *x = c->src;
    size_t cap = c->capsrc;
    c->src = c->nsrc;
    c->capsrc = c->capnsrc;
    c->nsrc = x;
    c->capnsrc = cap;
    return ISM_BOX_CLIP_OK;
}

enum ism_box_clip_status ism_dual_box_clip(ism_mesh *m, ism_sampler *s, const double box[6],
                                           double max_error, uint8_t *miss,
                                           ism_box_clip_stats *cs)
{
    bclip c = {.m = m, .s = s, .box = box, .snap = ISM_DUAL_BOX_SNAP * max_error};
    c.diag = ism_box_diagonal(box);
    memset(cs, 0, sizeof *cs);
    enum ism_box_clip_status st = ISM_BOX_CLIP_OK;
    size_t nt0 = m->ntris;
    if (!ism_grow((void **)&c.on, &c.capon, m->nverts, 1, 1024) ||
        !ism_grow((void **)&c.src, &c.capsrc, nt0, sizeof *c.src, 256))
        st = ISM_BOX_CLIP_NO_MEMORY;
    else {
        memset(c.on, 0, m->nverts);
        for (size_t t = 0; t < nt0; t++)
            c.src[t] = (uint32_t)t;
    }
    if (miss)
        memset(miss, 0, nt0);
    for (int p = 0; p < 6 && st == ISM_BOX_CLIP_OK; p++)
        st = clip_plane(&c, p);
    /* the triangles with a corner on a plane are the cuts': measured as the dual mesh's own */
    for (size_t t = 0; t < m->ntris && st == ISM_BOX_CLIP_OK; t++) {
        const uint32_t *v = m->tri + 3 * t;
        if (!(c.on[v[0]] | c.on[v[1]] | c.on[v[2]]))
            continue;
        cs->cut++;
        if (!ism_dual_triangle_within(s, m, v, max_error)) {
            cs->missed++;
            if (miss)
                miss[c.src[t]] = 1;
        }
    }
    if (st == ISM_BOX_CLIP_OK && cs->missed)
        st = ISM_BOX_CLIP_MISS;
    if (st == ISM_BOX_CLIP_OK && !ism_mesh_drop_loose(m))
        st = ISM_BOX_CLIP_NO_MEMORY;
    free(c.on);
    free(c.sd);
    free(c.need);
    free(c.cut);
    free(c.cutv);
    free(c.tri);
    free(c.src);
    free(c.nsrc);
    return st;
}
