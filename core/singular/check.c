/* check.c — the mesh against the locus (contract in check.h). The locus's curve segments go
 * into a uniform grid of buckets; a mesh vertex is on the locus when it is within the
 * tolerance of a singular point or of a segment in its bucket's neighbourhood. Cones of faces
 * at a singular point's vertex are counted locally: its triangles, joined when they share an
 * edge through the vertex. */
#include "core/singular/check.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

/* Buckets per axis: 64³ bucket starts are 1 MiB; a bucket then spans 2 to 16 finest cells
 * at depths 7 to 10, so it holds a few dozen segments of a curve traced at cell steps. */
#define GRID_MAX_SIDE 64

typedef struct seg_grid {
    double lo[3], cell;
    int side;
    size_t nsegs;
    const double **a, **b; /* segment ends, per segment */
    uint32_t *start;       /* side³ + 1 bucket starts into idx */
    uint32_t *idx;         /* segment numbers, bucketed */
} seg_grid;

static double dist2_point_segment(const double p[3], const double a[3], const double b[3])
{
    double ab[3], ap[3], t = 0, l2 = 0;
    for (int k = 0; k < 3; k++) {
        ab[k] = b[k] - a[k];
        ap[k] = p[k] - a[k];
        l2 += ab[k] * ab[k];
        t += ab[k] * ap[k];
    }
    t = l2 > 0 ? fmin(1.0, fmax(0.0, t / l2)) : 0.0;
    double d2 = 0;
    for (int k = 0; k < 3; k++) {
        double d = ap[k] - t * ab[k];
        d2 += d * d;
    }
    return d2;
}

static int bucket_of(const seg_grid *g, double x, int k)
{
    int i = (int)floor((x - g->lo[k]) / g->cell);
    return i < 0 ? 0 : i >= g->side ? g->side - 1 : i;
}

/* Bucket ranges [i0, i1] per axis of the segment's box grown by pad. */
static void seg_range(const seg_grid *g, const double *a, const double *b, double pad,
                      int i0[3], int i1[3])
{
    for (int k = 0; k < 3; k++) {
        i0[k] = bucket_of(g, fmin(a[k], b[k]) - pad, k);
        i1[k] = bucket_of(g, fmax(a[k], b[k]) + pad, k);
    }
}

static size_t bucket_index(const seg_grid *g, int i, int j, int k)
{
    return ((size_t)i * g->side + j) * g->side + k;
}

/* Visits every bucket of a segment: counting (idx == NULL) or filling. */
static void place(seg_grid *g, size_t s, double pad, uint32_t *fill)
{
    int i0[3], i1[3];
    seg_range(g, g->a[s], g->b[s], pad, i0, i1);
    for (int i = i0[0]; i <= i1[0]; i++)
        for (int j = i0[1]; j <= i1[1]; j++)
            for (int k = i0[2]; k <= i1[2]; k++) {
                size_t c = bucket_index(g, i, j, k);
                if (fill)
                    g->idx[fill[c]++] = (uint32_t)s;
                else
                    g->start[c + 1]++;
            }
}

static void grid_free(seg_grid *g)
{
    free(g->a);
    free(g->b);
    free(g->start);
    free(g->idx);
}

/* Segments of every curve (a closed curve also joins its last point to its first). */
static bool grid_build(seg_grid *g, const ism_locus *l, const double box[6], double pad)
{
    memset(g, 0, sizeof *g);
    size_t n = 0;
    for (size_t c = 0; c < l->ncurves; c++)
        n += l->curves[c].n > 1 ? l->curves[c].n - 1 + l->curves[c].closed : 0;
    double side = 0;
    for (int k = 0; k < 3; k++) {
        g->lo[k] = box[k];
        side = fmax(side, box[k + 3] - box[k]);
    }
    g->side = n ? GRID_MAX_SIDE : 1;
    g->cell = side / g->side;
    size_t cells = (size_t)g->side * g->side * g->side;
    g->a = malloc((n ? n : 1) * sizeof *g->a);
    g->b = malloc((n ? n : 1) * sizeof *g->b);
    g->start = calloc(cells + 1, sizeof *g->start);
    if (!g->a || !g->b || !g->start)
        return false;
    for (size_t c = 0; c < l->ncurves; c++) {
        const ism_sing_curve *cv = &l->curves[c];
        size_t segs = cv->n > 1 ? cv->n - 1 + cv->closed : 0;
        for (size_t i = 0; i < segs; i++) {
            g->a[g->nsegs] = cv->xyz + 3 * i;
            g->b[g->nsegs] = cv->xyz + 3 * ((i + 1) % cv->n);
            g->nsegs++;
        }
    }
    for (size_t s = 0; s < g->nsegs; s++)
        place(g, s, pad, NULL);
    for (size_t c = 0; c < cells; c++)
        g->start[c + 1] += g->start[c];
    g->idx = malloc((g->start[cells] ? g->start[cells] : 1) * sizeof *g->idx);
    uint32_t *fill = malloc(cells * sizeof *fill);
    if (!g->idx || !fill) {
        free(fill);
        return false;
    }
    memcpy(fill, g->start, cells * sizeof *fill);
    for (size_t s = 0; s < g->nsegs; s++)
        place(g, s, pad, fill);
    free(fill);
    return true;
}

static bool near_locus(const ism_locus *l, const seg_grid *g, const double p[3], double tol)
{
    double t2 = tol * tol;
    for (size_t i = 0; i < l->npoints; i++) {
        double d2 = 0;
        for (int k = 0; k < 3; k++)
            d2 += (p[k] - l->points[i].p[k]) * (p[k] - l->points[i].p[k]);
        if (d2 <= t2)
            return true;
    }
    if (!g->nsegs)
        return false;
    size_t c = bucket_index(g, bucket_of(g, p[0], 0), bucket_of(g, p[1], 1),
                            bucket_of(g, p[2], 2));
    for (uint32_t j = g->start[c]; j < g->start[c + 1]; j++)
        if (dist2_point_segment(p, g->a[g->idx[j]], g->b[g->idx[j]]) <= t2)
            return true;
    return false;
}

/* Cones of faces at vertex v: v's triangles, joined when they share an edge at v. */
static int cones_at(const ism_mesh *m, uint32_t v)
{
    size_t n = 0, cap = 0;
    uint32_t(*other)[2] = NULL; /* the two other corners of each triangle at v */
    for (size_t t = 0; t < m->ntris; t++) {
        const uint32_t *c = m->tri + 3 * t;
        if (c[0] == c[1] || c[1] == c[2] || c[0] == c[2])
            continue;
        int at = c[0] == v ? 0 : c[1] == v ? 1 : c[2] == v ? 2 : -1;
        if (at < 0)
            continue;
        if (n == cap) {
            cap = cap ? 2 * cap : 16;
            void *p = realloc(other, cap * sizeof *other);
            if (!p) {
                free(other);
                return -1;
            }
            other = p;
        }
        other[n][0] = c[(at + 1) % 3];
        other[n][1] = c[(at + 2) % 3];
        n++;
    }
    int *parent = malloc((n ? n : 1) * sizeof *parent);
    if (!parent) {
        free(other);
        return -1;
    }
    for (size_t i = 0; i < n; i++)
        parent[i] = (int)i;
    int cones = (int)n;
    for (size_t i = 0; i < n; i++)
        for (size_t j = i + 1; j < n; j++) {
            bool share = other[i][0] == other[j][0] || other[i][0] == other[j][1] ||
                         other[i][1] == other[j][0] || other[i][1] == other[j][1];
            if (!share)
                continue;
            int a = (int)i, b = (int)j;
            while (parent[a] != a)
                a = parent[a];
            while (parent[b] != b)
                b = parent[b];
            if (a != b) {
                parent[a] = b;
                cones--;
            }
        }
    free(parent);
    free(other);
    return cones;
}

/* The mesh vertex nearest to p within tol, or UINT32_MAX. */
static uint32_t vertex_at(const ism_mesh *m, const double p[3], double tol)
{
    uint32_t best = UINT32_MAX;
    double best2 = tol * tol;
    for (size_t v = 0; v < m->nverts; v++) {
        double d2 = 0;
        for (int k = 0; k < 3; k++)
            d2 += (m->pos[3 * v + k] - p[k]) * (m->pos[3 * v + k] - p[k]);
        if (d2 <= best2) {
            best2 = d2;
            best = (uint32_t)v;
        }
    }
    return best;
}

void ism_locus_check_free(ism_locus_check *c)
{
    free(c->curve_on);
    free(c->point_on);
    free(c->point_vertex);
    free(c->point_cones);
    memset(c, 0, sizeof *c);
}

static void check_curves(const ism_locus *l, const seg_grid *g, const ism_mesh *m,
                         const ism_analysis *a, double tol, ism_locus_check *out)
{
    for (size_t c = 0; c < a->ncurves; c++) {
        bool all = true;
        bool prev_on = false;
        for (uint32_t j = a->curve_start[c]; j < a->curve_start[c + 1]; j++) {
            bool on = near_locus(l, g, m->pos + 3 * (size_t)a->curve_verts[j], tol);
            if (j > a->curve_start[c]) {
                out->nonmanifold_edges++;
                out->nonmanifold_edges_off += !(on && prev_on);
            }
            prev_on = on;
            all = all && on;
        }
        out->curve_on[c] = all;
    }
}

bool ism_locus_check_mesh(const ism_locus *l, const double box[6], const ism_mesh *m,
                          const ism_analysis *a, ism_locus_check *out, ism_error *err)
{
    memset(out, 0, sizeof *out);
    double diag = 0;
    for (int k = 0; k < 3; k++)
        diag += (box[k + 3] - box[k]) * (box[k + 3] - box[k]);
    double tol = ISM_LOCUS_ON_REL * sqrt(diag);
    seg_grid g;
    bool ok = grid_build(&g, l, box, tol);
    out->curve_on = calloc(a->ncurves ? a->ncurves : 1, 1);
    out->point_on = calloc(a->npoints ? a->npoints : 1, 1);
    out->point_vertex = malloc((l->npoints ? l->npoints : 1) * sizeof *out->point_vertex);
    out->point_cones = calloc(l->npoints ? l->npoints : 1, sizeof *out->point_cones);
    ok = ok && out->curve_on && out->point_on && out->point_vertex && out->point_cones;
    if (ok) {
        check_curves(l, &g, m, a, tol, out);
        out->nonmanifold_points = a->npoints;
        for (size_t i = 0; i < a->npoints; i++) {
            out->point_on[i] = near_locus(l, &g, m->pos + 3 * (size_t)a->points[i], tol);
            out->nonmanifold_points_off += !out->point_on[i];
        }
        out->artefacts = out->nonmanifold_edges_off + out->nonmanifold_points_off;
        for (size_t i = 0; i < l->npoints && ok; i++) {
            out->point_vertex[i] = vertex_at(m, l->points[i].p, tol);
            int c = out->point_vertex[i] == UINT32_MAX ? 0 : cones_at(m, out->point_vertex[i]);
            ok = c >= 0;
            out->point_cones[i] = c;
        }
    }
    grid_free(&g);
    if (!ok) {
        ism_locus_check_free(out);
        return ism_error_set(err, "out of memory checking the mesh against the singular locus");
    }
    return true;
}
