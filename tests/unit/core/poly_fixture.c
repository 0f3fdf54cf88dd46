/* poly_fixture.c — mesh measurements for the polygoniser tests, written independently of the
 * analysis module: sorted edge lists, union-find, triangle areas, f at every vertex. */
#include "poly_fixture.h"

#include <criterion/criterion.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include "core/eval/eval.h"
#include "core/singular/surface.h"
#include "core/util/vec3.h"

int pf_first_box(void)
{
    return pf_quick() ? 2 : 0;
}

int pf_quick(void)
{
    const char *q = getenv("ISOMESH_TEST_QUICK");
    return q && *q && strcmp(q, "0") != 0;
}

ism_tape *pf_compile(const pf_surface *s)
{
    ism_error err;
    ism_tape *t = ism_tape_compile(s->expr, s->params, s->nparams, s->lets, s->nlets, NULL, &err);
    cr_assert(t, "compile %s: %s (col %d)", s->expr, err.message, err.column);
    return t;
}

void pf_options(ism_poly_options *o, const double box[6], int dmin, int dmax)
{
    ism_poly_options_default(o);
    memcpy(o->box, box, sizeof o->box);
    o->min_depth = dmin;
    o->max_depth = dmax;
}

void pf_run_options(const ism_tape *t, const ism_poly_options *o, ism_mesh *m,
                    ism_poly_stats *st)
{
    ism_error err;
    ism_mesh_init(m);
    enum ism_poly_status s = ism_polygonise(t, o, m, st, &err);
    cr_assert_eq(s, ISM_POLY_OK, "polygonise failed: %s", err.message);
}

void pf_run(const ism_tape *t, const double box[6], int dmin, int dmax, int threads,
            ism_mesh *m, ism_poly_stats *st)
{
    ism_poly_options o;
    pf_options(&o, box, dmin, dmax);
    o.threads = threads;
    pf_run_options(t, &o, m, st);
}

void pf_run_surface_bounded(const ism_tape *t, const double box[6], int dmin, int dmax,
                            double max_error, ism_mesh *m, ism_locus *l)
{
    ism_poly_options o;
    ism_poly_options_default(&o);
    memcpy(o.box, box, sizeof o.box);
    o.min_depth = dmin, o.max_depth = dmax, o.threads = 1, o.max_error = max_error;
    pf_mesh_surface_with(t, &o, m, l, NULL);
}

void pf_mesh_surface_with(const ism_tape *t, const ism_poly_options *o, ism_mesh *m,
                          ism_locus *l, ism_poly_stats *ps)
{
    ism_poly_stats own;
    ism_conform_stats cs;
    ism_surface_times tm;
    ism_error err;
    ism_mesh_init(m);
    ism_locus_init(l);
    enum ism_poly_status s = ism_mesh_surface(t, o, m, l, ps ? ps : &own, &cs, &tm, &err);
    cr_assert_eq(s, ISM_POLY_OK, "meshing the surface failed: %s", err.message);
}

void pf_run_surface(const ism_tape *t, const double box[6], int dmin, int dmax, ism_mesh *m,
                    ism_locus *l)
{
    pf_run_surface_bounded(t, box, dmin, dmax, 0, m, l);
}

static void sweep_box(const double base[6], int d, int which, const double cell_shift[3],
                      double box[6])
{
    static const double abs_shift[3] = {PF_OFF_X, PF_OFF_Y, PF_OFF_Z};
    for (int k = 0; k < 3; k++) {
        double s = which < 0 ? 0 : which == 0 ? abs_shift[k]
                                              : cell_shift[k] * ldexp(base[k + 3] - base[k], -d);
        box[k] = base[k] + s;
        box[k + 3] = base[k + 3] + s;
    }
}

void pf_sweep_box(const double base[6], int d, int which, double box[6])
{
    static const double irr[3] = {PF_IRR_X, PF_IRR_Y, PF_IRR_Z};
    sweep_box(base, d, which, irr, box);
}

ism_grid pf_sweep_grid(const double base[6], int d, int which, double box[6])
{
    pf_sweep_box(base, d, which, box);
    ism_grid g = {.depth = d}; /* lo and step below */
    for (int a = 0; a < 3; a++) {
        g.lo[a] = box[a];
        g.step[a] = (box[a + 3] - box[a]) / (1 << d);
    }
    return g;
}

ism_tape *pf_build_sampler(const pf_surface *surf, ism_sampler *s)
{
    ism_tape *t = pf_compile(surf);
    memset(s, 0, sizeof *s);
    s->tape = t;
    s->ws = ism_eval_ws_new(t);
    s->batch = true; /* the build's samplers */
    cr_assert(s->ws);
    return t;
}

void pf_sweep_box_old(const double base[6], int d, int which, double box[6])
{
    static const double old[3] = {PF_OLD_X, PF_OLD_Y, PF_OLD_Z};
    sweep_box(base, d, which, old, box);
}

void pf_run_placed(const ism_tape *t, const double base[6], int d, int which, double box[6],
                   ism_mesh *m, pf_props *p)
{
    ism_poly_stats st;
    pf_sweep_box(base, d, which, box);
    pf_run(t, box, 3, d, 0, m, &st);
    pf_measure(m, t, p);
}

bool pf_inside_box(const double a[3], const double b[3], const void *arg)
{
    const double *box = arg, tol = 1e-9;
    bool in = true;
    for (int k = 0; k < 3; k++)
        in = in && fmin(a[k], b[k]) > box[k] + tol && fmax(a[k], b[k]) < box[k + 3] - tol;
    return in;
}

double pf_default_error(const double box[6])
{
    return 1e-3 * ism_box_diagonal(box);
}

double pf_cell(const double box[6], int d)
{
    double s = box[3] - box[0];
    for (int k = 1; k < 3; k++)
        if (box[3 + k] - box[k] < s)
            s = box[3 + k] - box[k];
    return ldexp(s, -d);
}

typedef struct edge {
    uint32_t a, b;
} edge;

static int cmp_edge(const void *x, const void *y)
{
    const edge *p = x, *q = y;
    if (p->a != q->a)
        return p->a < q->a ? -1 : 1;
    return (p->b > q->b) - (p->b < q->b);
}

static edge *sorted_edges(const ism_mesh *m)
{
    edge *e = malloc((m->ntris * 3 + 1) * sizeof *e);
    cr_assert(e);
    for (size_t t = 0; t < m->ntris; t++)
        for (int k = 0; k < 3; k++) {
            uint32_t a = m->tri[3 * t + k], b = m->tri[3 * t + (k + 1) % 3];
            e[3 * t + k] = a < b ? (edge){a, b} : (edge){b, a};
        }
    qsort(e, m->ntris * 3, sizeof *e, cmp_edge);
    return e;
}

static uint32_t find(uint32_t *p, uint32_t x)
{
    while (p[x] != x)
        x = p[x] = p[p[x]];
    return x;
}

void pf_measure(const ism_mesh *m, const ism_tape *t, pf_props *p)
{
    memset(p, 0, sizeof *p);
    p->faces = m->ntris;
    edge *e = sorted_edges(m);
    uint32_t *parent = malloc((m->nverts + 1) * sizeof *parent);
    bool *used = calloc(m->nverts + 1, 1);
    cr_assert(parent && used);
    for (uint32_t v = 0; v < m->nverts; v++)
        parent[v] = v;
    size_t n = m->ntris * 3;
    for (size_t i = 0; i < n;) {
        size_t j = i;
        while (j < n && e[j].a == e[i].a && e[j].b == e[i].b)
            j++;
        size_t c = j - i;
        p->edges++;
        if (c == 1)
            p->boundary_edges++;
        else if (c == 2)
            p->manifold_edges++;
        else
            p->nonmanifold_edges++;
        parent[find(parent, e[i].a)] = find(parent, e[i].b);
        i = j;
    }
    for (size_t k = 0; k < m->ntris * 3; k++)
        used[m->tri[k]] = true;
    for (uint32_t v = 0; v < m->nverts; v++)
        if (used[v]) {
            p->verts_used++;
            if (find(parent, v) == v)
                p->components++;
        }
    p->euler = (long)p->verts_used - (long)p->edges + (long)p->faces;
    for (size_t k = 0; k < m->ntris; k++) {
        const double *a = m->pos + 3 * m->tri[3 * k], *b = m->pos + 3 * m->tri[3 * k + 1],
                     *c = m->pos + 3 * m->tri[3 * k + 2];
        double u[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]};
        double w[3] = {c[0] - a[0], c[1] - a[1], c[2] - a[2]};
        double x[3] = {u[1] * w[2] - u[2] * w[1], u[2] * w[0] - u[0] * w[2], u[0] * w[1] - u[1] * w[0]};
        p->area += 0.5 * sqrt(x[0] * x[0] + x[1] * x[1] + x[2] * x[2]);
    }
    ism_eval_ws *ws = ism_eval_ws_new(t);
    for (uint32_t v = 0; v < m->nverts; v++) {
        double g[3];
        const double *q = m->pos + 3 * v;
        double f = ism_eval_gradient(t, ws, q[0], q[1], q[2], g);
        double gl = sqrt(g[0] * g[0] + g[1] * g[1] + g[2] * g[2]);
        if (fabs(f) > p->max_abs_f)
            p->max_abs_f = fabs(f);
        if (gl > 1e-9 && fabs(f) / gl > p->max_dist)
            p->max_dist = fabs(f) / gl;
    }
    ism_eval_ws_free(ws);
    free(e);
    free(parent);
    free(used);
}

size_t pf_count_nm_edges(const ism_mesh *m, bool (*pred)(const double a[3], const double b[3]))
{
    edge *e = sorted_edges(m);
    size_t n = m->ntris * 3, count = 0;
    for (size_t i = 0; i < n;) {
        size_t j = i;
        while (j < n && e[j].a == e[i].a && e[j].b == e[i].b)
            j++;
        if (j - i > 2 && pred(m->pos + 3 * e[i].a, m->pos + 3 * e[i].b))
            count++;
        i = j;
    }
    free(e);
    return count;
}

size_t pf_count_edges(const ism_mesh *m, size_t lo, size_t hi,
                      bool (*pred)(const double a[3], const double b[3], const void *arg),
                      const void *arg)
{
    edge *e = sorted_edges(m);
    size_t n = m->ntris * 3, count = 0;
    for (size_t i = 0, j; i < n; i = j) {
        for (j = i; j < n && e[j].a == e[i].a && e[j].b == e[i].b; j++)
            ;
        if (j - i >= lo && j - i <= hi &&
            (!pred || pred(m->pos + 3 * e[i].a, m->pos + 3 * e[i].b, arg)))
            count++;
    }
    free(e);
    return count;
}

/* Fans round v of its n triangles tris (joined when they share a vertex other than v). */
static size_t cones_of(const ism_mesh *m, uint32_t v, const size_t *tris, size_t n)
{
    uint32_t *parent = malloc((n + 1) * sizeof *parent);
    cr_assert(parent);
    for (uint32_t i = 0; i < n; i++)
        parent[i] = i;
    for (size_t i = 0; i < n; i++)
        for (size_t j = i + 1; j < n; j++) {
            int shared = 0; /* vertices other than v common to both triangles */
            for (int a = 0; a < 3; a++)
                for (int b = 0; b < 3; b++) {
                    uint32_t p = m->tri[3 * tris[i] + a], q = m->tri[3 * tris[j] + b];
                    shared += p == q && p != v;
                }
            if (shared >= 1)
                parent[find(parent, (uint32_t)i)] = find(parent, (uint32_t)j);
        }
    size_t cones = 0;
    for (uint32_t i = 0; i < n; i++)
        cones += find(parent, i) == i;
    free(parent);
    return cones;
}

size_t pf_vertex_cones(const ism_mesh *m, uint32_t v)
{
    size_t n = 0, cap = 64;
    size_t *tris = malloc(cap * sizeof *tris);
    cr_assert(tris);
    for (size_t t = 0; t < m->ntris; t++)
        for (int k = 0; k < 3; k++)
            if (m->tri[3 * t + k] == v) {
                if (n == cap)
                    cr_assert(tris = realloc(tris, (cap *= 2) * sizeof *tris));
                tris[n++] = t;
            }
    size_t cones = cones_of(m, v, tris, n);
    free(tris);
    return cones;
}

size_t *pf_all_vertex_cones(const ism_mesh *m)
{
    size_t *start = calloc(m->nverts + 2, sizeof *start), *tris = malloc((3 * m->ntris + 1) *
                                                                         sizeof *tris);
    size_t *cones = malloc((m->nverts + 1) * sizeof *cones);
    cr_assert(start && tris && cones);
    for (size_t i = 0; i < 3 * m->ntris; i++)
        start[m->tri[i] + 2]++;
    for (uint32_t v = 0; v < m->nverts; v++)
        start[v + 2] += start[v + 1];
    for (size_t t = 0; t < m->ntris; t++) /* triangles in order, as pf_vertex_cones lists */
        for (int k = 0; k < 3; k++)
            tris[start[m->tri[3 * t + k] + 1]++] = t;
    for (uint32_t v = 0; v < m->nverts; v++)
        cones[v] = cones_of(m, v, tris + start[v], start[v + 1] - start[v]);
    free(start);
    free(tris);
    return cones;
}

bool pf_nm_edges_one_closed_curve(const ism_mesh *m, size_t *nedges)
{
    edge *e = sorted_edges(m);
    size_t n = m->ntris * 3;
    uint32_t *deg = calloc(m->nverts + 1, sizeof *deg);
    uint32_t *parent = malloc((m->nverts + 1) * sizeof *parent);
    cr_assert(deg && parent);
    for (uint32_t v = 0; v < m->nverts; v++)
        parent[v] = v;
    *nedges = 0;
    for (size_t i = 0; i < n;) {
        size_t j = i;
        while (j < n && e[j].a == e[i].a && e[j].b == e[i].b)
            j++;
        if (j - i > 2) {
            (*nedges)++;
            deg[e[i].a]++;
            deg[e[i].b]++;
            parent[find(parent, e[i].a)] = find(parent, e[i].b);
        }
        i = j;
    }
    bool ok = *nedges > 0;
    uint32_t root = UINT32_MAX;
    for (uint32_t v = 0; v < m->nverts && ok; v++) {
        if (!deg[v])
            continue;
        ok = deg[v] == 2;
        uint32_t r = find(parent, v);
        if (root == UINT32_MAX)
            root = r;
        ok = ok && r == root;
    }
    free(e);
    free(deg);
    free(parent);
    return ok;
}

static double angle_deg(const double *p, const double *q, const double *r)
{
    double u[3], v[3], dot = 0, uu = 0, vv = 0;
    for (int k = 0; k < 3; k++) {
        u[k] = q[k] - p[k], v[k] = r[k] - p[k];
        dot += u[k] * v[k], uu += u[k] * u[k], vv += v[k] * v[k];
    }
    return acos(fmax(-1, fmin(1, dot / sqrt(uu * vv)))) * 180 / M_PI;
}

double pf_tri_min_angle(const ism_mesh *m, size_t t)
{
    const uint32_t *v = m->tri + 3 * t;
    const double *a = m->pos + 3 * (size_t)v[0], *b = m->pos + 3 * (size_t)v[1],
                 *c = m->pos + 3 * (size_t)v[2];
    return fmin(angle_deg(a, b, c), fmin(angle_deg(b, c, a), angle_deg(c, a, b)));
}

void pf_tri_normal(const ism_mesh *m, size_t t, double n[3])
{
    const uint32_t *v = m->tri + 3 * t;
    const double *a = m->pos + 3 * (size_t)v[0], *b = m->pos + 3 * (size_t)v[1],
                 *c = m->pos + 3 * (size_t)v[2];
    double u[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]};
    double w[3] = {c[0] - a[0], c[1] - a[1], c[2] - a[2]};
    n[0] = u[1] * w[2] - u[2] * w[1];
    n[1] = u[2] * w[0] - u[0] * w[2];
    n[2] = u[0] * w[1] - u[1] * w[0];
    double l = sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
    for (int i = 0; i < 3; i++)
        n[i] /= l;
}

void pf_same_mesh(const ism_mesh *a, const ism_mesh *b, const char *what)
{
    cr_assert_eq(a->nverts, b->nverts, "%s: %zu vertices against %zu", what, a->nverts,
                 b->nverts);
    cr_assert_eq(a->ntris, b->ntris, "%s: %zu triangles against %zu", what, a->ntris, b->ntris);
    cr_assert_eq(a->nsegs, b->nsegs, "%s: %zu segments against %zu", what, a->nsegs, b->nsegs);
    cr_assert(memcmp(a->pos, b->pos, 3 * a->nverts * sizeof *a->pos) == 0, "%s: positions",
              what);
    cr_assert(memcmp(a->normal, b->normal, 3 * a->nverts * sizeof *a->normal) == 0,
              "%s: normals", what);
    cr_assert(memcmp(a->tri, b->tri, 3 * a->ntris * sizeof *a->tri) == 0, "%s: triangles",
              what);
    cr_assert(a->nsegs == 0 || memcmp(a->seg, b->seg, 2 * a->nsegs * sizeof *a->seg) == 0,
              "%s: segments", what);
}

double pf_vec_angle_deg(const double a[3], const double b[3])
{
    double d = (a[0] * b[0] + a[1] * b[1] + a[2] * b[2]) /
               sqrt((a[0] * a[0] + a[1] * a[1] + a[2] * a[2]) *
                    (b[0] * b[0] + b[1] * b[1] + b[2] * b[2]));
    return acos(fmax(-1, fmin(1, d))) * 180 / M_PI;
}

static const ism_param unit_r[] = {{"r", 1}};
const pf_surface pf_unit_sphere = {"x^2 + y^2 + z^2 - r^2", unit_r, 1, NULL, 0};
static const ism_param ring_rr[] = {{"R", 1}, {"r", 0.3}};
const pf_surface pf_ring_torus = {"(x^2 + y^2 + z^2 + R^2 - r^2)^2 - 4*R^2*(x^2 + y^2)",
                                  ring_rr, 2, NULL, 0};
static const ism_param barth_phi[] = {{"phi", 1.6180339887498949}};
const pf_surface pf_barth_sextic = {
    "max(4*(phi^2*x^2 - y^2)*(phi^2*y^2 - z^2)*(phi^2*z^2 - x^2) - "
    "(1 + 2*phi)*(x^2 + y^2 + z^2 - 1)^2, x^2 + y^2 + z^2 - 2.25)",
    barth_phi, 1, NULL, 0};

static const ism_param gyroid_k[] = {{"k", 4}};
const pf_surface pf_gyroid_ball = {
    "max(sin(k*x)*cos(k*y) + sin(k*y)*cos(k*z) + sin(k*z)*cos(k*x), x^2 + y^2 + z^2 - 1.96)",
    gyroid_k, 1, NULL, 0};

double pf_unit_sphere_dist(const double p[3])
{
    return fabs(sqrt(p[0] * p[0] + p[1] * p[1] + p[2] * p[2]) - 1);
}

double pf_ring_torus_dist(const double p[3])
{
    double ring = sqrt(p[0] * p[0] + p[1] * p[1]) - 1;
    return fabs(sqrt(ring * ring + p[2] * p[2]) - 0.3);
}

double pf_worst_distance(const ism_mesh *m, double (*dist)(const double *))
{
    double worst = 0;
    for (size_t v = 0; v < m->nverts; v++)
        worst = fmax(worst, fabs(dist(m->pos + 3 * v)));
    for (size_t t = 0; t < m->ntris; t++) {
        const double *v[3];
        for (int k = 0; k < 3; k++)
            v[k] = m->pos + 3 * (size_t)m->tri[3 * t + k];
        double c[3], mid[3];
        for (int k = 0; k < 3; k++) {
            for (int a = 0; a < 3; a++) {
                c[a] = (v[0][a] + v[1][a] + v[2][a]) / 3;
                mid[a] = (v[k][a] + v[(k + 1) % 3][a]) / 2;
            }
            worst = fmax(worst, fmax(fabs(dist(c)), fabs(dist(mid))));
        }
    }
    return worst;
}

/* Distance from p to f = 0 by Newton's projection (the last iterate's distance plus its
 * |f| / |∇f| when it does not settle: an over-estimate). */
double pf_newton_dist(const ism_tape *t, ism_eval_ws *ws, const double p[3])
{
    double q[3] = {p[0], p[1], p[2]}, g[3], last = 0;
    for (int it = 0; it < 50; it++) {
        double f = ism_eval_gradient(t, ws, q[0], q[1], q[2], g);
        double gg = g[0] * g[0] + g[1] * g[1] + g[2] * g[2];
        if (!(gg > 0) || !isfinite(f))
            break;
        last = fabs(f) / sqrt(gg);
        if (last < 1e-13) {
            last = 0;
            break;
        }
        for (int k = 0; k < 3; k++)
            q[k] -= f * g[k] / gg;
    }
    double d2 = 0;
    for (int k = 0; k < 3; k++)
        d2 += (q[k] - p[k]) * (q[k] - p[k]);
    return sqrt(d2) + last;
}

/* The farthest centroid or edge midpoint from f = 0, by dist (NULL: Newton on t); the
 * triangles whose normal points against ∇f at their centroid into *turned (the mesh is
 * oriented along ∇f, fans included). */
double pf_worst_turned(const ism_mesh *m, const ism_tape *t, double (*dist)(const double *),
                    size_t *turned)
{
    ism_eval_ws *ws = ism_eval_ws_new(t);
    cr_assert(ws);
    double w = 0;
    *turned = 0;
    for (size_t i = 0; i < m->ntris; i++) {
        const double *p[3];
        for (int j = 0; j < 3; j++)
            p[j] = m->pos + 3 * (size_t)m->tri[3 * i + j];
        double q[4][3], g[3], n[3];
        for (int a = 0; a < 3; a++) {
            q[0][a] = (p[0][a] + p[1][a] + p[2][a]) / 3;
            for (int j = 0; j < 3; j++)
                q[1 + j][a] = 0.5 * (p[j][a] + p[(j + 1) % 3][a]);
        }
        for (int k = 0; k < 4; k++)
            w = fmax(w, dist ? dist(q[k]) : pf_newton_dist(t, ws, q[k]));
        ism_eval_gradient(t, ws, q[0][0], q[0][1], q[0][2], g);
        pf_tri_normal(m, i, n);
        *turned += n[0] * g[0] + n[1] * g[1] + n[2] * g[2] < 0;
    }
    ism_eval_ws_free(ws);
    return w;
}

void pf_analyse_plain(const ism_mesh *m, const ism_tape *t, ism_analysis *a)
{
    ism_analysis_options ao;
    ism_analysis_options_default(&ao);
    ao.curvature = false;
    ao.threads = 1;
    ism_error err;
    cr_assert(ism_analyse(m, t, &ao, a, &err), "analyse: %s", err.message);
}
