/* straddle.c — vertices moved toward the convex side by a share of the bound (straddle.h). */
#include "core/octree/straddle.h"
#include "core/octree/refine.h"
#include "core/util/vec3.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

/* The share of E a vertex moves. Chords of a surface bending one way lie on its concave
 * side by their sag s >= 0; moved by σE the vertex errs σE and a chord point |s − σE|, so
 * polygons with s <= (1 + σ) E meet E. Below 1 so that a vertex stays strictly within E
 * whatever rounds the first-order distance; 0.9 gives sag room 1.9 E (cells ×1.38). */
#define STRADDLE_SHARE 0.9
/* A vertex this close to a face of the box (relative to the box) is on it: it stays. */
#define BOX_FACE_REL 1e-12

/* The tangential Hessian's quadratic form in an orthonormal basis t1, t2 of the plane
 * across n (ism_across_least3): a, b, c of [[a, b], [b, c]]. */
static void tangential(const double h[6], const double n[3], double *a, double *b, double *c)
{
    double t[2][3];
    ism_across_least3(n, t);
    const double *t1 = t[0], *t2 = t[1];
    const double H[3][3] = {{h[0], h[1], h[2]}, {h[1], h[3], h[4]}, {h[2], h[4], h[5]}};
    double Ht1[3], Ht2[3];
    for (int i = 0; i < 3; i++) {
        Ht1[i] = H[i][0] * t1[0] + H[i][1] * t1[1] + H[i][2] * t1[2];
        Ht2[i] = H[i][0] * t2[0] + H[i][1] * t2[1] + H[i][2] * t2[2];
    }
    *a = ism_dot3(t1, Ht1);
    *b = ism_dot3(t1, Ht2);
    *c = ism_dot3(t2, Ht2);
}

static bool on_box_face(const double box[6], const double p[3])
{
    for (int k = 0; k < 3; k++) {
        double tol = BOX_FACE_REL * (box[3 + k] - box[k]);
        if (!(p[k] > box[k] + tol && p[k] < box[3 + k] - tol))
            return true;
    }
    return false;
}

/* The unit normal n = ∇f/|∇f| at p and f's tangential Hessian there (a, b, c as
 * tangential() gives them; *gl: |∇f|, when gl is not NULL); false at the box's faces and
 * where f, ∇f or |∇f| is not usable. j: f, ∇f and the Hessian at p taken beforehand
 * (ism_eval_hessian's bits), or NULL: evaluated here. */
static bool local_form(ism_sampler *s, const double box[6], const double p[3],
                       const ism_straddle_jet *j, double n[3], double *a, double *b, double *c,
                       double *glen)
{
    if (on_box_face(box, p))
        return false;
    double g[3], h[6], f;
    s->n_gradient++;
    if (j) {
        f = j->f;
        memcpy(g, j->g, sizeof g);
        memcpy(h, j->h, sizeof h);
    } else {
        f = ism_eval_hessian(s->tape, s->ws, p[0], p[1], p[2], g, h);
    }
    double gl = ism_norm3(g);
    if (!isfinite(f) || !(gl > 0) || !isfinite(gl))
        return false;
    for (int k = 0; k < 3; k++)
        n[k] = g[k] / gl;
    tangential(h, n, a, b, c);
    if (glen)
        *glen = gl;
    return true;
}

bool ism_straddle_point(ism_sampler *s, double shift, const double box[6], const double p[3],
                        double q[3])
{
    memcpy(q, p, 3 * sizeof *q);
    double n[3], a, b, c;
    if (!(shift > 0) || !local_form(s, box, p, NULL, n, &a, &b, &c, NULL))
        return false;
    if (!(a * c - b * b > 0) || !isfinite(a))
        return false; /* a saddle, a parabolic point, or no Hessian: chords on both sides */
    /* f grows along the tangent plane (a > 0): the surface bends toward f < 0, its chords
     * lie there, and the vertex moves toward f > 0 (along ∇f); the other way round else */
    double step = a > 0 ? shift : -shift;
    /* the point where f's first-order model reaches f(p) + step |∇f| */
    for (int k = 0; k < 3; k++)
        q[k] = p[k] + step * n[k];
    return true;
}

bool ism_straddle_balanced_point(ism_sampler *s, double shift, const double box[6],
                                 const double p[3], double q[3], double *bend)
{
    double bends[2];
    bool moved = ism_straddle_balanced_point_at(s, shift, box, p, NULL, q, bends);
    if (bend)
        *bend = bends[0];
    return moved;
}

bool ism_straddle_balanced_point_at(ism_sampler *s, double shift, const double box[6],
                                    const double p[3], const ism_straddle_jet *j, double q[3],
                                    double bend[2])
{
    memcpy(q, p, 3 * sizeof *q);
    double n[3], a, b, c, gl;
    if (bend)
        bend[0] = bend[1] = 0;
    if (!(shift > 0) || !local_form(s, box, p, j, n, &a, &b, &c, &gl))
        return false;
    /* the tangential Hessian's eigenvalues l1 >= l2: their sum and difference */
    double sum = a + c, diff = sqrt((a - c) * (a - c) + 4 * b * b);
    if (bend && isfinite(sum) && isfinite(diff)) {
        bend[0] = 0.5 * (fabs(sum) + diff) / gl; /* max(|l1|, |l2|) / |∇f| */
        if (fabs(sum) > diff) /* l1, l2 of one sign: min(|l1|, |l2|) / |∇f| */
            bend[1] = 0.5 * (fabs(sum) - diff) / gl;
    }
    if (!isfinite(sum) || !isfinite(diff) || !(fabs(sum) > 0))
        return false; /* no Hessian, or chords as far to each side: no move */
    /* (l1 + l2) / (l1 - l2) capped at ±STRADDLE_SHARE: the full shift wherever the cap
     * binds (every point bending one way, where diff < |sum|: ism_straddle_point's move) */
    double step = fabs(sum) >= STRADDLE_SHARE * diff ? (sum > 0 ? shift : -shift)
                                                     : shift / STRADDLE_SHARE * (sum / diff);
    for (int k = 0; k < 3; k++)
        q[k] = p[k] + step * n[k];
    return true;
}

bool ism_straddle_emitted_error(ism_sampler *s, double shift, const double box[6],
                                ism_cell_out *out, size_t first_vert, size_t first_tri,
                                double *err)
{
    size_t n = out->nverts - first_vert;
    double (*keep)[3] = malloc((n ? n : 1) * sizeof *keep);
    if (!keep)
        return false;
    for (size_t i = 0; i < n; i++) {
        double *p = out->verts[first_vert + i].p;
        memcpy(keep[i], p, sizeof keep[i]);
        ism_straddle_point(s, shift, box, keep[i], p);
    }
    *err = ism_emitted_error(s, out, first_tri, INFINITY);
    for (size_t i = 0; i < n; i++)
        memcpy(out->verts[first_vert + i].p, keep[i], sizeof keep[i]);
    free(keep);
    return true;
}

void ism_straddle_mesh(ism_sampler *s, double shift, const double box[6], ism_mesh *m)
{
    for (size_t v = 0; shift > 0 && v < m->nverts; v++) {
        double q[3];
        if (ism_straddle_point(s, shift, box, &m->pos[3 * v], q))
            memcpy(&m->pos[3 * v], q, sizeof q);
    }
}

double ism_straddle_shift(const ism_tape *t, double max_error, bool has_locus)
{
    if (!(max_error > 0) || has_locus || ism_tape_has_min_max(t))
        return 0;
    return STRADDLE_SHARE * max_error;
}
