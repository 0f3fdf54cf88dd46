/* conform_fill.c — refilling a hole loop around a singular point: rings of vertices between
 * the loop and the point, each moved onto f = 0 by Newton along ∇f, joined row to row by
 * ladders of triangles and fanned to the point's vertex at the last ring.
 *
 *     loop  v0 ──── v1 ──── v2        each ring vertex: apex + t (v_i − apex), projected;
 *            │ ╲     │ ╲     │        rows joined (v_i, v_i+1, r_i+1), (v_i, r_i+1, r_i)
 *     ring  r0 ──── r1 ──── r2
 *              ╲     |     ╱
 *                  apex
 */
#include "core/singular/conform_internal.h"
#include "core/util/vec3.h"

#include <math.h>
#include <string.h>
#include <stdlib.h>

/* Newton steps projecting a ring vertex (quadratic convergence from a fraction of a cell:
 * a handful suffices; more would only wander near a singular point). */
#define PROJECT_STEPS 6
/* ... and none once the point is this close, × the finest cell (|f| / |∇f|): the next step
 * would move it by less, a rounding-level amount (Newton has reached 1e-8 cell after the
 * third step, 1e-14 after the fourth; without this the last steps only jitter). */
#define PROJECT_DONE 1e-12
/* Rings at most (each one more row of triangles; the strip is a few cells wide). */
#define MAX_RINGS 6
/* A ring's spacing relative to the loop's mean edge: rows about as far apart as the rim's
 * vertices, so the new triangles are about as large as the polygoniser's around them. */
#define RING_SPACING 1.0
/* A loop of fewer vertices than this (a thin sheet round a cusp) gets twice as many on its
 * rings: a ring of a few chords sags far off a thin, round sheet. */
#define FINE_RING_MIN 8

double cf_project_keep(cf_ctx *c, double p[3], double max_move, cf_grad *kept)
{
    cf_poll(c, 1);
    double q[3] = {p[0], p[1], p[2]}, g[3], fv;
    double at[3] = {q[0], q[1], q[2]}; /* where g was evaluated */
    double d0 = cf_distance_estimate(c, q, g, &fv), d = d0;
    for (int it = 0; it < PROJECT_STEPS && d > PROJECT_DONE * c->cell && isfinite(d); it++) {
        double gg = g[0] * g[0] + g[1] * g[1] + g[2] * g[2], before[3] = {q[0], q[1], q[2]};
        for (int k = 0; k < 3; k++)
            q[k] -= fv * g[k] / gg;
        if (q[0] == before[0] && q[1] == before[1] && q[2] == before[2])
            break; /* a fixed point: the steps left would repeat this one exactly */
        d = cf_distance_estimate(c, q, g, &fv);
        memcpy(at, q, sizeof at);
    }
    bool moved = isfinite(d) && d < d0 && ism_dist3(p, q) <= max_move;
    if (moved)
        for (int k = 0; k < 3; k++)
            p[k] = q[k];
    if (kept) {
        kept->at = memcmp(at, p, sizeof at) == 0; /* the very point (bits, signed zeros) */
        memcpy(kept->g, g, sizeof kept->g);
    }
    return moved ? d : d0;
}

double cf_project(cf_ctx *c, double p[3], double max_move)
{
    return cf_project_keep(c, p, max_move, NULL);
}

int cf_ring_count(double width, double edge)
{
    if (!(edge > 0) || !(width > 0))
        return 0;
    double r = ceil(width / (RING_SPACING * edge)) - 1;
    return r < 0 ? 0 : r > MAX_RINGS ? MAX_RINGS : (int)r;
}

double cf_loop_mean_edge(const cf_ctx *c, const cf_loop *l)
{
    size_t ne = l->closed ? l->n : l->n - 1;
    if (ne == 0)
        return 0;
    double sum = 0;
    for (size_t i = 0; i < ne; i++)
        sum += ism_dist3(c->m->pos + 3 * (size_t)l->v[i],
                         c->m->pos + 3 * (size_t)l->v[(i + 1) % l->n]);
    return sum / (double)ne;
}

bool cf_ladder(cf_ctx *c, const uint32_t *a, const uint32_t *b, size_t n, bool closed)
{
    size_t ne = closed ? n : n - 1;
    for (size_t i = 0; i < ne; i++) {
        size_t j = (i + 1) % n;
        if (!cf_add_triangle(c, a[i], a[j], b[j]) || !cf_add_triangle(c, a[i], b[j], b[i]))
            return false;
    }
    return true;
}

static bool fan_row(cf_ctx *c, const uint32_t *r, size_t n, bool closed, uint32_t apex)
{
    size_t ne = closed ? n : n - 1;
    for (size_t i = 0; i < ne; i++)
        if (!cf_add_triangle(c, r[i], r[(i + 1) % n], apex))
            return false;
    return true;
}

/* The ring at fraction t of the way from the apex to the loop, projected onto f = 0 (moves
 * bounded by half the ring's distance to the apex: never onto another sheet). */
static bool make_ring(cf_ctx *c, const double *dirs, size_t m, const double apex[3], double t,
                      uint32_t *r)
{
    for (size_t i = 0; i < m; i++) {
        const double *v = dirs + 3 * i;
        double p[3];
        for (int k = 0; k < 3; k++)
            p[k] = apex[k] + t * (v[k] - apex[k]);
        cf_grad kept;
        cf_project_keep(c, p, 0.5 * t * ism_dist3(v, apex), &kept);
        r[i] = cf_add_vertex_kept(c, p, false, &kept);
        if (r[i] == CF_NONE)
            return false;
        c->st->vertices_added++;
    }
    return true;
}

/* The rings' directions: the loop's vertices, and between them the midpoints of its edges
 * when the loop has few vertices (a thin sheet: a cusp). Returns the count. */
static size_t ring_dirs(const cf_ctx *c, const cf_loop *l, bool split, double *d)
{
    size_t m = 0, ne = l->closed ? l->n : l->n - 1;
    for (size_t i = 0; i < l->n; i++) {
        const double *a = c->m->pos + 3 * (size_t)l->v[i];
        for (int k = 0; k < 3; k++)
            d[3 * m + k] = a[k];
        m++;
        if (!split || i >= ne)
            continue;
        const double *b = c->m->pos + 3 * (size_t)l->v[(i + 1) % l->n];
        for (int k = 0; k < 3; k++)
            d[3 * m + k] = (a[k] + b[k]) / 2;
        m++;
    }
    return m;
}

/* Triangles between the loop and a ring with a vertex at each loop vertex and one between
 * (inner[2i] below l->v[i], inner[2i+1] below the edge's middle). */
static bool ladder_split(cf_ctx *c, const cf_loop *l, const uint32_t *inner, size_t m)
{
    size_t ne = l->closed ? l->n : l->n - 1;
    for (size_t i = 0; i < ne; i++) {
        uint32_t a = l->v[i], b = l->v[(i + 1) % l->n];
        uint32_t p = inner[2 * i], q = inner[2 * i + 1], r = inner[(2 * i + 2) % m];
        if (!cf_add_triangle(c, a, b, q) || !cf_add_triangle(c, a, q, p) ||
            !cf_add_triangle(c, b, r, q))
            return false;
    }
    return true;
}

bool cf_fan(cf_ctx *c, const cf_loop *l, uint32_t apex, const double apex_pos[3], int rings)
{
    bool split = rings > 0 && l->n < FINE_RING_MIN;
    size_t cap = 2 * l->n;
    uint32_t *rows = malloc(2 * cap * sizeof *rows);
    double *dirs = malloc(3 * cap * sizeof *dirs);
    if (!rows || !dirs) {
        free(rows);
        free(dirs);
        return false;
    }
    size_t m = ring_dirs(c, l, split, dirs), n = l->n;
    uint32_t *outer = rows, *inner = rows + cap;
    for (size_t i = 0; i < l->n; i++)
        outer[i] = l->v[i];
    bool ok = true;
    for (int r = rings; ok && r >= 1 && !c->stopped; r--) {
        ok = make_ring(c, dirs, m, apex_pos, (double)r / (rings + 1), inner) &&
             (n == m ? cf_ladder(c, outer, inner, m, l->closed) : ladder_split(c, l, inner, m));
        n = m;
        uint32_t *t = outer;
        outer = inner;
        inner = t;
    }
    ok = ok && fan_row(c, outer, n, l->closed, apex);
    free(rows);
    free(dirs);
    return ok;
}

bool cf_fan_centroid(cf_ctx *c, const cf_loop *l)
{
    double p[3] = {0, 0, 0};
    for (size_t i = 0; i < l->n; i++)
        for (int k = 0; k < 3; k++)
            p[k] += c->m->pos[3 * (size_t)l->v[i] + k] / (double)l->n;
    cf_grad kept;
    cf_project_keep(c, p, cf_loop_mean_edge(c, l), &kept);
    uint32_t v = cf_add_vertex_kept(c, p, false, &kept);
    if (v == CF_NONE)
        return false;
    c->st->vertices_added++;
    c->st->loops_fallback++;
    return fan_row(c, l->v, l->n, l->closed, v);
}
