/* cell_error.c — the distance to f = 0 of the triangles a node would emit, measured at their
 * centroids and edge midpoints (see cell_error.h). */
#include "core/octree/cell_error.h"
#include "core/octree/cell_cache.h"
#include "core/octree/crease_split.h"
#include "core/octree/edge_roots.h"
#include "core/octree/refine.h"
#include "core/octree/root_table.h"
#include "core/octree/sample_dist.h"
#include "core/octree/straddle.h"
#include "core/octree/triangulate.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#define MAX_ROOTS 12
/* Newton steps that move a large polygon's centre onto f = 0 (triangulate.c uses up to 5
 * and stops at 1e-6 of the node: after 3 the remaining step is far below any useful error
 * bound on a smooth surface, and a centre that has not landed is measured where it is). */
#define CENTRE_NEWTON_STEPS 3

typedef struct root_pt {
    double p[3];
    int face[2];
} root_pt;

/* A point loop_error measures: its distance is ism_sample_dist_between's over the n (2: an
 * edge's midpoint, 3: a centroid) vertices v, or ism_plain_dist's alone (n 0). */
typedef struct loop_pt {
    double p[3];
    const double *v[3];
    int n;
} loop_pt;

/* Points per polygon at most: its n edge midpoints, then a fan's centre and its n spokes'
 * midpoints and n centroids. */
#define LOOP_PTS (3 * MAX_ROOTS + 1)

static void midpoint_at(loop_pt *q, const double *a, const double *b)
{
    for (int k = 0; k < 3; k++)
        q->p[k] = 0.5 * (a[k] + b[k]);
    q->v[0] = a, q->v[1] = b, q->v[2] = NULL;
    q->n = 2;
}

static void centroid_at(loop_pt *q, const double *a, const double *b, const double *c)
{
    for (int k = 0; k < 3; k++)
        q->p[k] = (a[k] + b[k] + c[k]) / 3;
    q->v[0] = a, q->v[1] = b, q->v[2] = c;
    q->n = 3;
}

/* The mean of the polygon's corners, where centre_on_surface starts. */
static void corner_mean(const double (*p)[3], int n, double c[3])
{
    memset(c, 0, 3 * sizeof *c);
    for (int i = 0; i < n; i++)
        for (int k = 0; k < 3; k++)
            c[k] += p[i][k] / n;
}

/* The polygon's centre c, which starts at the corners' mean (corner_mean), moved toward
 * f = 0 along ∇f, as triangulate.c fans from it; f0, g0: f and ∇f at that start when the
 * caller has them (ism_sample_grad's bits), else NULL. */
static void centre_on_surface(ism_sampler *s, const double *f0, const double *g0, double c[3])
{
    for (int it = 0; it < CENTRE_NEWTON_STEPS; it++) {
        double g[3], f;
        if (it == 0 && f0) {
            f = *f0;
            memcpy(g, g0, sizeof g);
        } else {
            f = ism_sample_grad(s, c, g);
        }
        double gg = ism_dot3(g, g);
        if (!isfinite(f) || !isfinite(gg) || !(gg > 0))
            return;
        for (int k = 0; k < 3; k++)
            c[k] -= f * g[k] / gg;
    }
}

/* worst = max(worst, d); true once it is beyond bound (the measuring may stop). */
static bool beyond(double *worst, double d, double bound)
{
    *worst = fmax(*worst, d);
    return *worst > bound;
}

/* The points q[0..n) measured in order into *worst, their gradients in one batch
 * (ism_sample_grad_batch: ism_sample_grad's values); true at the first beyond bound (the
 * points after it were evaluated for nothing: the same answer as one by one). With at
 * (not NULL), the point at is evaluated in the same batch, not measured: its f and ∇f into
 * *fa, ga. */
static bool measure_beyond(ism_sampler *s, const loop_pt *q, int n, double *worst,
                           double bound, const double *at, double *fa, double *ga)
{
    double p[LOOP_PTS + 1][3], f[LOOP_PTS + 1], g[LOOP_PTS + 1][3];
    for (int i = 0; i < n; i++)
        memcpy(p[i], q[i].p, sizeof p[i]);
    if (at)
        memcpy(p[n], at, sizeof p[n]);
    ism_sample_grad_batch(s, (const double (*)[3])p, f, g, (size_t)(n + (at != NULL)));
    if (at) {
        *fa = f[n];
        memcpy(ga, g[n], sizeof g[n]);
    }
    double plain[LOOP_PTS];
    ism_plain_dists(s, (const double (*)[3])p, f, (const double (*)[3])g, s->dist_above, plain,
                    (size_t)n);
    for (int i = 0; i < n; i++) {
        double d = plain[i];
        if (q[i].n)
            d = ism_dist_beyond(s, q[i].p, d, q[i].v, q[i].n);
        if (beyond(worst, d, bound))
            return true;
    }
    return false;
}

/* The worst distance on one polygon p[0..n), triangulated as triangulate.c does; the
 * measuring stops at the first point beyond bound. Its points in two batches: the edges'
 * midpoints and a triangle's or a quad's other three, or a fan's centre (moved onto f = 0
 * only when the edges pass) and spokes. */
static double loop_error(ism_sampler *s, const double (*p)[3], int n, double bound)
{
    double worst = 0, c[3];
    loop_pt q[LOOP_PTS];
    int m = 0;
    for (int i = 0; i < n; i++)
        midpoint_at(&q[m++], p[i], p[(i + 1) % n]);
    if (n == 3)
        centroid_at(&q[m++], p[0], p[1], p[2]);
    if (n == 4) {
        int a = ism_dist3(p[0], p[2]) <= ism_dist3(p[1], p[3]) ? 0 : 1;
        const double *d0 = p[a], *d1 = p[a + 2];
        midpoint_at(&q[m++], d0, d1);
        centroid_at(&q[m++], d0, p[a + 1], d1);
        centroid_at(&q[m++], d0, d1, p[(a + 3) % 4]);
    }
    /* a fan's centre starts at the corners' mean: in batches its first gradient rides in the
       edges' batch (a lane of its padding for up to seven sides: one scalar evaluation less;
       gyroid ball at E = 1e-3, callgrind, one thread, ism_mesh_surface: 1,978.0M ->
       1,975.3M); the scalar reference path (!s->batch) takes it on its own, as before */
    double f0, g0[3];
    bool fan = n >= 5, ride = fan && s->batch;
    if (fan)
        corner_mean(p, n, c);
    if (measure_beyond(s, q, m, &worst, bound, ride ? c : NULL, &f0, g0) || !fan)
        return worst;
    centre_on_surface(s, ride ? &f0 : NULL, g0, c);
    m = 0;
    q[m++] = (loop_pt){{c[0], c[1], c[2]}, {NULL, NULL, NULL}, 0};
    for (int i = 0; i < n; i++) {
        midpoint_at(&q[m++], c, p[i]);
        centroid_at(&q[m++], c, p[i], p[(i + 1) % n]);
    }
    measure_beyond(s, q, m, &worst, bound, NULL, NULL, NULL);
    return worst;
}

/* Polygon p[0..n) triangulated as loop_error measures it, into out; false when out of
 * memory. */
static bool loop_tris(ism_sampler *s, const double (*p)[3], int n, ism_cell_out *out)
{
    uint32_t base = (uint32_t)out->nverts, idx;
    for (int i = 0; i <= n; i++) {
        ism_fpoint v = {{0, 0, 0}, {0, 0, 0}, 0};
        if (i < n)
            memcpy(v.p, p[i], sizeof v.p);
        else if (n >= 5) {
            corner_mean(p, n, v.p);
            centre_on_surface(s, NULL, NULL, v.p);
        } else
            break;
        if (!ism_cell_out_vert(out, &v, &idx))
            return false;
    }
    if (n == 3)
        return ism_cell_out_tri(out, base, base + 1, base + 2);
    if (n == 4) {
        uint32_t a = ism_dist3(p[0], p[2]) <= ism_dist3(p[1], p[3]) ? 0 : 1;
        return ism_cell_out_tri(out, base + a, base + a + 1, base + a + 2) &&
               ism_cell_out_tri(out, base + a, base + a + 2, base + (a + 3) % 4);
    }
    for (int i = 0; i < n; i++)
        if (!ism_cell_out_tri(out, idx, base + (uint32_t)i, base + (uint32_t)((i + 1) % n)))
            return false;
    return true;
}

/* The root parameter on node edge c0 -> c1 (a single root: ism_single_root_edges), from the
 * thread's root memo when it holds the edge, else searched (regula falsi) and kept there and
 * in its log (root_table.h's claim and store, as the level prefetch keeps its lanes' roots). */
static double edge_root(ism_sampler *s, const ism_corners *k, int c0, int c1)
{
    double t;
    ism_root_entry *m = NULL;
    if (k->memo) {
        m = ism_root_slot(k->memo->roots, k->key[c0], k->key[c1]);
        if (ism_root_memo_find(m, k->key[c0], k->key[c1], &t))
            return t;
    }
    t = ism_regula_falsi(s, k->p[c0], k->p[c1], k->f[c0], k->f[c1]);
    if (m) {
        ism_root_claim(m, k->key[c0], k->key[c1]);
        ism_root_store(m, k->memo->log, k->key[c0], k->key[c1], t);
    }
    return t;
}

/* The node's edge roots, each with the two faces its edge lies on. A corner exactly on the
 * surface is one root, on the two faces the surface enters there (none: it only touches the
 * node; ism_zero_corner_faces). */
static void edge_roots(ism_sampler *s, const ism_corners *k, double shift, const double *box,
                       root_pt *r, int *n)
{
    *n = 0;
    for (int c = 0; c < 8; c++) {
        if (k->f[c] != 0)
            continue;
        unsigned m = ism_zero_corner_faces(k->f, c);
        if (!m)
            continue;
        for (int f = 0, j = 0; f < 6; f++)
            if (m >> f & 1)
                r[*n].face[j++] = f;
        ism_straddle_point(s, shift, box, k->p[c], r[*n].p);
        (*n)++;
    }
    for (unsigned es = ism_single_root_edges(k->f); es; es &= es - 1) { /* in edge order */
        int c0, c1;
        ism_cube_edge(__builtin_ctz(es), &c0, &c1, r[*n].face);
        double t = edge_root(s, k, c0, c1);
        double p[3];
        for (int a = 0; a < 3; a++)
            p[a] = k->p[c0][a] + t * (k->p[c1][a] - k->p[c0][a]);
        ism_straddle_point(s, shift, box, p, r[*n].p);
        (*n)++;
    }
}

/* The polygons through the node's edge roots, measured one by one (cut NULL) or
 * triangulated into cut, split along f's crease and measured there. */
static bool cell_loops(ism_sampler *s, const ism_corners *k, ism_cell_out *cut, double bound,
                       double shift, const double *box, double *err)
{
    root_pt r[MAX_ROOTS];
    int n;
    edge_roots(s, k, shift, box, r, &n);
    /* on_face[f]: the roots on face f; exactly two or none make clean polygons */
    int on_face[6][2], count[6] = {0};
    for (int i = 0; i < n; i++)
        for (int j = 0; j < 2; j++) {
            int f = r[i].face[j];
            if (count[f] == 2)
                return false;
            on_face[f][count[f]++] = i;
        }
    for (int f = 0; f < 6; f++)
        if (count[f] == 1)
            return false;
    bool used[MAX_ROOTS] = {false};
    double worst = 0, loop[MAX_ROOTS][3];
    for (int start = 0; start < n && !(worst > bound); start++) {
        if (used[start])
            continue;
        int m = 0, cur = start, via = r[start].face[0];
        while (!used[cur]) {
            used[cur] = true;
            memcpy(loop[m++], r[cur].p, sizeof loop[0]);
            via = r[cur].face[0] == via ? r[cur].face[1] : r[cur].face[0];
            cur = on_face[via][0] == cur ? on_face[via][1] : on_face[via][0];
        }
        if (!cut)
            worst = fmax(worst, loop_error(s, (const double (*)[3])loop, m, bound));
        else if (!loop_tris(s, (const double (*)[3])loop, m, cut))
            return false;
    }
    if (cut) {
        if (!ism_crease_split(s, cut, 0))
            return false;
        worst = ism_emitted_error(s, cut, 0, bound);
    }
    *err = worst;
    return true;
}

bool ism_cell_error(ism_sampler *s, const ism_corners *k, double bound, double shift,
                    const double box[6], double *err)
{
    return cell_loops(s, k, NULL, bound, shift, box, err);
}

bool ism_cell_error_cut(ism_sampler *s, const ism_corners *k, double bound, double *err)
{
    ism_cell_out cut;
    memset(&cut, 0, sizeof cut);
    bool ok = cell_loops(s, k, &cut, bound, 0, NULL, err);
    free(cut.verts);
    free(cut.tris);
    return ok;
}
