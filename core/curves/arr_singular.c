/* arr_singular.c — which curve vertices lie on the singular locus, so that the arrangement
 * types them and its curves end there: a vertex within the tolerance of a singular point of
 * the locus (the conformance pass put the point's vertex on it), else a vertex ending a mesh
 * edge of three or more triangles (a double curve, which the conformance pass made a chain of
 * such edges) that a curve crosses rather than runs along. */
#include "core/curves/arr_internal.h"
#include <math.h>
#include <stdlib.h>

typedef struct by_x {
    double x;
    uint32_t i;
} by_x;

static int cmp_by_x(const void *a, const void *b)
{
    double x = ((const by_x *)a)->x, y = ((const by_x *)b)->x;
    return (x > y) - (x < y);
}

/* The locus point nearest p within tol (points sorted by x), or ARR_SING_NONE. */
static uint32_t point_at(const by_x *s, size_t n, const ism_sing_point *pts, const double *p,
                         double tol)
{
    size_t lo = 0, hi = n;
    while (lo < hi) { /* the first point with x ≥ p.x − tol */
        size_t mid = (lo + hi) / 2;
        if (s[mid].x < p[0] - tol)
            lo = mid + 1;
        else
            hi = mid;
    }
    uint32_t best = ARR_SING_NONE;
    double best_d = tol;
    for (size_t k = lo; k < n && s[k].x <= p[0] + tol; k++) {
        const double *q = pts[s[k].i].p;
        double d = sqrt((p[0] - q[0]) * (p[0] - q[0]) + (p[1] - q[1]) * (p[1] - q[1]) +
                        (p[2] - q[2]) * (p[2] - q[2]));
        if (d <= best_d) {
            best_d = d;
            best = s[k].i;
        }
    }
    return best;
}

/* Whether a cut edge lies on a mesh edge of three or more triangles. */
static bool cut_edge_double(const arr_mesh_edges *e, const ism_cut_edge *c)
{
    uint32_t k = arr_edge_find(e, c->a, c->b);
    return k != ARR_NO_EDGE && e->ntri[k] > 2;
}

/* v_double[v]: 1 when v ends a mesh edge of three or more triangles; 2 when, moreover, some
 * cut edge at v does not lie on such an edge (the curve crosses or leaves the double curve
 * there, not only runs along it). */
static void double_curve_vertices(const ism_mesh *m, const ism_cut *c, const arr_mesh_edges *e,
                                  uint8_t *v_double)
{
    for (size_t t = 0; t < m->ntris; t++)
        for (int i = 0; i < 3; i++)
            if (e->ntri[e->tri_edge[3 * t + i]] > 2)
                v_double[m->tri[3 * t + i]] = v_double[m->tri[3 * t + (i + 1) % 3]] = 1;
    for (size_t i = 0; i < c->nedges; i++) {
        const ism_cut_edge *ce = &c->edges[i];
        if (cut_edge_double(e, ce))
            continue;
        if (v_double[ce->a])
            v_double[ce->a] = 2;
        if (v_double[ce->b])
            v_double[ce->b] = 2;
    }
}

bool arr_singular_marks(const ism_mesh *m, const ism_cut *c, const arr_mesh_edges *e,
                        const ism_locus *l, double tol, uint32_t *mark)
{
    size_t np = l ? l->npoints : 0;
    by_x *s = malloc((np + 1) * sizeof *s);
    uint8_t *v_double = calloc(m->nverts + 1, 1);
    bool ok = s && v_double;
    if (ok) {
        for (size_t i = 0; i < np; i++)
            s[i] = (by_x){l->points[i].p[0], (uint32_t)i};
        qsort(s, np, sizeof *s, cmp_by_x);
        double_curve_vertices(m, c, e, v_double);
        for (size_t v = 0; v < m->nverts; v++) {
            mark[v] = ARR_SING_NONE;
            if (!e->v_on_curve[v])
                continue;
            if (np)
                mark[v] = point_at(s, np, l->points, m->pos + 3 * v, tol);
            if (mark[v] == ARR_SING_NONE && v_double[v] == 2)
                mark[v] = ARR_SING_DOUBLE;
        }
    }
    free(s);
    free(v_double);
    return ok;
}
