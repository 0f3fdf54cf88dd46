/* sheet_mesh.c — marching tetrahedra on ψ inside the cells of a double sheet (see
 * sheet_mesh.h). Three passes: list the crossings of every candidate cell, project them
 * onto the sheet on all threads, then emit the triangles of the cells whose crossings all
 * landed. A vertex with ψ = 0 counts as positive; a crossing on an edge whose positive end
 * has ψ = 0 is that vertex (sheets lying on a lattice plane, such as x² in a box centred on
 * 0, then give the face's triangles once, from the cells on the negative side).
 *
 *        6───────7      Kuhn tetrahedra: the six paths 0 → 7 along the three axes in every
 *       ╱│      ╱│      order (0-1-3-7, 0-1-5-7, 0-2-3-7, 0-2-6-7, 0-4-5-7, 0-4-6-7). Each
 *      4───────5 │      face is cut by its diagonal through its lowest and highest corner,
 *      │ 2─────│─3      the same diagonal from the cells on both sides: crack-free.
 *      │╱      │╱       Corner c sits at (c & 1, c >> 1 & 1, c >> 2 & 1).
 *      0───────1                                                                          */
#include "core/singular/sheet_mesh.h"
#include "core/singular/sheet_project.h"
#include "core/util/parallel.h"
#include "core/util/vec3.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

/* Corners of a cell whose directions differ by more than acos(SHEET_AGREE) = 60° have no
 * common side for ψ: the cell is near a double curve or a point where the Hessian's
 * dominant direction is not defined, and is left out. */
#define SHEET_AGREE 0.5
/* Crossings per projection task. */
#define SHEET_CHUNK 256
/* Triangles of a cell: two per tetrahedron. */
#define CELL_TRIS 12

static const uint8_t KUHN[6][4] = {{0, 1, 3, 7}, {0, 1, 5, 7}, {0, 2, 3, 7},
                                   {0, 2, 6, 7}, {0, 4, 5, 7}, {0, 4, 6, 7}};

typedef struct xedge {
    uint32_t a, b; /* ψ(a) < 0 ≤ ψ(b) */
} xedge;

typedef struct ctri {
    xedge e[3];
} ctri;

void ism_sheet_tris_init(ism_sheet_tris *t)
{
    memset(t, 0, sizeof *t);
    ism_key_map_init(&t->xmap);
}

void ism_sheet_tris_free(ism_sheet_tris *t)
{
    ism_key_map_free(&t->xmap);
    free(t->x);
    free(t->tri);
    ism_sheet_tris_init(t);
}

static uint64_t xedge_key(const ism_sheet_field *sf, xedge e)
{
    if (sf->v[e.b].psi == 0)
        return (uint64_t)e.b << 32 | e.b;
    uint32_t lo = e.a < e.b ? e.a : e.b, hi = e.a ^ e.b ^ lo;
    return (uint64_t)lo << 32 | hi;
}

/* Where ψ interpolated linearly along the edge vanishes. */
static void xedge_point(const ism_sheet_field *sf, xedge e, double q[3])
{
    double sa = sf->v[e.a].psi, sb = sf->v[e.b].psi;
    const double *pa = ism_sheet_field_point(sf, e.a), *pb = ism_sheet_field_point(sf, e.b);
    if (sb == 0) {
        memcpy(q, pb, 3 * sizeof *pb);
        return;
    }
    double t = sa / (sa - sb);
    for (int k = 0; k < 3; k++)
        q[k] = pa[k] + t * (pb[k] - pa[k]);
}

static xedge make_xedge(const ism_sheet_field *sf, uint32_t u, uint32_t v)
{
    return sf->v[u].psi < 0 ? (xedge){u, v} : (xedge){v, u};
}

/* Appends triangle (e0 e1 e2), turned so that its normal has a positive part along d. */
static void add_ctri(const ism_sheet_field *sf, xedge e0, xedge e1, xedge e2, const double d[3],
                     ctri *out, int *n)
{
    double q[3][3], nrm[3];
    xedge_point(sf, e0, q[0]);
    xedge_point(sf, e1, q[1]);
    xedge_point(sf, e2, q[2]);
    ism_tri_cross3(q[0], q[1], q[2], nrm);
    out[*n] = ism_dot3(nrm, d) >= 0 ? (ctri){{e0, e1, e2}} : (ctri){{e0, e2, e1}};
    (*n)++;
}

static void lattice_diff(const ism_sheet_field *sf, uint32_t to, uint32_t from, double d[3])
{
    const double *a = ism_sheet_field_point(sf, to), *b = ism_sheet_field_point(sf, from);
    for (int k = 0; k < 3; k++)
        d[k] = a[k] - b[k];
}

/* One positive and three negative vertices, or the reverse: the lone one is cut off. */
static void tet_corner(const ism_sheet_field *sf, const uint32_t v[4], int lone, ctri *out, int *n)
{
    uint32_t o[3];
    for (int i = 0, k = 0; i < 4; i++)
        if (i != lone)
            o[k++] = v[i];
    double d[3];
    lattice_diff(sf, v[lone], o[0], d); /* from the other side toward the lone vertex */
    if (sf->v[v[lone]].psi < 0)
        for (int k = 0; k < 3; k++)
            d[k] = -d[k];
    add_ctri(sf, make_xedge(sf, v[lone], o[0]), make_xedge(sf, v[lone], o[1]),
             make_xedge(sf, v[lone], o[2]), d, out, n);
}

static double xedge_dist(const ism_sheet_field *sf, xedge e, xedge f)
{
    double p[3], q[3];
    xedge_point(sf, e, p);
    xedge_point(sf, f, q);
    return sqrt((p[0] - q[0]) * (p[0] - q[0]) + (p[1] - q[1]) * (p[1] - q[1])
                + (p[2] - q[2]) * (p[2] - q[2]));
}

/* Two negative (m0 m1) and two positive (p0 p1) vertices: a quadrilateral, split along its
 * shorter diagonal. */
static void tet_quad(const ism_sheet_field *sf, uint32_t m0, uint32_t m1, uint32_t p0,
                     uint32_t p1, ctri *out, int *n)
{
    xedge a = {m0, p0}, b = {m0, p1}, c = {m1, p1}, e = {m1, p0}; /* the cycle a b c e */
    double d[3], d2[3];
    lattice_diff(sf, p0, m0, d);
    lattice_diff(sf, p1, m1, d2);
    for (int k = 0; k < 3; k++)
        d[k] += d2[k];
    if (xedge_dist(sf, a, c) <= xedge_dist(sf, b, e)) {
        add_ctri(sf, a, b, c, d, out, n);
        add_ctri(sf, a, c, e, d, out, n);
    } else {
        add_ctri(sf, a, b, e, d, out, n);
        add_ctri(sf, b, c, e, d, out, n);
    }
}

static void tet_triangles(const ism_sheet_field *sf, const uint32_t v[4], ctri *out, int *n)
{
    int pos[4], np = 0, neg[4], nn = 0;
    for (int i = 0; i < 4; i++) {
        if (sf->v[v[i]].psi < 0)
            neg[nn++] = i;
        else
            pos[np++] = i;
    }
    if (np == 1)
        tet_corner(sf, v, pos[0], out, n);
    else if (nn == 1)
        tet_corner(sf, v, neg[0], out, n);
    else if (np == 2)
        tet_quad(sf, v[neg[0]], v[neg[1]], v[pos[0]], v[pos[1]], out, n);
}

/* True when ψ is usable in the cell (all directions agree) and changes sign there. */
static bool cell_candidate(const ism_sheet_field *sf, const uint32_t c[8])
{
    bool neg = false, pos = false;
    for (int i = 0; i < 8; i++) {
        const ism_sheet_vertex *v = &sf->v[c[i]];
        if (!(v->have & ISM_SF_ORIENTED) || ism_dot3(v->n, sf->v[c[0]].n) < SHEET_AGREE)
            return false;
        neg |= v->psi < 0;
        pos |= v->psi >= 0;
    }
    return neg && pos;
}

static int cell_triangles(const ism_sheet_field *sf, const uint32_t c[8], ctri *out)
{
    int n = 0;
    for (int t = 0; t < 6; t++) {
        uint32_t v[4] = {c[KUHN[t][0]], c[KUHN[t][1]], c[KUHN[t][2]], c[KUHN[t][3]]};
        tet_triangles(sf, v, out, &n);
    }
    return n;
}

/* The index of edge e's crossing, listed (not yet projected) when new; ISM_KEY_NONE when
 * out of memory. */
static uint32_t add_crossing(const ism_sheet_field *sf, ism_sheet_tris *t, xedge e)
{
    bool added;
    uint32_t i = ism_key_map_add(&t->xmap, xedge_key(sf, e), &added);
    if (i == ISM_KEY_NONE || !added)
        return i;
    if (i >= t->cap_x) {
        size_t c = t->cap_x ? 2 * t->cap_x : 1024;
        ism_sheet_crossing *x = realloc(t->x, c * sizeof *x);
        if (!x)
            return ISM_KEY_NONE;
        t->x = x;
        t->cap_x = c;
    }
    bool at_vertex = sf->v[e.b].psi == 0;
    t->x[i] = (ism_sheet_crossing){{0, 0, 0}, {0, 0, 0}, at_vertex ? e.b : e.a, e.b, false};
    return i;
}

typedef struct project_job {
    ism_sheet_field *sf;
    ism_sheet_tris *t;
    double cell;
} project_job;

static void project_task(void *ctx, size_t task, int thread)
{
    project_job *j = ctx;
    ism_sheet_field *sf = j->sf;
    if (ism_sheet_field_should_stop(sf))
        return;
    size_t end = (task + 1) * SHEET_CHUNK;
    if (end > j->t->xmap.n)
        end = j->t->xmap.n;
    for (size_t i = task * SHEET_CHUNK; i < end; i++) {
        ism_sheet_crossing *x = &j->t->x[i];
        double p0[3], n[3];
        xedge_point(sf, (xedge){x->a, x->b}, p0);
        x->ok = ism_sheet_project(sf->f, sf->ws[thread], p0, sf->v[x->a].n, j->cell, x->p, n);
        for (int k = 0; k < 3; k++)
            x->n[k] = (float)n[k];
    }
}

/* Appends triangle v (3 indices) to a growable index array of *n triangles. */
static bool push_tri(uint32_t **tri, size_t *n, size_t *cap, const uint32_t v[3])
{
    if (*n == *cap) {
        size_t c = *cap ? 2 * *cap : 1024;
        uint32_t *p = realloc(*tri, 3 * c * sizeof *p);
        if (!p)
            return false;
        *tri = p;
        *cap = c;
    }
    memcpy(*tri + 3 * (*n)++, v, 3 * sizeof *v);
    return true;
}

/* The triangles of the candidate cells on crossing indices: cell k of the kept list has
 * triangles start[k] .. start[k + 1] of tri. */
typedef struct cell_list {
    size_t *keep, *start, nkeep;
    uint32_t *tri;
    size_t ntri, cap;
} cell_list;

/* Lists the cells where ψ is usable and changes sign, with their triangles' crossings. */
static bool list_cells(const ism_sheet_field *sf, const uint32_t (*corners)[8], size_t n,
                       ism_sheet_tris *t, cell_list *cl)
{
    for (size_t i = 0; i < n; i++) {
        if (!cell_candidate(sf, corners[i]))
            continue;
        cl->start[cl->nkeep] = cl->ntri;
        cl->keep[cl->nkeep++] = i;
        ctri tris[CELL_TRIS];
        int m = cell_triangles(sf, corners[i], tris);
        for (int j = 0; j < m; j++) {
            uint32_t v[3];
            for (int k = 0; k < 3; k++)
                if ((v[k] = add_crossing(sf, t, tris[j].e[k])) == ISM_KEY_NONE)
                    return false;
            if (!push_tri(&cl->tri, &cl->ntri, &cl->cap, v))
                return false;
        }
    }
    cl->start[cl->nkeep] = cl->ntri;
    return true;
}

/* Emits the triangles of kept cell k when all its crossings landed on the sheet (*emitted
 * says whether it did). */
static bool emit_cell(const cell_list *cl, size_t k, ism_sheet_tris *t, uint8_t *emitted)
{
    const uint32_t *v = cl->tri + 3 * cl->start[k];
    size_t n = cl->start[k + 1] - cl->start[k];
    for (size_t i = 0; i < 3 * n; i++)
        if (!t->x[v[i]].ok) {
            t->cells_refused++;
            return true;
        }
    t->cells_meshed++;
    *emitted = n > 0;
    for (size_t i = 0; i < n; i++, v += 3)
        if (v[0] != v[1] && v[1] != v[2] && v[2] != v[0]
            && !push_tri(&t->tri, &t->ntris, &t->cap_tris, v))
            return false;
    return true;
}

bool ism_sheet_mesh_cells(const ism_sheet_field *sf, const uint32_t (*corners)[8], size_t n,
                          double cell, ism_sheet_tris *t, uint8_t *emitted)
{
    if (emitted)
        memset(emitted, 0, n);
    cell_list cl = {malloc((n ? n : 1) * sizeof *cl.keep), malloc((n + 1) * sizeof *cl.start),
                    0, NULL, 0, 0};
    bool ok = cl.keep && cl.start && list_cells(sf, corners, n, t, &cl);
    if (ok) {
        project_job job = {(ism_sheet_field *)sf, t, cell}; /* tasks may set sf->stopped */
        ism_parallel_for(sf->threads, (t->xmap.n + SHEET_CHUNK - 1) / SHEET_CHUNK, project_task,
                         &job);
        for (size_t i = 0; i < t->xmap.n; i++)
            t->crossings_refused += !t->x[i].ok;
    }
    uint8_t dummy;
    for (size_t k = 0; ok && k < cl.nkeep; k++)
        ok = emit_cell(&cl, k, t, emitted ? &emitted[cl.keep[k]] : &dummy);
    free(cl.keep);
    free(cl.start);
    free(cl.tri);
    return ok;
}
