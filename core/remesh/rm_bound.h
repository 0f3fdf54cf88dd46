/* rm_bound.h — the error bound the simplification keeps (rm_bound.c): the distance from a
 * point to f = 0 measured with a Newton step, and the checks that a changed piece of mesh —
 * a vertex's fan with the vertex moved, a flipped pair — has every triangle centroid and
 * every edge midpoint within max_error. Measured, not assumed: nothing is taken from the
 * mesh's size or curvature. */
#ifndef ISM_RM_BOUND_H
#define ISM_RM_BOUND_H

#include "core/remesh/rm_pass.h"
#include "core/util/vec3.h"

#include <math.h>

/* A point whose first step is at most this share of the limit it is measured against (of
 * max_error when the limit is infinite) is measured by that step alone: the second is the
 * residual of a Newton step, about κ s1² / 2 (κ the curvature of f's level set along the
 * step), within the rest of the limit whenever κ × limit <= 2 (1 - share) / share² = 4 — a
 * level set bending with a radius under a quarter of the bound, which no mesh within the
 * bound follows anyway. bench_error at bench_accuracy's E: evaluations of f and ∇f in the
 * simplification -22% (sphere), -26% (torus), -35% (gyroid-ball, klein-bottle); the meshes
 * byte-identical but klein-bottle's at 0.0251 (12,402 -> 12,394 triangles). */
#define RM_BOUND_ONE_STEP_SHARE 0.5

/* The distance from x to f = 0: |f|/|∇f| at x (the Newton step's length) plus |f|/|∇f| where
 * that step lands — by the triangle inequality no less than the distance to the zero set
 * when the landing point's estimate is (second order there). INFINITY where ∇f vanishes or
 * f is not finite; above limit, or at most half of it (of max_error when limit is infinite),
 * the first term alone: the step is not taken (its residual, second order, cannot carry a
 * point from half the bound beyond it; rm_bound.c).
 *
 * With the pass's Hessian cells (rm_hcell.h) and a finite limit, a value at most limit may
 * be a bound on the measure rather than the measure (|s1| plus a bound on the second term,
 * rm_bound.c's residual_within): never below it, and at most limit exactly when the measure
 * is. So a comparison `<= limit` against the limit passed decides as the measure does; any
 * other use (a strict `<`, a different threshold, a max over values) decides as the measure
 * does or more strictly (sp_place.c's `< before` may refuse a move the measure would take). */
double rm_bound_distance(rm_pass *p, const double x[3], double limit);

/* The first Newton step's signed length from a point where f is fv and |∇f| is gn: f/|∇f|
 * into *s1, or false and INFINITY where |∇f| is at most gthresh or f is not finite.
 * rm_bound_signed's measure (rm_bound.c first_step_from) and the offsets rm_normals keeps
 * for the records (rm_brec.h) are both this one, so a kept offset is what rm_bound_signed
 * would measure, bit for bit. */
static inline bool rm_bound_first_step(const rm_pass *p, double fv, double gn, double *s1)
{
    bool ok = isfinite(fv) && gn > p->gthresh;
    *s1 = ok ? fv / gn : INFINITY;
    return ok;
}

/* Without a bound, the distance to f = 0 from a point where f is fv and ∇f is g: |f|/|∇f|,
 * with |∇f| into *gn; INFINITY where |∇f| is at most gthresh or f is not finite. Every
 * unbounded measure (rm_distance, rm_cbound_distance, rm_bound_distances) is this one, so
 * they agree bit for bit. */
static inline double rm_unbounded_distance(const rm_pass *p, double fv, const double g[3],
                                           double *gn)
{
    double len = sqrt(ism_dot3(g, g));
    *gn = len;
    return len > p->gthresh && isfinite(fv) ? fabs(fv) / len : INFINITY;
}

/* d[i] = rm_distance(p, x[i]) for i < n, bit for bit (rm_bound_distance with an infinite
 * limit under a bound; |f|/|∇f| without one, with |∇f| into gn[i], 0 under a bound; gn may
 * be NULL), through the batched evaluator: one pass over the tape for a chunk of points'
 * first steps and one for the second steps they need. The memo is neither read nor written
 * (points measured once, as the found mesh's: they would only push out what the moves will
 * ask again). */
void rm_bound_distances(rm_pass *p, const double (*x)[3], size_t n, double *d, double *gn);
/* Points rm_bound_distances evaluates in one call of the batched evaluator (its stack
 * arrays): two of the evaluator's chunks. A caller gathering points hands them over in
 * multiples of this (a shorter list's last chunk pays its bookkeeping for fewer lanes). */
#define RM_DISTANCES_CHUNK (2 * ISM_GRAD_BATCH)

/* An upper bound on the distance from x to f = 0, as far as the bound max_error needs one:
 * rm_bound_distance with limit max_error, and where it took one step (|f|/|∇f| at most half
 * the bound) that step's residual at the steepest bend of f's level set the one-step rule
 * admits (rm_bound.c). Above max_error when x lies beyond it (then only a first step's
 * length); INFINITY where ∇f vanishes or f is not finite. */
double rm_bound_upper(rm_pass *p, const double x[3]);

/* The signed distance from x to f = 0 to first order, positive where f is: f/|∇f| at x
 * (INFINITY where ∇f vanishes or f is not finite). Moving x by δ along ∇f's unit vector
 * changes it by about δ. A model's input: bounds are checked with rm_bound_distance. */
double rm_bound_signed(rm_pass *p, const double x[3]);

/* ∇f at x into g, through the pass's memo: the measures at x that follow cost nothing more.
 * False where ∇f vanishes or f is not finite (as rm_bound_distance's INFINITY). */
bool rm_bound_gradient(rm_pass *p, const double x[3], double g[3]);

/* The centroid of abc into m, summed in an order fixed by the values (each coordinate's two
 * smallest first): the same bits whichever corner comes first, so the memo (rm_memo.h)
 * knows a centroid however a caller lists its triangle's corners. */
void rm_centroid(const double *a, const double *b, const double *c, double m[3]);

/* The midpoint of ab into m, as every measure of an edge's midpoint works it out. */
static inline void rm_midpoint(const double *a, const double *b, double m[3])
{
    for (int k = 0; k < 3; k++)
        m[k] = 0.5 * (a[k] + b[k]);
}

/* True when the midpoint of ab lies within max_error of f = 0. */
bool rm_bound_edge(rm_pass *p, const double *a, const double *b);
/* True when the centroid of abc lies within max_error of f = 0. */
bool rm_bound_triangle(rm_pass *p, const double *a, const double *b, const double *c);

/* Triangle i of v's fan: the triangle (*t) and v's corner in it. */
static inline int rm_fan_corner(const rm_pass *p, uint32_t v, uint32_t i, uint32_t *t)
{
    *t = p->r.vt[p->r.start[v] + i];
    const uint32_t *c = p->r.m->tri + 3 * (size_t)*t;
    return c[0] == v ? 0 : c[1] == v ? 1 : 2;
}

/* Triangle i of v's fan with v at x: the triangle (*t), v's corner (*k), the centroid g and
 * the midpoint m of the edge from v to the next corner (each edge at v is the next edge of
 * exactly one triangle of a closed fan). */
static inline void rm_fan_point(const rm_pass *p, uint32_t v, uint32_t i, const double *x,
                                uint32_t *t, int *k, double g[3], double m[3])
{
    *k = rm_fan_corner(p, v, i, t);
    const uint32_t *c = p->r.m->tri + 3 * (size_t)*t;
    const double *q[3];
    for (int j = 0; j < 3; j++)
        q[j] = c[j] == v ? x : p->r.m->pos + 3 * (size_t)c[j];
    rm_centroid(q[0], q[1], q[2], g);
    for (int j = 0; j < 3; j++)
        m[j] = 0.5 * (x[j] + q[(*k + 1) % 3][j]);
}

/* The largest distance over v's fan with v at x: its centroids, the midpoints of the edges at
 * v, and x itself (v free: a closed fan), each point measured with limit (rm_bound_distance);
 * as soon as one measures above stop, that one (the rest are not measured). */
double rm_bound_fan_worst(rm_pass *p, uint32_t v, const double *x, double limit, double stop);

#endif
