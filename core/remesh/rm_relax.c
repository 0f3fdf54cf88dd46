/* rm_relax.c — tangential relaxation: each free vertex moves toward the area-weighted
 * centroid of its triangles' centroids (a step of centroidal smoothing), within the tangent
 * plane of f = 0 there, and is put back on f = 0 by Newton steps along ∇f. A move is kept
 * only when no triangle of the fan turns over (against the fan's normal or against ∇f at a
 * corner; tested first at the tangent point, before Newton), Newton converged close to where
 * it started,
 * the fan's smallest angle does not get worse (or stays above a comfortable angle) and no
 * centroid of the fan ends farther from f = 0 than the mesh's farthest before the pass;
 * otherwise a half step is tried, then the vertex stays. Also ∇f's unit normals and the
 * distance estimate the pass uses. */
#include "core/remesh/rm_bound.h"
#include "core/remesh/rm_brec.h"
#include "core/remesh/rm_cbound.h"
#include "core/remesh/rm_pass.h"
#include "core/analysis/select.h"
#include "core/util/vec3.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

/* Newton steps projecting a moved vertex onto f = 0 (quadratic convergence: from a tangent
 * step of a fraction of an edge, 3-4 steps reach rounding). */
#define ISM_RM_NEWTON_STEPS 8
/* Newton has converged when its last step is below this × the fan's mean edge: the distance
 * left after a step of length s is about κ s² (κ the curvature), some 1e-12 of an edge on
 * the presets' meshes, far below any error bound — and one evaluation fewer than asking the
 * step itself to be that small. */
#define ISM_RM_NEWTON_REL 1e-6
/* The projection may move a vertex at most this × the fan's mean edge off its tangent step
 * (farther means it found another sheet). */
#define ISM_RM_PROJECT_MAX_REL 0.5
/* A move is refused when a triangle of the fan would face more than this away from the
 * fan's normal (fold-over guard; smooth fans spread a few degrees around it). */
#define ISM_RM_MAX_TURN_DEG 60.0

double rm_distance(rm_pass *p, const double x[3])
{
    if (p->bounded)
        return rm_bound_distance(p, x, INFINITY);
    double g[3], gn, fv = ism_eval_gradient(p->f, p->ws, x[0], x[1], x[2], g);
    return rm_unbounded_distance(p, fv, g, &gn);
}

double rm_midpoint_distance(rm_pass *p, const double *a, const double *b)
{
    double m[3];
    rm_midpoint(a, b, m);
    return rm_distance(p, m);
}

double rm_centroid_distance(rm_pass *p, const double *a, const double *b, const double *c)
{
    double m[3];
    rm_centroid(a, b, c, m);
    return rm_distance(p, m);
}

bool rm_normals(rm_pass *p)
{
    const ism_mesh *m = p->r.m;
    size_t nv = m->nverts;
    double *gn = malloc((nv ? nv : 1) * sizeof *gn);
    if (!gn)
        return false;
    size_t n = 0;
    /* f at every vertex, kept for its first offset (NULL when out of memory: each measured
       when asked, rm_brec_offset) */
    double *fs = p->found_offset = malloc((nv ? nv : 1) * sizeof *p->found_offset);
    p->found_offset_n = fs ? nv : 0;
    /* ∇f at every vertex, a chunk of the batched evaluator at a time (bit for bit
       ism_eval_gradient's, a NaN's sign aside (eval.h): a NaN gradient's vertex is no
       normal's either way; at under half the instructions a point on chmutov-quartic) */
    for (size_t v0 = 0; v0 < nv; v0 += ISM_GRAD_BATCH) {
        size_t c = nv - v0 < ISM_GRAD_BATCH ? nv - v0 : ISM_GRAD_BATCH;
        double x[ISM_GRAD_BATCH], y[ISM_GRAD_BATCH], z[ISM_GRAD_BATCH], fv[ISM_GRAD_BATCH];
        for (size_t i = 0; i < c; i++) {
            const double *q = m->pos + 3 * (v0 + i);
            x[i] = q[0], y[i] = q[1], z[i] = q[2];
        }
        ism_eval_gradient_batch(p->f, p->ws, x, y, z, fs ? fs + v0 : fv,
                                (double (*)[3])(p->normal + 3 * v0), c);
    }
    for (size_t v = 0; v < nv; v++) {
        const double *g = p->normal + 3 * v;
        double len = sqrt(ism_dot3(g, g));
        if (isfinite(len) && p->r.count[v])
            gn[n++] = len;
    }
    p->gthresh = n ? ISM_RM_SINGULAR_REL * ism_an_select_double(gn, n, n / 2) : 0;
    free(gn);
    for (size_t v = 0; v < nv; v++) {
        double *g = p->normal + 3 * v, len = sqrt(ism_dot3(g, g));
        double s = isfinite(len) && len > p->gthresh ? 1 / len : 0;
        if (fs)
            rm_bound_first_step(p, fs[v], len, &fs[v]);
        for (int k = 0; k < 3; k++)
            g[k] *= s;
    }
    return true;
}

bool rm_project(rm_pass *p, double x[3], double scale, int axis, double g[3])
{
    for (int i = 0; i < ISM_RM_NEWTON_STEPS; i++) {
        double fv = ism_eval_gradient(p->f, p->ws, x[0], x[1], x[2], g);
        if (axis >= 0)
            g[axis] = 0;
        double g2 = ism_dot3(g, g);
        if (!isfinite(fv) || !(sqrt(g2) > p->gthresh))
            return false;
        double s = fv / g2;
        for (int k = 0; k < 3; k++)
            x[k] -= s * g[k];
        if (fabs(s) * sqrt(g2) <= ISM_RM_NEWTON_REL * scale)
            return true; /* g is from a point this close: the normal to keep */
    }
    return false;
}

/* rm_fan_measure, or with shape false only f->normal: one loop, so that the normal the
 * collapses read (rm_fan_normal) is rm_fan_measure's bit for bit. */
static void fan_sum(const rm_pass *p, uint32_t v, rm_fan *f, bool shape)
{
    const rm_mesh *r = &p->r;
    const double *P = r->m->pos;
    double area = 0, edges = 0;
    f->min_sine = INFINITY;
    f->mean_edge = 0;
    memset(f->centroid, 0, sizeof f->centroid);
    memset(f->normal, 0, sizeof f->normal);
    for (uint32_t i = 0; i < r->count[v]; i++) {
        const uint32_t *t = r->m->tri + 3 * r->vt[r->start[v] + i];
        const double *a = P + 3 * t[0], *b = P + 3 * t[1], *c = P + 3 * t[2];
        double n[3], twice = rm_cross(a, b, c, n), w = 0.5 * twice;
        for (int k = 0; k < 3; k++)
            f->normal[k] += n[k];
        if (!shape)
            continue;
        /* side[k] joins corners k and k + 1: each side measured once */
        double side[3] = {rm_dist(a, b), rm_dist(b, c), rm_dist(c, a)};
        double sine = rm_sine_of(twice, side[0], side[1], side[2]);
        f->min_sine = sine < f->min_sine ? sine : f->min_sine; /* no libm call */
        for (int k = 0; k < 3; k++)
            f->centroid[k] += w * (a[k] + b[k] + c[k]) / 3;
        /* the sides at v's corner j, one per other corner k in order (side[k] joins corners k
           and k + 1): j = 0: sides 0, 2; j = 1: 0, 1; j = 2: 2, 1 */
        int j = t[0] == v ? 0 : t[1] == v ? 1 : 2;
        if ((t[0] == v) + (t[1] == v) + (t[2] == v) == 1) {
            f->mean_edge += side[j == 2 ? 2 : 0];
            f->mean_edge += side[j == 0 ? 2 : 1];
            edges += 2;
        } else { /* a collapsed triangle: v at two corners */
            for (int k = 0; k < 3; k++)
                if (t[k] != v) {
                    f->mean_edge += side[(k + 1) % 3 == j ? k : j];
                    edges++;
                }
        }
        area += w;
    }
    for (int k = 0; shape && k < 3; k++)
        f->centroid[k] = area > 0 ? f->centroid[k] / area : P[3 * v + k];
    f->mean_edge /= edges > 0 ? edges : 1;
}

void rm_fan_measure(const rm_pass *p, uint32_t v, rm_fan *f) { fan_sum(p, v, f, true); }

void rm_fan_normal(const rm_pass *p, uint32_t v, double normal[3])
{
    rm_fan f;
    fan_sum(p, v, &f, false);
    memcpy(normal, f.normal, sizeof f.normal);
}

bool rm_turns_over(const rm_pass *p, const uint32_t *t, uint32_t v, const double gv[3],
                   const double n[3])
{
    const double *P = p->r.m->pos;
    double m[3];
    rm_cross(P + 3 * (size_t)t[0], P + 3 * (size_t)t[1], P + 3 * (size_t)t[2], m);
    for (int k = 0; k < 3; k++) {
        const double *before = p->normal + 3 * (size_t)t[k];
        if (ism_dot3(m, before) > 0 && !(ism_dot3(n, t[k] == v ? gv : before) > 0))
            return true;
    }
    return false;
}

double rm_fan_cross(const rm_pass *p, uint32_t v, uint32_t i, const double *x, double n[3])
{
    const rm_mesh *r = &p->r;
    const uint32_t *t = r->m->tri + 3 * r->vt[r->start[v] + i];
    const double *q[3];
    for (int k = 0; k < 3; k++)
        q[k] = t[k] == v ? x : r->m->pos + 3 * (size_t)t[k];
    return rm_cross(q[0], q[1], q[2], n);
}

/* Moving v to x (∇f there g) turns no triangle of its fan over (rm_turns_over). Where ∇f at
 * every corner of the fan lies within 90° − ISM_RM_MAX_TURN_DEG of the fan's normal (or of
 * its opposite, at every corner) nothing can: rm_fan_accepts keeps each triangle within
 * ISM_RM_MAX_TURN_DEG of that normal, so each faces one side of ∇f at every corner, before
 * and after (the smooth parts' fans: no triangle normal is computed). */
static bool fan_keeps_facing(const rm_pass *p, uint32_t v, const double *x, const double g[3],
                             const rm_fan *f)
{
    const rm_mesh *r = &p->r;
    double lf = ism_norm3(f->normal), lg = ism_norm3(g), along = ism_dot3(g, f->normal);
    double side = along < 0 ? -1 : 1; /* the fan may face ∇f's side or the other */
    double near = cos((90 - ISM_RM_MAX_TURN_DEG) * M_PI / 180) * lf;
    bool all_near = side * along >= near * lg;
    for (uint32_t i = 0; i < r->count[v] && all_near; i++) {
        const uint32_t *t = r->m->tri + 3 * r->vt[r->start[v] + i];
        for (int k = 0; k < 3 && all_near; k++)
            all_near = t[k] == v ||
                       side * ism_dot3(p->normal + 3 * (size_t)t[k], f->normal) >= near;
    }
    for (uint32_t i = 0; i < r->count[v] && !all_near; i++) {
        double n[3];
        rm_fan_cross(p, v, i, x, n);
        if (rm_turns_over(p, r->m->tri + 3 * r->vt[r->start[v] + i], v, g, n))
            return false;
    }
    return true;
}

bool rm_fan_accepts(const rm_pass *p, uint32_t v, const double x[3], const rm_fan *f)
{
    const rm_mesh *r = &p->r;
    const double *P = r->m->pos;
    double worst = INFINITY, turn = cos(ISM_RM_MAX_TURN_DEG * M_PI / 180);
    double comfort = sin(ISM_RM_COMFORT_DEG * M_PI / 180);
    double ln = sqrt(ism_dot3(f->normal, f->normal));
    for (uint32_t i = 0; i < r->count[v]; i++) {
        const uint32_t *t = r->m->tri + 3 * r->vt[r->start[v] + i];
        const double *q[3];
        for (int k = 0; k < 3; k++)
            q[k] = t[k] == v ? x : P + 3 * t[k];
        double n1[3], l1 = rm_cross(q[0], q[1], q[2], n1);
        if (!(ism_dot3(f->normal, n1) > turn * ln * l1))
            return false;
        double sine = rm_sine_of(l1, rm_dist(q[0], q[1]), rm_dist(q[1], q[2]), rm_dist(q[2], q[0]));
        if (sine < f->min_sine && sine < comfort)
            return false; /* the worst can only fall from here (most refused tries) */
        worst = sine < worst ? sine : worst;
    }
    return worst >= f->min_sine || worst >= comfort;
}

void rm_commit_move(rm_pass *p, uint32_t v, const double x[3], const double g[3])
{
    double *pos = p->r.m->pos + 3 * v, *n = p->normal + 3 * v;
    float *mn = p->r.m->normal + 3 * v;
    double len = sqrt(ism_dot3(g, g));
    double side = mn[0] * g[0] + mn[1] * g[1] + mn[2] * g[2] < 0 ? -1 : 1;
    rm_cbound_moved(p, v, x);
    rm_brec_moved(p, v, x);
    rm_brec_offset_set(p, v, x); /* (x was measured by the move's checks: the memo answers) */
    for (uint32_t i = 0; i < p->r.count[v]; i++)
        rm_shape_changed(p, p->r.vt[p->r.start[v] + i]);
    memcpy(pos, x, 3 * sizeof *x);
    for (int k = 0; k < 3; k++) {
        n[k] = g[k] / len;
        mn[k] = (float)(side * n[k]);
    }
}

/* The farthest of v's fan's centroids from f = 0 with v where it is: as measured last where
 * that was at the centroid as it is (rm_cbound.h), else measured now (and kept). */
static double fan_centroid_error(rm_pass *p, uint32_t v)
{
    const rm_mesh *r = &p->r;
    const double *P = r->m->pos;
    double worst = 0;
    for (uint32_t i = 0; i < r->count[v]; i++) {
        uint32_t t = r->vt[r->start[v] + i];
        const uint32_t *c = r->m->tri + 3 * (size_t)t;
        double m[3];
        rm_centroid(P + 3 * (size_t)c[0], P + 3 * (size_t)c[1], P + 3 * (size_t)c[2], m);
        double d = rm_cbound_exact(p, t, m);
        if (isnan(d)) {
            double gn;
            d = rm_cbound_distance(p, m, &gn); /* never NaN */
            rm_cbound_set(p, t, m, d, gn);
        }
        worst = d > worst ? d : worst;
    }
    return worst;
}

/* Moving v to x puts no centroid of its fan farther from f = 0 than the mesh's farthest
 * before the pass (centroid_bound) or than the fan's farthest now (bounded: every centroid
 * and edge midpoint of the fan within max_error). A centroid known to stay within
 * centroid_bound (rm_cbound_within) is not measured: when every measured one is within it
 * too the move passes as it would have, and when one is beyond it that one is the fan's
 * farthest whatever the others measure. The measures are kept for the move (rm_cbound_fan). */
bool rm_centroids_stay(rm_pass *p, uint32_t v, const double *x)
{
    if (p->bounded) /* the simplification's rule: within max_error, measured */
        return rm_bound_fan(p, v, x);
    const rm_mesh *r = &p->r;
    double now = 0, *keep = rm_cbound_fan(p, v, x);
    for (uint32_t i = 0; i < r->count[v]; i++) {
        uint32_t t = r->vt[r->start[v] + i];
        const uint32_t *c = r->m->tri + 3 * (size_t)t;
        const double *q[3];
        for (int k = 0; k < 3; k++)
            q[k] = c[k] == v ? x : r->m->pos + 3 * (size_t)c[k];
        double m[3];
        for (int k = 0; k < 3; k++) /* near enough for the bound; the exact one if measured */
            m[k] = (q[0][k] + q[1][k] + q[2][k]) / 3;
        if (rm_cbound_within(p, t, m))
            continue;
        rm_centroid(q[0], q[1], q[2], m);
        double gn, d = rm_cbound_distance(p, m, &gn); /* never NaN */
        if (keep) {
            double *k = keep + RM_CBOUND_REC * i;
            memcpy(k, m, sizeof m), k[3] = d, k[4] = gn;
        }
        now = d > now ? d : now;
    }
    bool stays = now <= p->centroid_bound || now <= fan_centroid_error(p, v);
    if (!stays)
        rm_cbound_drop(p);
    return stays;
}

/* The simplification's vertices sit off f = 0 by a balancing offset (sp_place.h): x, just
 * put on f = 0 (∇f there g), takes the signed distance the vertex had where it stands
 * (rm_brec_offset). ∇f is measured again at x only once the fan's shape passed
 * (rm_relax_vertex): the shape needs no evaluation. False where f cannot be measured. */
static bool keep_offset(rm_pass *p, uint32_t v, double x[3], const double g[3])
{
    double d = rm_brec_offset(p, v), gn = sqrt(ism_dot3(g, g));
    if (!isfinite(d) || !(gn > 0))
        return false;
    for (int k = 0; k < 3; k++)
        x[k] += d * g[k] / gn;
    return true;
}

/* Under an error bound where f cannot crease, v is marked only as a poor triangle's
 * neighbour (rm_mark_active's mark 2) and every triangle of its fan still has its smallest
 * angle at least ISM_RM_COMFORT_DEG (rm_tri_sine: bit for bit rm_fan_measure's min_sine):
 * it is not relaxed. Moving v changes only its own fan's triangles, all comfortable, so
 * such a move mends nothing itself; the room it was to give its neighbours (remesh.c
 * relax_reach) they get once v's fan turns poor. Beside a min/max crease, whose locked
 * vertices cannot move, that room counts (relax_reach's cube-minus-ball): the rule
 * skipped there too cost three-balls' 0.37-cell box a needle, 10.18 -> 9.75 degrees.
 * callgrind, --quality good, default bound, ism_quality_pass own / 1e-3 / irr / c037 /
 * 1e-4 box: chmutov-quartic (its 12 locked nodes relax their neighbours' neighbours)
 * 542.7M -> 444.8M in its own box, 1.43 / 0.72 / 1.32 / 1.40 / 1.43 -> 1.14 / 0.58 / 1.07
 * / 1.15 / 1.15 of the polygonisation; catenoid (its box-cut boundary locked) 1.28 / 1.29 /
 * 1.28 / 1.19 / 1.28 -> 1.17 / 1.17 / 1.14 / 1.10 / 1.17. cusp22_sweep.py, 42 presets x
 * 5 boxes: no run gained a triangle under 10 degrees. Wider rules each did somewhere:
 * skipping mark-1 vertices whose fans turned comfortable too (torus's 1e-3 box in
 * test_quality, --max-error E --no-simplify --no-dual, 19.1 degrees; cusp-a2 1e-3 and
 * horn-cyclide 0.37-cell one more needle under 10 degrees), and skipping such slides too
 * (rm_slide.c; hyperboloid's irrational box 18.3 -> 8.9 degrees). */
static bool idle(rm_pass *p, uint32_t v)
{
    if (!p->bounded || p->may_crease || p->active[v] != 2)
        return false;
    double comfort = sin(ISM_RM_COMFORT_DEG * M_PI / 180);
    for (uint32_t i = 0; i < p->r.count[v]; i++)
        if (!(rm_tri_sine(p, p->r.vt[p->r.start[v] + i]) >= comfort))
            return false;
    return true;
}

/* Within this many of its fan's mean edges of a given singular point a vertex keeps the
 * least step (ISM_RM_MIN_STEP), not the far one (remesh.c's ISM_RM_FAR_STEP): beside a cusp
 * the vertices two rings and more out, which far_from_features lets take the far step, lie
 * on a tube a few edges across, and their longer idle steps left a needle in the tube
 * (cusp-a2, 1e-3 box: 8.27°, 0.007-0.014 from the cusp) whose merge into the cusp
 * (rm_horn.c) made its cone 1.66° (5.84° before the far step; 6.33° at the cusp). cusp-a2
 * 1e-3 box, the cusp's smallest angle: 6.28° within 5 edges, 6.33° within 10 (the mesh as
 * with the far step nowhere), and the same within 20 and 40. */
#define ISM_RM_FAR_POINT_EDGES 10.0

/* No vertex of v's fan is locked and no triangle with a corner there is under
 * ISM_RM_INSERT_DEG (two rings of triangles round v): v lies more than a ring away from
 * every protected vertex (point, crease, boundary) and no needle lies among those triangles,
 * where remesh.c's ISM_RM_FAR_STEP is v's least step (when far_from_points too). */
static bool far_from_features(rm_pass *p, uint32_t v)
{
    const rm_mesh *r = &p->r;
    double needle = rm_insert_poor();
    for (uint32_t i = 0; i < r->count[v]; i++) {
        const uint32_t *t = r->m->tri + 3 * (size_t)r->vt[r->start[v] + i];
        for (int k = 0; k < 3; k++) {
            uint32_t u = t[k];
            if (r->locked[u])
                return false;
            for (uint32_t j = 0; u != v && j < r->count[u]; j++)
                if (!(rm_tri_sine(p, r->vt[r->start[u] + j]) >= needle))
                    return false;
        }
    }
    return true;
}

/* v lies farther than ISM_RM_FAR_POINT_EDGES × its fan's mean edge from every given
 * singular point. O(points) a call, asked last (only of a vertex that would otherwise take
 * the far step); the points have no cap of their own (the locus's, bounded only by its
 * candidate-box budget max_boxes; the presets 1-16), the same order as rm_lock_vertices'
 * rm_point_vertex, which scans every vertex for each point at each locking. */
static bool far_from_points(const rm_pass *p, uint32_t v, double mean_edge)
{
    for (size_t i = 0; i < p->npoints; i++)
        if (rm_dist(rm_pos(p, v), p->points + 3 * i) < ISM_RM_FAR_POINT_EDGES * mean_edge)
            return false;
    return true;
}

/* Whether v's step d (its fan f) is too short to try: under the least step (relax_min_step,
 * or relax_far_step away from features and given points) × the fan's mean edge, with no
 * needle in its fan. */
static bool step_too_short(rm_pass *p, uint32_t v, const double d[3], const rm_fan *f)
{
    double d2 = ism_dot3(d, d), e2 = f->mean_edge * f->mean_edge;
    if (!(f->min_sine >= rm_collapse_poor()))
        return false;
    if (d2 < p->relax_min_step * p->relax_min_step * e2)
        return true;
    return d2 < p->relax_far_step * p->relax_far_step * e2 && far_from_features(p, v) &&
           far_from_points(p, v, f->mean_edge);
}

bool rm_relax_vertex(rm_pass *p, uint32_t v)
{
    double *pos = p->r.m->pos + 3 * v, *n = p->normal + 3 * v;
    if (idle(p, v))
        return false; /* a comfortable neighbour of a poor triangle's vertex */
    rm_fan f;
    rm_fan_measure(p, v, &f);
    double d[3] = {f.centroid[0] - pos[0], f.centroid[1] - pos[1], f.centroid[2] - pos[2]};
    double dn = ism_dot3(d, n);
    for (int k = 0; k < 3; k++)
        d[k] -= dn * n[k];
    if (step_too_short(p, v, d, &f))
        return false; /* near enough its fan's centroid, no needle in its fan (remesh.c's
                         ISM_RM_MIN_STEP, ISM_RM_FAR_STEP) */
    for (double step = 1; step >= 0.5; step *= 0.5) {
        double x[3] = {pos[0] + step * d[0], pos[1] + step * d[1], pos[2] + step * d[2]}, g[3];
        double tangent[3] = {x[0], x[1], x[2]};
        /* the fan's shape first at the tangent point, which needs no evaluation (Newton
           then moves x off it by under 0.003 of the fan's mean edge in 85% of the tries):
           on the gyroid-ball at its default bound 34,151 of the 34,166 tries whose shape
           failed where Newton put x failed there too, each spared its projection (2.1
           evaluations of f and ∇f), and 5 of 36,400 moves that passed where Newton put x
           are refused (the shape is still tested there too) */
        if (!rm_fan_accepts(p, v, tangent, &f) || !rm_project(p, x, f.mean_edge, -1, g) ||
            !(rm_dist(x, tangent) <= ISM_RM_PROJECT_MAX_REL * f.mean_edge) ||
            (p->bounded && !keep_offset(p, v, x, g)) || !rm_fan_accepts(p, v, x, &f) ||
            (p->bounded && !rm_bound_gradient(p, x, g)) || /* the fan's measure at x: here */
            !fan_keeps_facing(p, v, x, g, &f) || !rm_centroids_stay(p, v, x))
            continue;
        rm_commit_move(p, v, x, g);
        return true;
    }
    return false;
}

size_t rm_mark_active(rm_pass *p)
{
    const ism_mesh *m = p->r.m;
    const rm_mesh *r = &p->r;
    double comfort = sin(ISM_RM_COMFORT_DEG * M_PI / 180);
    memset(p->active, 0, m->nverts);
    double needle = rm_collapse_poor();
    p->poorest = 1;
    p->poor = 0;
    for (size_t t = 0; t < m->ntris; t++) {
        const uint32_t *v = m->tri + 3 * t;
        if (r->dead[t])
            continue;
        double s = rm_tri_sine(p, (uint32_t)t);
        if (s < p->poorest)
            p->poorest = s;
        p->poor += s < needle;
        if (s < comfort)
            p->active[v[0]] = p->active[v[1]] = p->active[v[2]] = 1;
    }
    /* 1 = near a poor triangle, 2 = its neighbour: the unmarked corners of every live
       triangle with a corner marked 1 (every live triangle is in each of its corners' slots,
       rm_mesh.h), read once per triangle rather than once per marked corner's fan: callgrind,
       cube in the 0.37-cell box, this function 18.9M -> 13.3M instructions */
    for (size_t t = 0; t < m->ntris; t++) {
        const uint32_t *v = m->tri + 3 * t;
        uint8_t *a = p->active;
        if (r->dead[t] || !(a[v[0]] == 1 || a[v[1]] == 1 || a[v[2]] == 1))
            continue;
        for (int k = 0; k < 3; k++)
            a[v[k]] = a[v[k]] ? a[v[k]] : 2;
    }
    size_t n = 0;
    for (size_t v = 0; v < m->nverts; v++)
        n += p->active[v] != 0;
    return n;
}

size_t rm_relax_sweep(rm_pass *p, uint8_t most)
{
    size_t moves = 0;
    for (size_t v = 0; v < p->r.m->nverts; v++)
        if (p->active[v] && p->active[v] <= most && !p->r.locked[v] && p->r.count[v] &&
            rm_relax_vertex(p, (uint32_t)v))
            moves++;
    p->moves += moves;
    return moves;
}
