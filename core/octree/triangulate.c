/* triangulate.c — triangles from stitched polygons. A triangle or quadrilateral is split
 * directly (a quad along its shorter diagonal); a larger polygon (crack repair puts extra
 * points on coarse nodes' faces) is fanned around its centre, projected onto f = 0 by a few
 * Newton steps along ∇f — or, under an error bound, from one of its corners when that fan
 * measures within the bound. Each polygon is wound so that its normal agrees with the mean
 * gradient at its points: consistent orientation wherever ∇f does. */
#include "core/octree/triangulate.h"
#include "core/octree/face_flat.h"
#include "core/octree/sample_dist.h"
#include "core/util/grow.h"
#include "core/util/vec3.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

/* A point's gradient as ism_normalise3 leaves it, and whether it counts toward a mean unit
 * gradient (its norm > 0): unit_gradient is the one place a gradient is normalised; each
 * polygon's points are normalised once, and every test that sums unit gradients (reversed,
 * tri_agreement_u, clip_ears) reads them in its own order. */
typedef struct unit_g {
    double u[3];
    bool ok;
} unit_g;

/* Polygons of up to this many points keep what their triangulation works out per point
 * (struct polygon: unit gradients, faces, and the n × n distances, 8 KiB at 32) on the
 * stack; a larger one (a coarse node's face crossed by finer neighbours' tiles) allocates
 * it. 32: a loop has no more points than its node has lines, and stitch.c keeps a node of
 * up to FEW_ENDS = 32 ends (16 lines) on its stack too; no polygon of the rows
 * passes it (callgrind line counts of the allocating branches). On the heap the distance
 * table is n² doubles by design: the corner fans' search reads every pair, already n² in
 * time. */
#define UNIT_STACK 32

static void unit_gradient(const ism_fpoint *p, unit_g *ug)
{
    ug->u[0] = p->g[0], ug->u[1] = p->g[1], ug->u[2] = p->g[2];
    ug->ok = ism_normalise3(ug->u) > 0;
}

/* Room for n more vertices in o (false when memory runs out). */
static inline bool out_reserve(ism_cell_out *o, size_t n)
{
    return ism_grow((void **)&o->verts, &o->cap_verts, o->nverts + n, sizeof *o->verts, 256);
}

bool ism_cell_out_vert(ism_cell_out *o, const ism_fpoint *p, uint32_t *idx)
{
    if (!out_reserve(o, 1))
        return false;
    *idx = (uint32_t)o->nverts;
    o->verts[o->nverts++] = *p;
    return true;
}

/* Appends pts[0 .. n), in reverse order when flip, as ism_cell_out_vert would one by one
 * (one capacity check for the polygon; in order, one copy). */
static bool out_polygon(ism_cell_out *o, const ism_fpoint *pts, size_t n, bool flip)
{
    if (!out_reserve(o, n))
        return false;
    if (!flip) {
        memcpy(o->verts + o->nverts, pts, n * sizeof *pts);
        o->nverts += n;
        return true;
    }
    for (size_t i = 0; i < n; i++)
        o->verts[o->nverts++] = pts[n - 1 - i];
    return true;
}

/* Room for n more triangles in o (false when memory runs out). */
static inline bool tris_reserve(ism_cell_out *o, size_t n)
{
    return ism_grow((void **)&o->tris, &o->cap_tris, o->ntris + n, 3 * sizeof *o->tris, 256);
}

/* Appends triangle a, b, c to o, whose room tris_reserve made. */
static inline void push_tri(ism_cell_out *o, uint32_t a, uint32_t b, uint32_t c)
{
    uint32_t *t = o->tris + 3 * o->ntris++;
    t[0] = a, t[1] = b, t[2] = c;
}

bool ism_cell_out_tri(ism_cell_out *o, uint32_t a, uint32_t b, uint32_t c)
{
    if (!tris_reserve(o, 1))
        return false;
    push_tri(o, a, b, c);
    return true;
}

bool ism_cell_out_segment(ism_cell_out *out, const ism_fpoint *a, const ism_fpoint *b)
{
    uint32_t ia, ib;
    if (!ism_cell_out_vert(out, a, &ia) || !ism_cell_out_vert(out, b, &ib))
        return false;
    if (!ism_grow((void **)&out->segs, &out->cap_segs, out->nsegs + 1, 2 * sizeof *out->segs, 16))
        return false;
    out->segs[2 * out->nsegs] = ia;
    out->segs[2 * out->nsegs + 1] = ib;
    out->nsegs++;
    return true;
}

void ism_newell(const ism_fpoint *p, size_t n, double nrm[3])
{
    nrm[0] = nrm[1] = nrm[2] = 0;
    for (size_t i = 0; i < n; i++) {
        const double *a = p[i].p, *b = p[(i + 1) % n].p;
        nrm[0] += (a[1] - b[1]) * (a[2] + b[2]);
        nrm[1] += (a[2] - b[2]) * (a[0] + b[0]);
        nrm[2] += (a[0] - b[0]) * (a[1] + b[1]);
    }
}

/* The mean of the polygon's points (each point's share divided first, the order the meshes
 * were made with). */
static void centroid(const ism_fpoint *p, size_t n, double c[3])
{
    c[0] = c[1] = c[2] = 0;
    for (size_t i = 0; i < n; i++)
        for (int k = 0; k < 3; k++)
            c[k] += p[i].p[k] / (double)n;
}

/* The node's corners' vote on the polygon's normal nrm through its centre c: the sum of
 * sign(f) × the corner's height over the polygon's plane, > 0 when the normal points from
 * the corners where f < 0 toward those where f > 0 (as ∇f does), < 0 when turned over, 0
 * when the corners do not say. */
static double corner_vote(ism_sampler *s, const double node[6], const double c[3],
                          const double nrm[3])
{
    double sum = 0;
    for (int i = 0; i < 8; i++) {
        double q[3] = {node[i & 1 ? 3 : 0], node[i & 2 ? 4 : 1], node[i & 4 ? 5 : 2]};
        double d[3] = {q[0] - c[0], q[1] - c[1], q[2] - c[2]};
        sum += ism_sign(ism_sample_f(s, q)) * ism_dot3(d, nrm);
    }
    return isfinite(sum) ? sum : 0;
}

/* Is the polygon wound against ∇f? Its Newell normal against the mean unit gradient at its
 * points — unless the points split the vote (some gradients face the normal, others face
 * away: a polygon across a sharp CSG crease, such as the chord of cube-minus-ball's 40°
 * wedge between the ball and a face, two points on the ball and one on the face, whose mean
 * follows the majority and turns the polygon against all its neighbours; or a polygon round
 * a tiny closed piece of f = 0, such as the horn cyclide's near (9.86, −1.64, 0.013) in its box
 * moved by √2 − 1 of a cell, whose rim points' gradients lean one way and its apex's the
 * other). Then, given the node (s and node not NULL), the corners decide, as a sign-based
 * polygoniser would: the polygon separates the corners where f < 0 from those where f > 0.
 * For every f, not only one with a min/max: where two sheets cross a node the corners may say
 * nothing of one polygon (their sum is then 0 and the mean is kept), yet on all 42 presets
 * of the gallery, singular ones included, in their own box and moved by 1e-3, 0.37, √2 − 1
 * and 0.6 of a cell, they wind no edge against its neighbour, where the mean alone wound
 * 12 / 14 / 33 of the horn's in the last three. With `units` not NULL, each point's unit
 * gradient is left in units[i] for the caller's fans to read again. */
static bool reversed(ism_sampler *s, const double node[6], const ism_fpoint *p, size_t n,
                     unit_g *units)
{
    double nrm[3], g[3] = {0, 0, 0};
    ism_newell(p, n, nrm);
    bool facing = false, away = false;
    for (size_t i = 0; i < n; i++) {
        unit_g one, *ug = units ? &units[i] : &one;
        unit_gradient(&p[i], ug);
        const double *u = ug->u;
        if (ug->ok)
            for (int k = 0; k < 3; k++)
                g[k] += u[k];
        double d = ism_dot3(u, nrm);
        facing = facing || d > 0;
        away = away || d < 0;
    }
    if (facing && away && s && node) { /* rare: the centre only for the corners' vote */
        double c[3];
        centroid(p, n, c);
        double v = corner_vote(s, node, c, nrm);
        if (v != 0)
            return v < 0;
    }
    return ism_dot3(nrm, g) < 0;
}

/* The polygon's centre moved onto f = 0; false when Newton does not land on the surface
 * within reach (near singular points) or inside the node, and the polygon is then fanned
 * from a corner. */
static bool centre_point(ism_sampler *s, const ism_fpoint *p, size_t n, double reach,
                         const double node[6], ism_fpoint *c)
{
    double m[3];
    centroid(p, n, m);
    double q[3] = {m[0], m[1], m[2]}, g[3], f = 0;
    bool landed = false;
    for (int it = 0; it < 5; it++) {
        f = ism_sample_grad(s, q, g);
        double gg = ism_dot3(g, g);
        if (!(gg > 0) || !isfinite(f) || !isfinite(gg))
            return false;
        if (fabs(f) <= 1e-6 * reach * sqrt(gg)) {
            landed = true; /* q is on the surface and g is its gradient there */
            break;
        }
        for (int k = 0; k < 3; k++)
            q[k] -= f * g[k] / gg;
    }
    double moved = ism_dist3(q, m);
    if (!landed || !isfinite(moved) || moved > reach)
        return false;
    for (int k = 0; node && k < 3; k++)
        if (!(q[k] >= node[k] && q[k] <= node[3 + k]))
            return false; /* its fan would cover the neighbour's part of the surface */
    memcpy(c->p, q, sizeof c->p);
    memcpy(c->g, g, sizeof c->g);
    c->flags = ISM_FP_INTERIOR;
    return true;
}

/* A polygon as emitted (its points out->verts[base ..], in the emitted order) and what its
 * triangulation asks of its points again and again, worked out once: their unit
 * gradients, the faces of the node each lies in, and (for the fans from its corners) the
 * distances between them. */
typedef struct polygon {
    const ism_fpoint *q;
    size_t n;
    unit_g *u;      /* q[i]'s unit gradient */
    uint8_t *faces; /* q[i]'s ism_face_mask (0 without a node: no face then) */
    double *len;    /* n × n: |q[i] − q[j]| (ism_dist3, the same bits either way round) */
    double *ear;    /* min_angle_cos of q[j − 1], q[j], q[j + 1]: the first and last triangles
                       of the fans from q[j + 1] and q[j − 1], measured once */
    bool has_len;   /* len and ear are filled in (polygon_lengths) */
} polygon;

/* The cosine of the angle between sides of lengths nu, nw whose dot product is uw (1 at a
 * degenerate side). */
static double corner_cos(double uw, double nu, double nw)
{
    return nu > 0 && nw > 0 ? uw / (nu * nw) : 1;
}

/* The cosine of the smallest angle of triangle a, b, c (larger is worse; an angle at a
 * degenerate side counts 1), its sides side[k] = |v[k + 1] − v[k]| (v = a, b, c) given.
 * Each angle's cosine is that of its two sides leaving its corner, u · w / (|u| |w|): with
 * the sides e[k] = v[k + 1] − v[k], the corner v[k] has u = e[k] and w = −e[k + 2], and
 * u · w = −(e[k] · e[k + 2]) (a difference turned round, and a sum of products turned
 * round, only change sign: the same number, but for the sign of a zero, which no
 * comparison sees). The same for b, c, a: the measure does not depend on the corner the
 * triangle starts from. */
static double min_angle_cos(const double *a, const double *b, const double *c,
                            const double side[3])
{
    const double e0[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]};
    const double e1[3] = {c[0] - b[0], c[1] - b[1], c[2] - b[2]};
    const double e2[3] = {a[0] - c[0], a[1] - c[1], a[2] - c[2]};
    double c0 = corner_cos(-ism_dot3(e0, e2), side[0], side[2]);
    double c1 = corner_cos(-ism_dot3(e1, e0), side[1], side[0]);
    double c2 = corner_cos(-ism_dot3(e2, e1), side[2], side[1]);
    double worst = -1; /* the largest, in corner order (a NaN is never taken) */
    worst = c0 > worst ? c0 : worst;
    worst = c1 > worst ? c1 : worst;
    return c2 > worst ? c2 : worst;
}

/* min_angle_cos of the polygon's triangle q[a], q[b], q[c] (pg->len filled in). */
static double tri_cos(const polygon *pg, size_t a, size_t b, size_t c)
{
    size_t n = pg->n;
    const double side[3] = {pg->len[a * n + b], pg->len[b * n + c], pg->len[c * n + a]};
    return min_angle_cos(pg->q[a].p, pg->q[b].p, pg->q[c].p, side);
}

/* Fills in pg->len and pg->ear once. ism_dist3(a, b) squares a − b, whose terms are those of
 * b − a but for their signs: every pair's distance is the one ism_norm3 gives either way
 * round. */
static void polygon_lengths(polygon *pg)
{
    if (pg->has_len)
        return;
    size_t n = pg->n;
    for (size_t i = 0; i < n; i++) {
        pg->len[i * n + i] = 0;
        for (size_t j = i + 1; j < n; j++)
            pg->len[i * n + j] = pg->len[j * n + i] = ism_dist3(pg->q[i].p, pg->q[j].p);
    }
    for (size_t j = 0; j < n; j++)
        pg->ear[j] = tri_cos(pg, (j + n - 1) % n, j, (j + 1) % n);
    pg->has_len = true;
}

/* The faces of the node p lies in (ism_face_masks; none without a node). */
static unsigned point_faces(const double node[6], const ism_fpoint *p)
{
    uint8_t mask = 0;
    if (node)
        ism_face_masks(node, p, 1, &mask);
    return mask;
}

/* Do the polygon's points a, b, c lie in one face of the node? */
static bool tri_in_face(const polygon *pg, size_t a, size_t b, size_t c)
{
    return (pg->faces[a] & pg->faces[b] & pg->faces[c]) != 0;
}

/* g += u's unit gradient when it counts (u->ok). */
static void add_unit(double g[3], const unit_g *u)
{
    if (u->ok)
        for (int k = 0; k < 3; k++)
            g[k] += u->u[k];
}

/* Triangle a, b, c's normal against the mean unit gradient at its corners (their unit
 * gradients ua, ub, uc, added in that order): > 0 when it keeps the surface's orientation,
 * < 0 when it is turned over, 0 when degenerate. */
static double tri_agreement_u(const ism_fpoint *a, const ism_fpoint *b, const ism_fpoint *c,
                              const unit_g *ua, const unit_g *ub, const unit_g *uc)
{
    const double e1[3] = {b->p[0] - a->p[0], b->p[1] - a->p[1], b->p[2] - a->p[2]};
    const double e2[3] = {c->p[0] - a->p[0], c->p[1] - a->p[1], c->p[2] - a->p[2]};
    double nrm[3], g[3] = {0, 0, 0};
    ism_cross3(e1, e2, nrm);
    add_unit(g, ua);
    add_unit(g, ub);
    add_unit(g, uc);
    return ism_dot3(nrm, g);
}

/* tri_agreement_u with the corners' unit gradients computed here. */
static double tri_agreement(const ism_fpoint *a, const ism_fpoint *b, const ism_fpoint *c)
{
    unit_g ua, ub, uc;
    unit_gradient(a, &ua);
    unit_gradient(b, &ub);
    unit_gradient(c, &uc);
    return tri_agreement_u(a, b, c, &ua, &ub, &uc);
}

/* Does the fan of the polygon (wound to agree with ∇f) around apex — one of its corners or
 * a point off it, whose unit gradient is uapex — hold a turned-over triangle? A fan from a
 * corner of a polygon that is not star-shaped from it (a reflex corner across, as where the
 * polygon runs along a node's face) folds back: the sphere at E = 2e-3, depth 8, box 0.37
 * cell off the lattice had 4. */
static bool fan_folds(const polygon *pg, const ism_fpoint *apex, const unit_g *uapex)
{
    const ism_fpoint *q = pg->q;
    size_t n = pg->n;
    for (size_t i = 0; i < n; i++) {
        size_t j = (i + 1) % n;
        if (&q[i] == apex || &q[j] == apex)
            continue;
        if (tri_agreement_u(apex, &q[i], &q[j], uapex, &pg->u[i], &pg->u[j]) < 0)
            return true;
    }
    return false;
}

/* Does the fan of the polygon around `apex` (one of its corners or a point off it, in the
 * node's faces apex_faces) hold a triangle lying in one of the node's faces (which the node
 * across it may emit as well)? Never without a node (no faces). */
static bool fan_in_face(const polygon *pg, const double *apex, unsigned apex_faces)
{
    const ism_fpoint *q = pg->q;
    size_t n = pg->n;
    for (size_t i = 0; apex_faces && i < n; i++) {
        size_t j = (i + 1) % n;
        if (q[i].p != apex && q[j].p != apex && /* a corner's own two edges */
            (apex_faces & pg->faces[i] & pg->faces[j]))
            return true;
    }
    return false;
}

/* The corner whose fan has the largest smallest angle, among the corners whose fan has no
 * turned-over triangle nor one lying in a face of the node (else the fewest such faults:
 * a fold before a face triangle); *in_face: the chosen fan has one of them; *folds: it has
 * a turned-over triangle (fan_folds). */
static size_t best_corner(polygon *pg, bool *in_face, bool *folds)
{
    const ism_fpoint *q = pg->q;
    size_t n = pg->n, best = 0;
    bool best_folds = false;
    double best_cos = HUGE_VAL; /* cos + 1 (face) + 2 (fold) may pass 3 */
    polygon_lengths(pg);
    for (size_t c = 0; c < n; c++) {
        /* a fan measured no better than the best so far is never chosen, and its faults
         * only add: the rest of its measure is skipped (the choice is the full measure's).
         * Its two ears (c, c + 1, c + 2 and c, c − 2, c − 1, measured already) come first:
         * the largest of a fan's measures is the same in any order (a NaN is never taken),
         * and a fan that reaches best_cos at all reaches it in any order, so only the work
         * skipped changes */
        double worst = pg->ear[(c + 1) % n], w = pg->ear[(c + n - 1) % n];
        worst = worst > -1 ? worst : -1; /* from -1, as the loop below takes them */
        if (w > worst)
            worst = w;
        for (size_t i = 2; i + 2 < n && worst < best_cos; i++) {
            w = tri_cos(pg, c, (c + i) % n, (c + i + 1) % n);
            if (w > worst)
                worst = w;
        }
        if (worst < best_cos && fan_in_face(pg, q[c].p, pg->faces[c]))
            worst += 1; /* only when every corner's fan has one */
        if (!(worst < best_cos))
            continue;
        bool f = fan_folds(pg, &q[c], &pg->u[c]);
        if (f)
            worst += 2; /* only when every corner's fan folds */
        if (worst < best_cos)
            best_cos = worst, best = c, best_folds = f;
    }
    *in_face = best_cos > 1;
    *folds = best_folds;
    return best;
}

static bool fan_from_corner(ism_cell_out *out, size_t base, size_t n, size_t c)
{
    uint32_t b = (uint32_t)base;
    if (!tris_reserve(out, n - 2))
        return false;
    for (size_t i = 1; i + 1 < n; i++)
        push_tri(out, b + (uint32_t)c, b + (uint32_t)((c + i) % n),
                 b + (uint32_t)((c + i + 1) % n));
    return true;
}

/* Twice the signed area of the triangle of plane points a, b, c (> 0: counter-clockwise). */
static double area2(const double a[2], const double b[2], const double c[2])
{
    return (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]);
}

/* Does plane point p lie in the closed triangle a, b, c (counter-clockwise), other than at a
 * corner's own place? */
static bool in_ear(const double p[2], const double a[2], const double b[2], const double c[2])
{
    const double *v[3] = {a, b, c};
    for (int k = 0; k < 3; k++)
        if (p[0] == v[k][0] && p[1] == v[k][1])
            return false;
    return area2(a, b, p) >= 0 && area2(b, c, p) >= 0 && area2(c, a, p) >= 0;
}

/* A polygon that no fan triangulates without turning a triangle over (every corner's fan
 * folds and the centre's does too; a strip bent round a node's edge, its side along a face
 * that finer neighbours tile, as the roof of Steiner's lens beside a pinch point at depth
 * 7, where the fan's apex sat on the strip's own reflex turn): its ears clipped in the plane
 * across its mean unit gradient, where it is wound counter-clockwise (ism_triangulate_loop's
 * winding). Each ear is a convex corner whose triangle holds no other corner in that plane
 * and keeps ∇f's side at its own corners; of those, the one with the largest smallest angle,
 * lying in none of the node's faces when one such exists. *emitted false (nothing emitted)
 * when no ear is left at some step: the caller fans from its best corner; false out of
 * memory. */
static bool clip_ears(ism_cell_out *out, size_t base, polygon *pg, bool *emitted)
{
    *emitted = false;
    const ism_fpoint *q = pg->q;
    const unit_g *ug = pg->u;
    size_t n = pg->n;
    double nrm[3] = {0, 0, 0}, e[2][3];
    for (size_t i = 0; i < n; i++)
        if (ug[i].ok)
            for (int k = 0; k < 3; k++)
                nrm[k] += ug[i].u[k];
    if (!(ism_normalise3(nrm) > 0))
        return true;
    ism_across_least3(nrm, e); /* (e[0], e[1], nrm) right-handed */
    polygon_lengths(pg);
    double (*uv)[2] = malloc(n * sizeof *uv);
    size_t *left = malloc(n * sizeof *left);
    bool ok = uv && left;
    for (size_t i = 0; ok && i < n; i++) {
        uv[i][0] = ism_dot3(q[i].p, e[0]);
        uv[i][1] = ism_dot3(q[i].p, e[1]);
        left[i] = i;
    }
    size_t m = n, t0 = out->ntris;
    uint32_t b0 = (uint32_t)base;
    while (ok && m >= 3) {
        size_t best = m;
        double best_score = HUGE_VAL;
        for (size_t i = 0; i < m; i++) {
            size_t a = left[(i + m - 1) % m], b = left[i], c = left[(i + 1) % m];
            if (!(area2(uv[a], uv[b], uv[c]) > 0) ||
                !(tri_agreement_u(&q[a], &q[b], &q[c], &ug[a], &ug[b], &ug[c]) > 0))
                continue;
            bool empty = true;
            for (size_t j = 0; j < m && empty; j++)
                if (j != (i + m - 1) % m && j != i && j != (i + 1) % m)
                    empty = !in_ear(uv[left[j]], uv[a], uv[b], uv[c]);
            if (!empty)
                continue;
            double score = tri_cos(pg, a, b, c) + (tri_in_face(pg, a, b, c) ? 2 : 0);
            if (score < best_score)
                best_score = score, best = i;
        }
        if (best == m) { /* no ear: the polygon is not simple in that plane; none emitted */
            out->ntris = t0;
            free(uv);
            free(left);
            return true;
        }
        /* q stays valid: emitting grows the triangles, never the vertices */
        ok = ism_cell_out_tri(out, b0 + (uint32_t)left[(best + m - 1) % m],
                              b0 + (uint32_t)left[best], b0 + (uint32_t)left[(best + 1) % m]);
        memmove(left + best, left + best + 1, (m - best - 1) * sizeof *left);
        m--;
    }
    *emitted = ok;
    free(uv);
    free(left);
    return ok;
}

/* The fan from the best corner — or, when that fan folds, the polygon's ears (clip_ears). */
static bool fan_from_best_corner(ism_cell_out *out, size_t base, polygon *pg)
{
    bool in_face, folds, emitted;
    size_t c = best_corner(pg, &in_face, &folds);
    if (folds) {
        if (!clip_ears(out, base, pg, &emitted))
            return false;
        if (emitted)
            return true;
    }
    return fan_from_corner(out, base, pg->n, c);
}

/* The points corner_fan_error measures at once: a fan's centroids and diagonals' middles
 * are 2n − 5 for n corners, so a polygon of up to 10 corners in one batch of
 * ISM_GRAD_UNROLLED lanes (eval.h: one pass of the tape). */
#define FAN_POINTS ISM_GRAD_UNROLLED
_Static_assert(FAN_POINTS >= 2, "a triangle's centroid and diagonal in one batch, or no progress");

/* ism_sample_dist_between at p between the corners v[0..n), f and g = ∇f at p given. */
static double fan_point_dist(ism_sampler *s, const double p[3], double f, const double g[3],
                             const double *const *v, int n)
{
    return ism_dist_beyond(s, p, ism_plain_dist(s, p, f, g, s->dist_above), v, n);
}

/* The largest distance to f = 0 at the centroids of the fan of q[0..n) from corner c and at
 * the middles of its diagonals (its sides are the polygon's, whatever the triangulation),
 * stopping once it passes bound. f and ∇f at the points are evaluated FAN_POINTS at a time
 * (ism_sample_grad_batch: bit for bit ism_sample_grad's values one at a time), the rest of
 * ism_sample_dist_between point by point in the fan's order; a fan that passes the bound
 * early leaves the rest of its batch unread (counted in s->n_gradient though unread: the
 * --stats gradient count, not the mesh). Not inlined: its batch's room on the stack of
 * every polygon's call cost Barth 0.0259, which seldom fans from a corner, 16 instructions a
 * polygon. */
static __attribute__((noinline)) double corner_fan_error(ism_sampler *s, const ism_fpoint *q,
                                                         size_t n, size_t c, double bound)
{
    double worst = 0;
    const double *a = q[c].p;
    for (size_t i = 1; i + 1 < n && worst <= bound;) {
        double m[FAN_POINTS][3], f[FAN_POINTS], g[FAN_POINTS][3];
        size_t k = 0, last = i; /* triangles i .. last − 1 measured in this batch */
        for (; last + 1 < n && k + 2 <= FAN_POINTS; last++) {
            const double *b = q[(c + last) % n].p, *e = q[(c + last + 1) % n].p;
            for (int j = 0; j < 3; j++)
                m[k][j] = (a[j] + b[j] + e[j]) / 3;
            k++;
            if (last + 2 < n) { /* a-e is a diagonal */
                for (int j = 0; j < 3; j++)
                    m[k][j] = 0.5 * (a[j] + e[j]);
                k++;
            }
        }
        ism_sample_grad_batch(s, (const double (*)[3])m, f, g, k);
        for (k = 0; i < last && worst <= bound; i++) {
            const double *b = q[(c + i) % n].p, *e = q[(c + i + 1) % n].p;
            worst = fmax(worst, fan_point_dist(s, m[k], f[k], g[k], (const double *[3]){a, b, e},
                                               3));
            k++;
            if (i + 2 < n) {
                worst = fmax(worst, fan_point_dist(s, m[k], f[k], g[k], (const double *[2]){a, e},
                                                   2));
                k++;
            }
        }
    }
    return worst;
}

/* Under max_error, a polygon of five or more corners fanned from its best corner (n − 2
 * triangles) rather than from its centre (n triangles and one more vertex) when that fan
 * measures within the bound; false (and nothing emitted) when it does not. The sphere at
 * E = 7.9e-4 (box ±1.5): 21,224 -> 17,192 triangles, max centroid distance 6.5e-4 -> 6.7e-4;
 * the gyroid ball at 0.0334: 22,612 -> 17,236. */
static bool corner_fan_within(ism_sampler *s, ism_cell_out *out, size_t base, polygon *pg,
                              double max_error, bool *emitted)
{
    *emitted = false;
    bool in_face, folds;
    size_t c = best_corner(pg, &in_face, &folds);
    if (in_face || corner_fan_error(s, pg->q, pg->n, c, max_error) > max_error)
        return true;
    *emitted = true;
    return fan_from_corner(out, base, pg->n, c);
}

/* A quadrilateral along its shorter diagonal, unless that leaves a triangle lying in a face
 * of the node or the fan along it folds where the other's does not (a quad not convex: the
 * other diagonal keeps the orientation). */
static bool split_quad(ism_cell_out *out, uint32_t b, const polygon *pg)
{
    const ism_fpoint *q = pg->q;
    bool first = ism_dist3(q[0].p, q[2].p) <= ism_dist3(q[1].p, q[3].p);
    if (tri_in_face(pg, 0, 1, 2) || tri_in_face(pg, 0, 2, 3))
        first = false;
    else if (tri_in_face(pg, 1, 2, 3) || tri_in_face(pg, 1, 3, 0))
        first = true;
    else if (fan_folds(pg, &q[first ? 0 : 1], &pg->u[first ? 0 : 1]) &&
             !fan_folds(pg, &q[first ? 1 : 0], &pg->u[first ? 1 : 0]))
        first = !first;
    if (!tris_reserve(out, 2))
        return false;
    if (first) {
        push_tri(out, b, b + 1, b + 2);
        push_tri(out, b, b + 2, b + 3);
    } else {
        push_tri(out, b + 1, b + 2, b + 3);
        push_tri(out, b + 1, b + 3, b);
    }
    return true;
}

/* A polygon of four or more points, emitted at base: split, fanned from a corner under the
 * error bound, fanned from its centre, or else from its best corner. */
static bool triangulate_polygon(ism_sampler *s, ism_cell_out *out, size_t base, polygon *pg,
                                double reach, const double node[6], double max_error)
{
    uint32_t b = (uint32_t)base;
    size_t n = pg->n;
    if (n == 4)
        return split_quad(out, b, pg);
    bool emitted = false;
    if (max_error > 0 && !corner_fan_within(s, out, base, pg, max_error, &emitted))
        return false;
    if (emitted)
        return true;
    ism_fpoint c;
    unit_g uc;
    if (!centre_point(s, pg->q, n, reach, node, &c) ||
        fan_in_face(pg, c.p, point_faces(node, &c)) ||
        (unit_gradient(&c, &uc), fan_folds(pg, &c, &uc)))
        return fan_from_best_corner(out, base, pg);
    uint32_t ci;
    if (!ism_cell_out_vert(out, &c, &ci)) /* pg->q is not read again: this may move it */
        return false;
    if (!tris_reserve(out, n))
        return false;
    for (size_t i = 0; i < n; i++)
        push_tri(out, ci, b + (uint32_t)i, b + (uint32_t)((i + 1) % n));
    return true;
}

bool ism_loop_reversed(ism_sampler *s, const double node[6], const ism_fpoint *pts, size_t n)
{
    return n >= 3 && reversed(s, node, pts, n, NULL);
}

static bool wound(ism_sampler *s, const ism_fpoint *pts, size_t n, double reach,
                  const double node[6], double max_error, bool flip, const unit_g *pts_units,
                  ism_cell_out *out);

bool ism_triangulate_loop(ism_sampler *s, const ism_fpoint *pts, size_t n, double reach,
                          const double node[6], double max_error, ism_cell_out *out)
{
    if (n < 3)
        return true;
    unit_g units_in[UNIT_STACK], *units = units_in;
    if (n > UNIT_STACK && !(units = malloc(n * sizeof *units)))
        return false;
    bool flip = reversed(s, node, pts, n, units);
    bool ok = wound(s, pts, n, reach, node, max_error, flip, units, out);
    if (units != units_in)
        free(units);
    return ok;
}

bool ism_triangulate_wound(ism_sampler *s, const ism_fpoint *pts, size_t n, double reach,
                           const double node[6], double max_error, bool flip, ism_cell_out *out)
{
    return wound(s, pts, n, reach, node, max_error, flip, NULL, out);
}

/* ism_triangulate_wound, with pts' unit gradients in pts_units (pts' order; NULL: worked
 * out here). */
static bool wound(ism_sampler *s, const ism_fpoint *pts, size_t n, double reach,
                  const double node[6], double max_error, bool flip, const unit_g *pts_units,
                  ism_cell_out *out)
{
    if (n < 3)
        return true;
    size_t base = out->nverts;
    if (!out_polygon(out, pts, n, flip))
        return false;
    uint32_t b = (uint32_t)base;
    if (n == 3)
        return ism_cell_out_tri(out, b, b + 1, b + 2);
    unit_g u_in[UNIT_STACK];
    uint8_t faces_in[UNIT_STACK];
    double len_in[UNIT_STACK * UNIT_STACK], ear_in[UNIT_STACK];
    polygon pg = {out->verts + base, n, u_in, faces_in, len_in, ear_in, false};
    bool heap = n > UNIT_STACK;
    if (heap) {
        pg.u = malloc(n * sizeof *pg.u);
        pg.faces = malloc(n * sizeof *pg.faces);
        pg.len = malloc(n * n * sizeof *pg.len);
        pg.ear = malloc(n * sizeof *pg.ear);
    }
    bool ok = pg.u && pg.faces && pg.len && pg.ear;
    if (ok) {
        for (size_t i = 0; i < n; i++) /* in the emitted order, as out_polygon's */
            if (pts_units)
                pg.u[i] = pts_units[flip ? n - 1 - i : i];
            else
                unit_gradient(&pg.q[i], &pg.u[i]);
        if (node)
            ism_face_masks(node, pg.q, n, pg.faces);
        else
            memset(pg.faces, 0, n * sizeof *pg.faces);
    }
    ok = ok && triangulate_polygon(s, out, base, &pg, reach, node, max_error);
    if (heap) {
        free(pg.u);
        free(pg.faces);
        free(pg.len);
        free(pg.ear);
    }
    return ok;
}

static bool fan(const ism_fpoint *pts, size_t n, const ism_fpoint *apex, bool flip,
                ism_cell_out *out)
{
    size_t base = out->nverts;
    if (!out_polygon(out, pts, n, flip))
        return false;
    uint32_t a;
    if (!ism_cell_out_vert(out, apex, &a))
        return false;
    uint32_t b = (uint32_t)base;
    size_t edges = n == 2 ? 1 : n; /* a one-edge polygon gives one triangle */
    if (!tris_reserve(out, edges))
        return false;
    for (size_t i = 0; i < edges; i++)
        push_tri(out, a, b + (uint32_t)i, b + (uint32_t)((i + 1) % n));
    return true;
}

bool ism_triangulate_fan(const ism_fpoint *pts, size_t n, const ism_fpoint *apex,
                         ism_cell_out *out)
{
    if (n < 2)
        return true;
    return fan(pts, n, apex, n >= 3 && reversed(NULL, NULL, pts, n, NULL), out);
}

bool ism_triangulate_tent(const ism_fpoint *pts, size_t n, const ism_fpoint *apex,
                          ism_cell_out *out)
{
    if (n < 3)
        return true;
    double sum = 0; /* the fan's triangles against ∇f, in the polygon's order */
    for (size_t i = 0; i < n; i++)
        sum += tri_agreement(apex, &pts[i], &pts[(i + 1) % n]);
    return fan(pts, n, apex, sum < 0, out);
}
