/* check.c — the mesh against the locus (contract in check.h). The locus's curve segments go
 * into a uniform grid of buckets; a mesh vertex is on the locus when it is within the
 * tolerance of a singular point (filed by position in a hash of small cells) or of a segment
 * in its bucket's neighbourhood (the tolerance plus the segment's bulge: how far the curve
 * itself may bend from that chord). Each singular point's vertex is found in one pass over the
 * vertices, and the cones of faces at those vertices in one pass over the triangles: a
 * vertex's triangles, joined when they share an edge through the vertex. */
#include "core/singular/check.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>
#include "core/singular/key_map.h"
#include "core/util/vec3.h"

/* Buckets per axis: 64³ bucket starts are 1 MiB; a bucket then spans 2 to 16 finest cells
 * at depths 7 to 10, so it holds a few dozen segments of a curve traced at cell steps. */
#define GRID_MAX_SIDE 64
/* A point's cells are those of its tol-box grown by this fraction: a vertex at exactly tol
 * is never lost to the rounding of p ± tol. */
#define TOL_SLACK 1e-6

typedef struct seg_grid {
    double lo[3], cell;
    int side;
    size_t nsegs;
    const double **a, **b; /* segment ends, per segment */
    double *bulge;         /* per segment: how far the curve may bend from its chord */
    uint32_t *start;       /* side³ + 1 bucket starts into idx */
    uint32_t *idx;         /* segment numbers, bucketed */
} seg_grid;

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

/* Visits every bucket of a segment (its box grown by pad and its bulge): counting
 * (idx == NULL) or filling. */
static void place(seg_grid *g, size_t s, double pad, uint32_t *fill)
{
    int i0[3], i1[3];
    seg_range(g, g->a[s], g->b[s], pad + g->bulge[s], i0, i1);
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
    free(g->bulge);
    free(g->start);
    free(g->idx);
}

/* The curvature of the circle through p, q, r (Menger: 4 × area / product of the sides);
 * 0 when two of them coincide. */
static double curvature3(const double p[3], const double q[3], const double r[3])
{
    double x[3];
    ism_tri_cross3(p, q, r, x);
    double sides = ism_dist3(p, q) * ism_dist3(q, r) * ism_dist3(p, r);
    return sides > 0 ? 2 * ism_norm3(x) / sides : 0;
}

/* How far the curve may lie from the chord from point i to point i + 1 of cv. The traced
 * points sit on the curve (within 1e-9 × diagonal, locus.h), but a chord of length h of a
 * curve of curvature k is up to its sagitta h² k / 8 from the arc it cuts (1.3e-5 for the
 * 0.01 steps of a circle of radius 0.97, over 1e-6 × a diagonal of 5): a vertex the mesh
 * puts exactly on the curve between two traced points must not count as off. k is the
 * curvature of the circle through the segment and a neighbouring point, at each end; the
 * smaller of the two is taken, so a kink of the polyline at one end (a curve turning at a
 * singular point, where no arc bends) gives no allowance, and it is doubled for the change
 * of curvature along one step. It never exceeds h / 8 (the sagitta of an arc turning 56°
 * over one chord, far past the few degrees a trace at cell steps turns). A segment without neighbours (a curve
 * of two points) gets none. */
static double chord_bulge(const ism_sing_curve *cv, size_t i)
{
    size_t n = cv->n, j = (i + 1) % n;
    const double *a = cv->xyz + 3 * i, *b = cv->xyz + 3 * j;
    double h = ism_dist3(a, b), k = INFINITY;
    if (n >= 3 && (i > 0 || cv->closed))
        k = fmin(k, curvature3(cv->xyz + 3 * ((i + n - 1) % n), a, b));
    if (n >= 3 && (j + 1 < n || cv->closed))
        k = fmin(k, curvature3(a, b, cv->xyz + 3 * ((j + 1) % n)));
    if (k == INFINITY)
        return 0;
    return fmin(2 * h * h * k / 8, h / 8);
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
    g->bulge = malloc((n ? n : 1) * sizeof *g->bulge);
    g->start = calloc(cells + 1, sizeof *g->start);
    if (!g->a || !g->b || !g->bulge || !g->start)
        return false;
    for (size_t c = 0; c < l->ncurves; c++) {
        const ism_sing_curve *cv = &l->curves[c];
        size_t segs = cv->n > 1 ? cv->n - 1 + cv->closed : 0;
        for (size_t i = 0; i < segs; i++) {
            g->a[g->nsegs] = cv->xyz + 3 * i;
            g->b[g->nsegs] = cv->xyz + 3 * ((i + 1) % cv->n);
            g->bulge[g->nsegs] = chord_bulge(cv, i);
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

/* The singular points by position: each is filed in the cells (side 2 tol, so at most
 * eight) that its tol-box meets, so a position looks at the points of its own cell only. */
typedef struct point_grid {
    double lo[3], cell;
    ism_key_map cells;   /* packed cell coordinates → cell number */
    uint32_t *head;      /* per cell: first filing (UINT32_MAX: none) */
    uint32_t *next;      /* per filing: the next one in its cell */
    uint32_t *point;     /* per filing: the point filed */
    size_t n;
} point_grid;

/* A position's cell coordinates (false when not finite: never within tol of anything). */
static bool point_cell(const point_grid *g, const double p[3], int64_t c[3])
{
    for (int k = 0; k < 3; k++) {
        double x = floor((p[k] - g->lo[k]) / g->cell);
        if (!(fabs(x) < 4e18))
            return false;
        c[k] = (int64_t)x;
    }
    return true;
}

/* Cell coordinates packed 21 bits an axis; far cells wrap onto others, which only adds
 * points to measure. */
static uint64_t point_cell_key(const int64_t c[3])
{
    return ((uint64_t)c[0] & 0x1fffff) << 42 | ((uint64_t)c[1] & 0x1fffff) << 21 |
           ((uint64_t)c[2] & 0x1fffff);
}

static void point_grid_free(point_grid *g)
{
    ism_key_map_free(&g->cells);
    free(g->head);
    free(g->next);
    free(g->point);
}

/* Files point i in cell c. */
static bool file_point(point_grid *g, const int64_t c[3], uint32_t i)
{
    bool added;
    uint32_t cell = ism_key_map_add(&g->cells, point_cell_key(c), &added);
    if (cell == ISM_KEY_NONE)
        return false;
    g->point[g->n] = i;
    g->next[g->n] = added ? UINT32_MAX : g->head[cell];
    g->head[cell] = (uint32_t)g->n++;
    return true;
}

static bool point_grid_build(point_grid *g, const ism_locus *l, const double box[6], double tol)
{
    memset(g, 0, sizeof *g);
    ism_key_map_init(&g->cells);
    for (int k = 0; k < 3; k++)
        g->lo[k] = box[k];
    g->cell = 2 * tol;
    /* a tol-box spans two cells an axis, three when rounding puts it on a cell face */
    size_t cap = 27 * l->npoints + 1;
    g->head = malloc(cap * sizeof *g->head);
    g->next = malloc(cap * sizeof *g->next);
    g->point = malloc(cap * sizeof *g->point);
    if (!g->head || !g->next || !g->point)
        return false;
    for (size_t i = 0; i < l->npoints; i++) {
        double lo[3], hi[3];
        for (int k = 0; k < 3; k++) { /* grown a little: the rounding of p ± tol */
            lo[k] = l->points[i].p[k] - tol * (1 + TOL_SLACK);
            hi[k] = l->points[i].p[k] + tol * (1 + TOL_SLACK);
        }
        int64_t a[3], b[3], c[3];
        if (!point_cell(g, lo, a) || !point_cell(g, hi, b))
            continue; /* not finite: no vertex is within tol of it */
        for (int k = 0; k < 3; k++)
            b[k] = b[k] > a[k] + 2 ? a[k] + 2 : b[k];
        for (c[0] = a[0]; c[0] <= b[0]; c[0]++)
            for (c[1] = a[1]; c[1] <= b[1]; c[1]++)
                for (c[2] = a[2]; c[2] <= b[2]; c[2]++)
                    if (!file_point(g, c, (uint32_t)i))
                        return false;
    }
    return true;
}

/* The first filing of the points whose tol-box meets p's cell (UINT32_MAX: none). */
static uint32_t points_near(const point_grid *g, const double p[3])
{
    int64_t c[3];
    if (!g->n || !point_cell(g, p, c))
        return UINT32_MAX;
    uint32_t cell = ism_key_map_find(&g->cells, point_cell_key(c));
    return cell == ISM_KEY_NONE ? UINT32_MAX : g->head[cell];
}

static bool near_locus(const ism_locus *l, const point_grid *pg, const seg_grid *g,
                       const double p[3], double tol)
{
    double t2 = tol * tol;
    for (uint32_t f = points_near(pg, p); f != UINT32_MAX; f = pg->next[f])
        if (ism_sqdist3(p, l->points[pg->point[f]].p) <= t2)
            return true;
    if (!g->nsegs)
        return false;
    size_t c = bucket_index(g, bucket_of(g, p[0], 0), bucket_of(g, p[1], 1),
                            bucket_of(g, p[2], 2));
    for (uint32_t j = g->start[c]; j < g->start[c + 1]; j++) {
        uint32_t s = g->idx[j];
        double r = tol + g->bulge[s];
        if (ism_sqdist_segment3(p, g->a[s], g->b[s]) <= r * r)
            return true;
    }
    return false;
}

/* For each point of the locus, the mesh vertex nearest to it within tol (the last of equals)
 * or UINT32_MAX: one pass over the vertices. */
static void vertices_at_points(const ism_locus *l, const point_grid *pg, const ism_mesh *m,
                               double tol, uint32_t *vertex, double *best2)
{
    for (size_t i = 0; i < l->npoints; i++) {
        vertex[i] = UINT32_MAX;
        best2[i] = tol * tol;
    }
    for (size_t v = 0; v < m->nverts; v++)
        for (uint32_t f = points_near(pg, m->pos + 3 * v); f != UINT32_MAX; f = pg->next[f]) {
            uint32_t i = pg->point[f];
            double d2 = ism_sqdist3(m->pos + 3 * v, l->points[i].p);
            if (d2 <= best2[i]) {
                best2[i] = d2;
                vertex[i] = (uint32_t)v;
            }
        }
}

/* Cones of faces at a vertex from the two other corners of each of its triangles: the
 * triangles joined when they share an edge at the vertex. */
static int cones_of(uint32_t (*other)[2], size_t n, int *parent)
{
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
    return cones;
}

/* cones[i] for each point's vertex (0 without one): the triangles at those vertices taken
 * in one pass over the mesh (collapsed ones left out), grouped by vertex. False when out of
 * memory. */
static bool cones_at_points(const ism_mesh *m, const uint32_t *vertex, size_t np, int *cones)
{
    /* slot[v]: the first point at vertex v, + 1 (0: no point there) */
    uint32_t *slot = calloc(m->nverts + 1, sizeof *slot), *count = calloc(np + 1, sizeof *count);
    uint32_t *start = calloc(np + 2, sizeof *start), (*other)[2] = NULL;
    int *parent = NULL;
    bool ok = slot && count && start;
    for (size_t i = 0; ok && i < np; i++)
        if (vertex[i] != UINT32_MAX && !slot[vertex[i]])
            slot[vertex[i]] = (uint32_t)i + 1;
    for (int pass = 0; ok && pass < 2; pass++) { /* count, then fill in triangle order */
        for (size_t t = 0; t < m->ntris; t++) {
            const uint32_t *c = m->tri + 3 * t;
            if (c[0] == c[1] || c[1] == c[2] || c[0] == c[2])
                continue;
            for (int at = 0; at < 3; at++) {
                uint32_t s = slot[c[at]];
                if (!s--)
                    continue;
                if (pass == 0) {
                    count[s]++;
                    continue;
                }
                other[start[s] + count[s]][0] = c[(at + 1) % 3];
                other[start[s] + count[s]][1] = c[(at + 2) % 3];
                count[s]++;
            }
        }
        if (pass == 0) {
            size_t most = 0;
            for (size_t i = 0; i < np; i++) {
                start[i + 1] = start[i] + count[i];
                most = count[i] > most ? count[i] : most;
                count[i] = 0;
            }
            other = malloc((start[np] + 1) * sizeof *other);
            parent = malloc((most + 1) * sizeof *parent);
            ok = other && parent;
        }
    }
    for (size_t i = 0; ok && i < np; i++) {
        uint32_t s = vertex[i] == UINT32_MAX ? 0 : slot[vertex[i]];
        cones[i] = s ? cones_of(other + start[s - 1], count[s - 1], parent) : 0;
    }
    free(slot);
    free(count);
    free(start);
    free(other);
    free(parent);
    return ok;
}

void ism_locus_check_free(ism_locus_check *c)
{
    free(c->curve_on);
    free(c->curve_vert_on);
    free(c->point_on);
    free(c->point_vertex);
    free(c->point_cones);
    memset(c, 0, sizeof *c);
}

static void check_curves(const ism_locus *l, const point_grid *pg, const seg_grid *g,
                         const ism_mesh *m, const ism_analysis *a, double tol,
                         ism_locus_check *out)
{
    for (size_t c = 0; c < a->ncurves; c++) {
        bool all = true;
        bool prev_on = false;
        for (uint32_t j = a->curve_start[c]; j < a->curve_start[c + 1]; j++) {
            bool on = near_locus(l, pg, g, m->pos + 3 * (size_t)a->curve_verts[j], tol);
            if (j > a->curve_start[c]) {
                out->nonmanifold_edges++;
                out->nonmanifold_edges_off += !(on && prev_on);
            }
            out->curve_vert_on[j] = on;
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
    double tol = ISM_LOCUS_ON_REL * ism_box_diagonal(box);
    seg_grid g;
    point_grid pg;
    double *best2 = malloc((l->npoints ? l->npoints : 1) * sizeof *best2);
    bool ok = grid_build(&g, l, box, tol) && point_grid_build(&pg, l, box, tol) && best2;
    out->curve_on = calloc(a->ncurves ? a->ncurves : 1, 1);
    size_t nchain = a->ncurves ? a->curve_start[a->ncurves] : 0;
    out->curve_vert_on = calloc(nchain ? nchain : 1, 1);
    out->point_on = calloc(a->npoints ? a->npoints : 1, 1);
    out->point_vertex = malloc((l->npoints ? l->npoints : 1) * sizeof *out->point_vertex);
    out->point_cones = calloc(l->npoints ? l->npoints : 1, sizeof *out->point_cones);
    ok = ok && out->curve_on && out->curve_vert_on && out->point_on && out->point_vertex && out->point_cones;
    if (ok) {
        check_curves(l, &pg, &g, m, a, tol, out);
        out->nonmanifold_points = a->npoints;
        for (size_t i = 0; i < a->npoints; i++) {
            out->point_on[i] = near_locus(l, &pg, &g, m->pos + 3 * (size_t)a->points[i], tol);
            out->nonmanifold_points_off += !out->point_on[i];
        }
        out->artefacts = out->nonmanifold_edges_off + out->nonmanifold_points_off;
        vertices_at_points(l, &pg, m, tol, out->point_vertex, best2);
        ok = cones_at_points(m, out->point_vertex, l->npoints, out->point_cones);
    }
    grid_free(&g);
    point_grid_free(&pg);
    free(best2);
    if (!ok) {
        ism_locus_check_free(out);
        return ism_error_set(err, "out of memory checking the mesh against the singular locus");
    }
    return true;
}
