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
 * gradient (its norm > 0): each polygon's points are normalised once, and every test that
 * sums unit gradients (reversed, tri_agreement) reads them in its own order. */
typedef struct unit_g {
    double u[3];
    bool ok;
} unit_g;

/* Polygons of up to this many points keep their unit gradients on the stack; a larger one
 * (a coarse node's face crossed by finer neighbours' tiles) normalises them as it goes. */
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
 * (one capacity check for the polygon). */
static bool out_polygon(ism_cell_out *o, const ism_fpoint *pts, size_t n, bool flip)
{
    if (!out_reserve(o, n))
        return false;
    for (size_t i = 0; i < n; i++)
        o->verts[o->nverts++] = pts[flip ? n - 1 - i : i];
    return true;
}

bool ism_cell_out_tri(ism_cell_out *o, uint32_t a, uint32_t b, uint32_t c)
{
    if (!ism_grow((void **)&o->tris, &o->cap_tris, o->ntris + 1, 3 * sizeof *o->tris, 256))
        return false;
    uint32_t *t = o->tris + 3 * o->ntris++;
    t[0] = a, t[1] = b, t[2] = c;
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

static double min_angle_cos(const double *a, const double *b, const double *c)
{
    const double *v[3] = {a, b, c};
    double worst = -1;
    for (int k = 0; k < 3; k++) {
        const double *o = v[k], *p = v[(k + 1) % 3], *q = v[(k + 2) % 3];
        double u[3] = {p[0] - o[0], p[1] - o[1], p[2] - o[2]};
        double w[3] = {q[0] - o[0], q[1] - o[1], q[2] - o[2]};
        double nu = ism_norm3(u), nw = ism_norm3(w);
        double cs = nu > 0 && nw > 0 ? ism_dot3(u, w) / (nu * nw) : 1;
        if (cs > worst)
            worst = cs;
    }
    return worst; /* cos of the smallest angle: larger is worse */
}

/* Triangle a, b, c's normal against the mean unit gradient at its corners (their unit
 * gradients ua, ub, uc): > 0 when it keeps the surface's orientation, < 0 when it is turned
 * over, 0 when degenerate. */
static double tri_agreement_u(const ism_fpoint *a, const ism_fpoint *b, const ism_fpoint *c,
                              const unit_g *ua, const unit_g *ub, const unit_g *uc)
{
    const unit_g *v[3] = {ua, ub, uc};
    double e1[3], e2[3], nrm[3], g[3] = {0, 0, 0};
    for (int k = 0; k < 3; k++) {
        e1[k] = b->p[k] - a->p[k];
        e2[k] = c->p[k] - a->p[k];
    }
    ism_cross3(e1, e2, nrm);
    for (int j = 0; j < 3; j++)
        if (v[j]->ok)
            for (int k = 0; k < 3; k++)
                g[k] += v[j]->u[k];
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

/* The unit gradient of q[i] (units[i] when units is not NULL, else computed into *tmp). */
static const unit_g *unit_of(const ism_fpoint *q, const unit_g *units, size_t i, unit_g *tmp)
{
    if (units)
        return &units[i];
    unit_gradient(&q[i], tmp);
    return tmp;
}

/* Does the fan of q[0..n) (wound to agree with ∇f) around apex — one of its corners or a
 * point off it — hold a turned-over triangle? A fan from a corner of a polygon that is not
 * star-shaped from it (a reflex corner across, as where the polygon runs along a node's
 * face) folds back: the sphere at E = 2e-3, depth 8, box 0.37 cell off the lattice had 4. */
static bool fan_folds(const ism_fpoint *q, const unit_g *units, size_t n, const ism_fpoint *apex,
                      const unit_g *uapex)
{
    for (size_t i = 0; i < n; i++) {
        const ism_fpoint *a = &q[i], *b = &q[(i + 1) % n];
        if (a == apex || b == apex)
            continue;
        unit_g ta, tb;
        const unit_g *ua = unit_of(q, units, i, &ta), *ub = unit_of(q, units, (i + 1) % n, &tb);
        if (tri_agreement_u(apex, a, b, uapex, ua, ub) < 0)
            return true;
    }
    return false;
}

/* Does the fan of out->verts[base .. base + n) around vertex `apex` hold a triangle lying in
 * one of the node's faces (which the node across it may emit as well)? Never without node. */
static bool fan_in_face(const ism_cell_out *out, size_t base, size_t n, const double *apex,
                        const double node[6])
{
    const ism_fpoint *q = out->verts + base;
    for (size_t i = 0; node && i < n; i++)
        if (q[i].p != apex && q[(i + 1) % n].p != apex && /* a corner's own two edges */
            ism_in_one_face(node, apex, q[i].p, q[(i + 1) % n].p))
            return true;
    return false;
}

/* The corner whose fan has the largest smallest angle, among the corners whose fan has no
 * turned-over triangle nor one lying in a face of the node (else the fewest such faults:
 * a fold before a face triangle); *in_face: the chosen fan has one of them; *folds: it has
 * a turned-over triangle (fan_folds). units: the polygon's unit gradients, or NULL. */
static size_t best_corner(const ism_cell_out *out, size_t base, size_t n, const double node[6],
                          const unit_g *units, bool *in_face, bool *folds)
{
    const ism_fpoint *q = out->verts + base;
    size_t best = 0;
    bool best_folds = false;
    double best_cos = HUGE_VAL; /* cos + 1 (face) + 2 (fold) may pass 3 */
    for (size_t c = 0; c < n; c++) {
        /* a fan measured no better than the best so far is never chosen, and its faults
         * only add: the rest of its measure is skipped (the choice is the full measure's) */
        double worst = -1;
        for (size_t i = 1; i + 1 < n && worst < best_cos; i++) {
            double w = min_angle_cos(q[c].p, q[(c + i) % n].p, q[(c + i + 1) % n].p);
            if (w > worst)
                worst = w;
        }
        if (worst < best_cos && fan_in_face(out, base, n, q[c].p, node))
            worst += 1; /* only when every corner's fan has one */
        if (!(worst < best_cos))
            continue;
        unit_g tc;
        bool f = fan_folds(q, units, n, &q[c], unit_of(q, units, c, &tc));
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
    for (size_t i = 1; i + 1 < n; i++)
        if (!ism_cell_out_tri(out, b + (uint32_t)c, b + (uint32_t)((c + i) % n),
                      b + (uint32_t)((c + i + 1) % n)))
            return false;
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
static bool clip_ears(ism_cell_out *out, size_t base, size_t n, const double node[6],
                      bool *emitted)
{
    *emitted = false;
    const ism_fpoint *q = out->verts + base;
    double nrm[3] = {0, 0, 0}, e[2][3];
    for (size_t i = 0; i < n; i++) {
        double u[3] = {q[i].g[0], q[i].g[1], q[i].g[2]};
        if (ism_normalise3(u) > 0)
            for (int k = 0; k < 3; k++)
                nrm[k] += u[k];
    }
    if (!(ism_normalise3(nrm) > 0))
        return true;
    ism_across_least3(nrm, e); /* (e[0], e[1], nrm) right-handed */
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
            if (!(area2(uv[a], uv[b], uv[c]) > 0) || !(tri_agreement(&q[a], &q[b], &q[c]) > 0))
                continue;
            bool empty = true;
            for (size_t j = 0; j < m && empty; j++)
                if (j != (i + m - 1) % m && j != i && j != (i + 1) % m)
                    empty = !in_ear(uv[left[j]], uv[a], uv[b], uv[c]);
            if (!empty)
                continue;
            double score = min_angle_cos(q[a].p, q[b].p, q[c].p) +
                           (node && ism_in_one_face(node, q[a].p, q[b].p, q[c].p) ? 2 : 0);
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
static bool fan_from_best_corner(ism_cell_out *out, size_t base, size_t n, const double node[6],
                                 const unit_g *units)
{
    bool in_face, folds, emitted;
    size_t c = best_corner(out, base, n, node, units, &in_face, &folds);
    if (folds) {
        if (!clip_ears(out, base, n, node, &emitted))
            return false;
        if (emitted)
            return true;
    }
    return fan_from_corner(out, base, n, c);
}

/* The largest distance to f = 0 at the centroids of the fan of q[0..n) from corner c and at
 * the middles of its diagonals (its sides are the polygon's, whatever the triangulation),
 * stopping once it passes bound. */
static double corner_fan_error(ism_sampler *s, const ism_fpoint *q, size_t n, size_t c,
                               double bound)
{
    double worst = 0;
    const double *a = q[c].p;
    for (size_t i = 1; i + 1 < n && worst <= bound; i++) {
        const double *b = q[(c + i) % n].p, *d = q[(c + i + 1) % n].p;
        double m[3];
        for (int k = 0; k < 3; k++)
            m[k] = (a[k] + b[k] + d[k]) / 3;
        worst = fmax(worst, ism_sample_dist_between(s, m, (const double *[3]){a, b, d}, 3));
        if (i + 2 < n) { /* a-d is a diagonal */
            for (int k = 0; k < 3; k++)
                m[k] = 0.5 * (a[k] + d[k]);
            worst = fmax(worst, ism_sample_dist_between(s, m, (const double *[2]){a, d}, 2));
        }
    }
    return worst;
}

/* Under max_error, a polygon of five or more corners fanned from its best corner (n − 2
 * triangles) rather than from its centre (n triangles and one more vertex) when that fan
 * measures within the bound; false (and nothing emitted) when it does not. The sphere at
 * E = 7.9e-4 (box ±1.5): 21,224 -> 17,192 triangles, max centroid distance 6.5e-4 -> 6.7e-4;
 * the gyroid ball at 0.0334: 22,612 -> 17,236. */
static bool corner_fan_within(ism_sampler *s, ism_cell_out *out, size_t base, size_t n,
                              const double node[6], double max_error, const unit_g *units,
                              bool *emitted)
{
    *emitted = false;
    bool in_face, folds;
    size_t c = best_corner(out, base, n, node, units, &in_face, &folds);
    if (in_face || corner_fan_error(s, out->verts + base, n, c, max_error) > max_error)
        return true;
    *emitted = true;
    return fan_from_corner(out, base, n, c);
}

/* fan_folds of the quad q from its corner c. */
static bool quad_folds(const ism_fpoint *q, const unit_g *units, size_t c)
{
    unit_g tc;
    return fan_folds(q, units, 4, &q[c], unit_of(q, units, c, &tc));
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
    if (n < 3 || n > UNIT_STACK)
        return ism_triangulate_wound(s, pts, n, reach, node, max_error,
                                     ism_loop_reversed(s, node, pts, n), out);
    unit_g units[UNIT_STACK];
    bool flip = reversed(s, node, pts, n, units);
    return wound(s, pts, n, reach, node, max_error, flip, units, out);
}

bool ism_triangulate_wound(ism_sampler *s, const ism_fpoint *pts, size_t n, double reach,
                           const double node[6], double max_error, bool flip, ism_cell_out *out)
{
    return wound(s, pts, n, reach, node, max_error, flip, NULL, out);
}

/* ism_triangulate_wound, with pts' unit gradients in pts_units (pts' order; NULL: each
 * normalised where it is needed, n ≤ UNIT_STACK when not NULL). */
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
    unit_g units_in[UNIT_STACK], *units = NULL; /* in the emitted order, as out_polygon's */
    if (pts_units) {
        units = units_in;
        for (size_t i = 0; i < n; i++)
            units[i] = pts_units[flip ? n - 1 - i : i];
    }
    if (n == 4) {
        /* along the shorter diagonal, unless that leaves a triangle lying in a face */
        const ism_fpoint *q = out->verts + base;
        bool first = ism_dist3(q[0].p, q[2].p) <= ism_dist3(q[1].p, q[3].p);
        if (node && (ism_in_one_face(node, q[0].p, q[1].p, q[2].p) ||
                     ism_in_one_face(node, q[0].p, q[2].p, q[3].p)))
            first = false;
        else if (node && (ism_in_one_face(node, q[1].p, q[2].p, q[3].p) ||
                          ism_in_one_face(node, q[1].p, q[3].p, q[0].p)))
            first = true;
        else if (quad_folds(q, units, first ? 0 : 1) && !quad_folds(q, units, first ? 1 : 0))
            first = !first; /* a quad not convex: the other diagonal keeps the orientation */
        if (first)
            return ism_cell_out_tri(out, b, b + 1, b + 2) && ism_cell_out_tri(out, b, b + 2, b + 3);
        return ism_cell_out_tri(out, b + 1, b + 2, b + 3) && ism_cell_out_tri(out, b + 1, b + 3, b);
    }
    bool emitted = false;
    if (max_error > 0 &&
        !corner_fan_within(s, out, base, n, node, max_error, units, &emitted))
        return false;
    if (emitted)
        return true;
    ism_fpoint c;
    unit_g uc;
    if (!centre_point(s, out->verts + base, n, reach, node, &c) ||
        fan_in_face(out, base, n, c.p, node) ||
        (unit_gradient(&c, &uc), fan_folds(out->verts + base, units, n, &c, &uc)))
        return fan_from_best_corner(out, base, n, node, units);
    uint32_t ci;
    if (!ism_cell_out_vert(out, &c, &ci))
        return false;
    for (size_t i = 0; i < n; i++)
        if (!ism_cell_out_tri(out, ci, b + (uint32_t)i, b + (uint32_t)((i + 1) % n)))
            return false;
    return true;
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
    for (size_t i = 0; i < edges; i++)
        if (!ism_cell_out_tri(out, a, b + (uint32_t)i, b + (uint32_t)((i + 1) % n)))
            return false;
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
