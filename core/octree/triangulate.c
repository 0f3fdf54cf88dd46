/* triangulate.c — triangles from stitched polygons. A triangle or quadrilateral is split
 * directly (a quad along its shorter diagonal); a larger polygon (crack repair puts extra
 * points on coarse nodes' faces) is fanned around its centre, projected onto f = 0 by a few
 * Newton steps along ∇f. Each polygon is wound so that its normal agrees with the mean
 * gradient at its points: consistent orientation wherever ∇f does. */
#include "core/octree/triangulate.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

static bool push_vert(ism_cell_out *o, const ism_fpoint *p, uint32_t *idx)
{
    if (o->nverts == o->cap_verts) {
        size_t c = o->cap_verts ? o->cap_verts * 2 : 256;
        ism_fpoint *v = realloc(o->verts, c * sizeof *v);
        if (!v)
            return false;
        o->verts = v;
        o->cap_verts = c;
    }
    *idx = (uint32_t)o->nverts;
    o->verts[o->nverts++] = *p;
    return true;
}

static bool push_tri(ism_cell_out *o, uint32_t a, uint32_t b, uint32_t c)
{
    if (o->ntris == o->cap_tris) {
        size_t cap = o->cap_tris ? o->cap_tris * 2 : 256;
        uint32_t *v = realloc(o->tris, cap * 3 * sizeof *v);
        if (!v)
            return false;
        o->tris = v;
        o->cap_tris = cap;
    }
    uint32_t *t = o->tris + 3 * o->ntris++;
    t[0] = a, t[1] = b, t[2] = c;
    return true;
}

bool ism_cell_out_segment(ism_cell_out *out, const ism_fpoint *a, const ism_fpoint *b)
{
    uint32_t ia, ib;
    if (!push_vert(out, a, &ia) || !push_vert(out, b, &ib))
        return false;
    if (out->nsegs == out->cap_segs) {
        size_t c = out->cap_segs ? out->cap_segs * 2 : 16;
        uint32_t *v = realloc(out->segs, c * 2 * sizeof *v);
        if (!v)
            return false;
        out->segs = v;
        out->cap_segs = c;
    }
    out->segs[2 * out->nsegs] = ia;
    out->segs[2 * out->nsegs + 1] = ib;
    out->nsegs++;
    return true;
}

/* Newell's normal of the polygon (twice its vector area). */
static void newell(const ism_fpoint *p, size_t n, double nrm[3])
{
    nrm[0] = nrm[1] = nrm[2] = 0;
    for (size_t i = 0; i < n; i++) {
        const double *a = p[i].p, *b = p[(i + 1) % n].p;
        nrm[0] += (a[1] - b[1]) * (a[2] + b[2]);
        nrm[1] += (a[2] - b[2]) * (a[0] + b[0]);
        nrm[2] += (a[0] - b[0]) * (a[1] + b[1]);
    }
}

static bool reversed(const ism_fpoint *p, size_t n)
{
    double nrm[3], g[3] = {0, 0, 0};
    newell(p, n, nrm);
    for (size_t i = 0; i < n; i++) {
        double u[3] = {p[i].g[0], p[i].g[1], p[i].g[2]};
        if (ism_normalise3(u) > 0)
            for (int k = 0; k < 3; k++)
                g[k] += u[k];
    }
    return ism_dot3(nrm, g) < 0;
}

/* The polygon's centre moved onto f = 0 (when Newton converges close by). */
static void centre_point(ism_sampler *s, const ism_fpoint *p, size_t n, double reach,
                         ism_fpoint *c)
{
    double m[3] = {0, 0, 0};
    for (size_t i = 0; i < n; i++)
        for (int k = 0; k < 3; k++)
            m[k] += p[i].p[k] / (double)n;
    double q[3] = {m[0], m[1], m[2]}, g[3];
    for (int it = 0; it < 4; it++) {
        double f = ism_sample_grad(s, q, g);
        double gg = ism_dot3(g, g);
        if (!(gg > 0) || !isfinite(f) || !isfinite(gg))
            break;
        for (int k = 0; k < 3; k++)
            q[k] -= f * g[k] / gg;
    }
    double moved = ism_dist3(q, m);
    bool ok = isfinite(moved) && moved <= reach;
    memcpy(c->p, ok ? q : m, sizeof c->p);
    ism_sample_grad(s, c->p, c->g);
    c->flags = ISM_FP_INTERIOR;
}

bool ism_triangulate_loop(ism_sampler *s, const ism_fpoint *pts, size_t n, double reach,
                          ism_cell_out *out)
{
    if (n < 3)
        return true;
    bool flip = reversed(pts, n);
    size_t base = out->nverts;
    for (size_t i = 0; i < n; i++) {
        uint32_t idx;
        if (!push_vert(out, &pts[flip ? n - 1 - i : i], &idx))
            return false;
    }
    uint32_t b = (uint32_t)base;
    if (n == 3)
        return push_tri(out, b, b + 1, b + 2);
    if (n == 4) {
        const ism_fpoint *q = out->verts + base;
        if (ism_dist3(q[0].p, q[2].p) <= ism_dist3(q[1].p, q[3].p))
            return push_tri(out, b, b + 1, b + 2) && push_tri(out, b, b + 2, b + 3);
        return push_tri(out, b + 1, b + 2, b + 3) && push_tri(out, b + 1, b + 3, b);
    }
    ism_fpoint c;
    centre_point(s, out->verts + base, n, reach, &c);
    uint32_t ci;
    if (!push_vert(out, &c, &ci))
        return false;
    for (size_t i = 0; i < n; i++)
        if (!push_tri(out, ci, b + (uint32_t)i, b + (uint32_t)((i + 1) % n)))
            return false;
    return true;
}
