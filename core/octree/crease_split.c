/* crease_split.c — a leaf's triangles cut where f's top min/max changes branch (see
 * crease_split.h). */
#include "core/octree/crease_split.h"
#include "core/octree/triangulate.h"
#include "core/util/min_norm.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

/* Newton steps toward a = b = 0 from the edge's linear estimate: quadratic convergence
 * reaches rounding in 4-5 on a transversal crease; more do not help where the branches
 * are tangent (the linear estimate is kept then). */
#define CREASE_NEWTON_STEPS 8
/* A Newton result farther than this many edge lengths from the edge is not the edge's
 * crease point (a distant part of the crease curve): the linear estimate is kept. */
#define CREASE_REACH_EDGES 1.0
/* The branches' gradients count as parallel (no crease line through x, the 2 × 2 normal
 * system singular) when |ga|²|gb|² − (ga·gb)² is below this share of |ga|²|gb|²: a sine
 * of the crossing angle under 1e-6 rad, where a step would run along the crease. */
#define CREASE_PARALLEL_SIN2 1e-12

/* Branch labels of a leaf's vertices kept on the stack up to this many vertices (a leaf
 * emits a few dozen); more take the heap. */
#define LABELS_ON_STACK 256
/* A vertex whose branch is not looked up yet. */
#define LABEL_UNKNOWN 2

/* Does t still end in f's top min/max (not decided by the intervals it was shortened by)? */
static bool top_undecided(const ism_tape *t)
{
    static const double any[2] = {0, 0};
    return ism_top_active_branch(t, any) >= 0;
}

/* The tape whose top min/max gives f's branches at p bit for bit: the leaf's shortened one
 * inside its box while it keeps that min/max (its operands are then computed as f's are, by
 * the same instructions or by a min/max decided strictly), else f's. */
static const ism_tape *top_tape(const ism_sampler *s, const double p[3])
{
    const ism_tape *t = ism_sampler_tape_at(s, p);
    return t == s->local && !top_undecided(t) ? s->tape : t;
}

int ism_crease_branch(ism_sampler *s, const double p[3], double g[3])
{
    double v[2], bg[2][3];
    const ism_tape *t = top_tape(s, p);
    if (!g) { /* the label alone: values, no gradients */
        s->n_point++;
        if (!ism_eval_top_values(t, s->ws, p[0], p[1], p[2], v))
            return -1;
        return ism_top_active_branch(t, v);
    }
    s->n_gradient++;
    if (!ism_eval_top_branches(t, s->ws, p[0], p[1], p[2], v, bg))
        return -1;
    int b = ism_top_active_branch(t, v);
    memcpy(g, bg[b], sizeof bg[b]);
    return b;
}

static bool before(const double *a, const double *b)
{
    for (int k = 0; k < 3; k++)
        if (a[k] != b[k])
            return a[k] < b[k];
    return false;
}

/* One minimum-norm Newton step on (a, b) = 0 from x; false when the branches' gradients
 * are parallel there or a value is not finite. */
static bool newton_step(ism_sampler *s, double x[3])
{
    double v[2], g[2][3];
    s->n_gradient++;
    ism_eval_top_branches(top_tape(s, x), s->ws, x[0], x[1], x[2], v, g);
    double step[3];
    if (!isfinite(v[0]) || !isfinite(v[1]) ||
        !ism_min_norm_step(2, (const double (*)[3])g, v, CREASE_PARALLEL_SIN2, step))
        return false;
    for (int k = 0; k < 3; k++)
        x[k] += step[k];
    return true;
}

/* CREASE_NEWTON_STEPS steps from x (false when one fails), ending early where x comes back
 * to where it was two steps before — a fixed point, or a 2-cycle of rounding: the steps left
 * would only repeat those two, so the last one's result is known. */
bool ism_crease_newton(ism_sampler *s, double x[3])
{
    double back[2][3]; /* back[it % 2]: x before step it */
    for (int it = 0; it < CREASE_NEWTON_STEPS; it++) {
        memcpy(back[it % 2], x, sizeof back[0]);
        if (!newton_step(s, x))
            return false;
        if (it >= 1 && memcmp(x, back[(it + 1) % 2], sizeof back[0]) == 0) {
            if ((CREASE_NEWTON_STEPS - it - 1) % 2)
                memcpy(x, back[it % 2], sizeof back[0]);
            return true;
        }
    }
    return true;
}

/* The crease point of edge p-q (branches differ at its ends): Newton on a = b = 0 from
 * where a - b changes sign along the edge, or that linear estimate itself. */
static void crease_point(ism_sampler *s, const double *p0, const double *q0, ism_fpoint *out)
{
    const double *p = before(q0, p0) ? q0 : p0, *q = p == p0 ? q0 : p0;
    double v[2], d[2];
    const double *ends[2] = {p, q};
    for (int e = 0; e < 2; e++) {
        s->n_point++;
        ism_eval_top_values(top_tape(s, ends[e]), s->ws, ends[e][0], ends[e][1], ends[e][2], v);
        d[e] = v[0] - v[1];
    }
    double t = d[0] / (d[0] - d[1]);
    if (!(t >= 0 && t <= 1))
        t = 0.5;
    double lin[3], x[3];
    for (int k = 0; k < 3; k++)
        lin[k] = x[k] = p[k] + t * (q[k] - p[k]);
    bool ok = ism_crease_newton(s, x);
    if (!ok || !(ism_dist3(x, lin) <= CREASE_REACH_EDGES * ism_dist3(p, q))) {
        memcpy(x, lin, sizeof x); /* onto f = 0 along ∇f at least */
        for (int it = 0; it < CREASE_NEWTON_STEPS; it++) {
            double gf[3];
            double f = ism_sample_grad(s, x, gf), gg = ism_dot3(gf, gf);
            if (!(gg > 0) || !isfinite(f))
                break;
            for (int k = 0; k < 3; k++)
                x[k] -= f * gf[k] / gg;
        }
        if (!(ism_dist3(x, lin) <= CREASE_REACH_EDGES * ism_dist3(p, q)))
            memcpy(x, ism_dist3(lin, p) <= ism_dist3(lin, q) ? p : q, sizeof x);
    }
    memcpy(out->p, x, sizeof out->p);
    ism_sample_grad(s, x, out->g);
    out->flags = ISM_FP_INTERIOR;
}

/* The branch of vertex v (labels[v - first], looked up once). */
static int vertex_branch(ism_sampler *s, const ism_cell_out *out, uint8_t *labels,
                         uint32_t first, uint32_t v)
{
    uint8_t *l = &labels[v - first];
    if (*l == LABEL_UNKNOWN)
        *l = (uint8_t)ism_crease_branch(s, out->verts[v].p, NULL);
    return *l;
}

/* Splits triangles first_tri..ntris - 1, whose vertices lie in first..first + n - 1 (labels:
 * n entries of LABEL_UNKNOWN). */
static bool split_labelled(ism_sampler *s, ism_cell_out *out, size_t first_tri, size_t ntris,
                           uint8_t *labels, uint32_t first)
{
    for (size_t t = first_tri; t < ntris; t++) {
        int br[3];
        for (int k = 0; k < 3; k++)
            br[k] = vertex_branch(s, out, labels, first, out->tris[3 * t + k]);
        if (br[0] == br[1] && br[1] == br[2])
            continue;
        /* r: the corner alone on its branch; the others follow it in winding order */
        int r = br[0] == br[1] ? 2 : br[0] == br[2] ? 1 : 0;
        uint32_t a = out->tris[3 * t + r], b = out->tris[3 * t + (r + 1) % 3],
                 c = out->tris[3 * t + (r + 2) % 3];
        ism_fpoint ab, ac;
        crease_point(s, out->verts[a].p, out->verts[b].p, &ab);
        crease_point(s, out->verts[a].p, out->verts[c].p, &ac);
        uint32_t iab, iac;
        if (!ism_cell_out_vert(out, &ab, &iab) || !ism_cell_out_vert(out, &ac, &iac))
            return false;
        uint32_t *tri = out->tris + 3 * t;
        tri[0] = a, tri[1] = iab, tri[2] = iac;
        if (!ism_cell_out_tri(out, iab, b, c) || !ism_cell_out_tri(out, iab, c, iac))
            return false;
    }
    return true;
}

/* Do all vertices of triangles first_tri..ntris - 1 lie on one branch because the leaf's
 * shortened tape decides f's top min/max (strictly) over its closed box and holds them all? */
static bool one_branch(const ism_sampler *s, const ism_cell_out *out, size_t first_tri,
                       size_t ntris)
{
    if (!s->local || top_undecided(s->local))
        return false;
    for (size_t i = 3 * first_tri; i < 3 * ntris; i++)
        if (ism_sampler_tape_at(s, out->verts[out->tris[i]].p) != s->local)
            return false;
    return true;
}

bool ism_crease_split(ism_sampler *s, ism_cell_out *out, size_t first_tri)
{
    size_t ntris = out->ntris;
    if (first_tri == ntris || one_branch(s, out, first_tri, ntris))
        return true;
    double v[2];
    const double *p0 = out->verts[out->tris[3 * first_tri]].p;
    const ism_tape *t0 = top_tape(s, p0);
    s->n_point++;
    if (!ism_eval_top_values(t0, s->ws, p0[0], p0[1], p0[2], v))
        return true; /* no min/max at the top of the tape */
    uint32_t lo = UINT32_MAX, hi = 0;
    for (size_t i = 3 * first_tri; i < 3 * ntris; i++) {
        lo = out->tris[i] < lo ? out->tris[i] : lo;
        hi = out->tris[i] > hi ? out->tris[i] : hi;
    }
    size_t n = (size_t)hi - lo + 1;
    uint8_t stack[LABELS_ON_STACK], *labels = n <= LABELS_ON_STACK ? stack : malloc(n);
    if (!labels)
        return false;
    memset(labels, LABEL_UNKNOWN, n);
    labels[out->tris[3 * first_tri] - lo] = (uint8_t)ism_top_active_branch(t0, v);
    bool ok = split_labelled(s, out, first_tri, ntris, labels, lo);
    if (labels != stack)
        free(labels);
    return ok;
}
