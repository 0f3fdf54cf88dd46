/* cut_cells.c — the cut's grid of triangle cells (cut_cells.h): built from the mesh, kept
 * up to date as the cut splits and adds triangles and moves vertices, and asked per function
 * for the triangles and vertices near its curve. */
#include "core/curves/cut_internal.h"
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include "core/util/bits.h"
#include "core/util/grow.h"
#include "core/util/vec3.h"

/* Triangles per cell at the start (the cell side is √(this × the mean triangle area)): a
 * curve crosses few cells, and a cell's interval test costs about as much as evaluating g
 * at a handful of vertices. */
#define CELL_TRIS 32.0
/* At most this many grid cells per triangle (a thin, long mesh box) and this many at all. */
#define CELL_PER_TRI 4
#define CELL_MAX (1u << 22)
/* Cells per block side: g's interval is tried on a block's bounds before its cells'. */
#define CELL_BLOCK 4
/* The grid is built afresh when the mesh has this many times the triangles it was built
 * for (each cut adds triangles along its curve, and a later curve crossing them would list
 * ever fuller cells). At 2 the benchmark's 25,008 → 291,526 triangles were placed anew three
 * times (8% of its cut); at 4 once, the cut and arrangement's CPU ~8% less over 6
 * alternating runs (least 1213 → 948 ms at load ~30). */
#define CELL_REBUILD_GROWTH 4.0
/* The interval of g over a cell is widened by this × its magnitude (plus the smallest
 * normal double) before 0 is ruled out: the vertex values are computed in rounded double
 * arithmetic (an error of ~1e-16 × g's largest term), and a vertex whose sign came out
 * against its cell's would crack the cut between a split triangle and a skipped one. The
 * interval spans at least |∇g| × the cell side, so this holds while g's terms stay below
 * 1e7 × that. */
#define CELL_WIDEN 1e-9
/* Rings of cells listed round the crossed ones: the stars of the crossed triangles' corners
 * (the tangency seeds' links, their longest edges). */
#define CELL_RINGS 1

static void free_grid(cut_cells *c)
{
    for (size_t i = 0; i < c->ncell; i++)
        free(c->cell[i].tri);
    for (size_t i = 0; i < c->nblock; i++)
        free(c->block[i].cells);
    free(c->cell);
    free(c->block);
    c->cell = NULL;
    c->block = NULL;
    c->ncell = c->nblock = 0;
}

void cut_cells_free(cut_cells *c)
{
    free_grid(c);
    free(c->tcell);
    free(c->tris);
    free(c->ring_tris);
    free(c->verts);
    free(c->vstamp);
    free(c->list);
    free(c->bits);
    memset(c, 0, sizeof *c);
}

static size_t cell_index(const cut_cells *c, const int i[3])
{
    return ((size_t)i[2] * (size_t)c->dim[1] + (size_t)i[1]) * (size_t)c->dim[0] + (size_t)i[0];
}

/* The grid coordinates of the cell holding p (clamped to the grid). */
static void cell_of(const cut_cells *c, const double p[3], int i[3])
{
    for (int a = 0; a < 3; a++) {
        double x = floor((p[a] - c->org[a]) * c->inv_h);
        i[a] = !(x > 0) ? 0 : x >= c->dim[a] - 1 ? c->dim[a] - 1 : (int)x;
    }
}

/* The reach of cell ci's bounds past its grid box, in cells, into c->over. */
static void note_over(cut_cells *c, size_t ci)
{
    const cut_cell *cl = &c->cell[ci];
    size_t i[3] = {ci % (size_t)c->dim[0], ci / (size_t)c->dim[0] % (size_t)c->dim[1],
                   ci / ((size_t)c->dim[0] * (size_t)c->dim[1])};
    for (int a = 0; a < 3; a++) {
        double lo = c->org[a] + (double)i[a] * c->h;
        double out = lo - cl->box[a] > cl->box[a + 3] - (lo + c->h) ? lo - cl->box[a]
                                                                    : cl->box[a + 3] - (lo + c->h);
        int over = out > 0 ? (int)ceil(out / c->h) : 0;
        c->over = over > c->over ? over : c->over;
    }
}

/* Widens box (lo xyz, hi xyz) to hold p; whether it grew. */
static bool box_hold(double box[6], const double p[3])
{
    bool grew = false;
    for (int a = 0; a < 3; a++) {
        if (p[a] < box[a]) {
            box[a] = p[a];
            grew = true;
        }
        if (p[a] > box[a + 3]) {
            box[a + 3] = p[a];
            grew = true;
        }
    }
    return grew;
}

/* The block (CELL_BLOCK³ cells) holding cell ci. */
static size_t block_of(const cut_cells *c, size_t ci)
{
    size_t i = ci % (size_t)c->dim[0], j = ci / (size_t)c->dim[0] % (size_t)c->dim[1];
    size_t k = ci / ((size_t)c->dim[0] * (size_t)c->dim[1]);
    return ((k / CELL_BLOCK) * (size_t)c->bdim[1] + j / CELL_BLOCK) * (size_t)c->bdim[0] +
           i / CELL_BLOCK;
}

/* Widens cell ci's bounds (and its block's) to hold p; the reach past the grid boxes is
 * noted at once once the grid is built (while it is built, after). */
static void cell_hold(cut_cells *c, size_t ci, const double p[3])
{
    if (box_hold(c->cell[ci].box, p)) {
        if (c->valid)
            note_over(c, ci);
        box_hold(c->block[c->cell[ci].block].box, p);
    }
}

/* Cell ci gets its first triangle: empty bounds, listed in its block. */
static bool cell_opened(cut_cells *c, size_t ci)
{
    c->cell[ci].block = (uint32_t)block_of(c, ci);
    cut_block *b = &c->block[c->cell[ci].block];
    if (!ism_grow((void **)&b->cells, &b->cap, b->n + 1, sizeof *b->cells, 8))
        return false;
    b->cells[b->n++] = (uint32_t)ci;
    for (int a = 0; a < 3; a++) {
        c->cell[ci].box[a] = INFINITY;
        c->cell[ci].box[a + 3] = -INFINITY;
    }
    return true;
}

/* Places triangle t in the cell of its centroid. False when out of memory. */
static bool place(cut_state *s, size_t t)
{
    cut_cells *c = &s->cells;
    const uint32_t *tv = s->m->tri + 3 * t;
    double cen[3] = {0, 0, 0};
    for (int k = 0; k < 3; k++)
        for (int a = 0; a < 3; a++)
            cen[a] += s->m->pos[3 * (size_t)tv[k] + a] / 3;
    int i[3];
    cell_of(c, cen, i);
    size_t ci = cell_index(c, i);
    cut_cell *cl = &c->cell[ci];
    if (!ism_grow((void **)&cl->tri, &cl->cap, cl->n + 1, sizeof *cl->tri, 8) ||
        !ism_grow((void **)&c->tcell, &c->cap_tcell, t + 1, sizeof *c->tcell, CUT_FIRST))
        return false;
    if (cl->n == 0 && !cell_opened(c, ci))
        return false;
    cl->tri[cl->n++] = (uint32_t)t;
    c->tcell[t] = (uint32_t)ci;
    for (int k = 0; k < 3; k++)
        cell_hold(c, ci, s->m->pos + 3 * (size_t)tv[k]);
    return true;
}

bool cut_cells_place(cut_state *s, size_t t)
{
    return !s->cells.valid || place(s, t);
}

void cut_cells_grow(cut_state *s, size_t t)
{
    cut_cells *c = &s->cells;
    if (!c->valid)
        return;
    for (int k = 0; k < 3; k++)
        cell_hold(c, c->tcell[t], s->m->pos + 3 * (size_t)s->m->tri[3 * t + k]);
}

void cut_cells_moved(cut_state *s, const double p[3], double r)
{
    cut_cells *c = &s->cells;
    if (!c->valid)
        return;
    double lo[3] = {p[0] - r, p[1] - r, p[2] - r}, hi[3] = {p[0] + r, p[1] + r, p[2] + r};
    int a[3], b[3], i[3];
    cell_of(c, lo, a);
    cell_of(c, hi, b);
    for (i[2] = a[2]; i[2] <= b[2]; i[2]++)
        for (i[1] = a[1]; i[1] <= b[1]; i[1]++)
            for (i[0] = a[0]; i[0] <= b[0]; i[0]++) {
                size_t ci = cell_index(c, i);
                if (c->cell[ci].n)
                    cell_hold(c, ci, p);
            }
}

/* The grid: bounds of the triangles' corners, the cell side from their mean area. */
static bool grid_size(cut_state *s, double lo[3], double hi[3])
{
    const ism_mesh *m = s->m;
    cut_cells *c = &s->cells;
    double area = 0;
    for (int a = 0; a < 3; a++) {
        lo[a] = INFINITY;
        hi[a] = -INFINITY;
    }
    for (size_t t = 0; t < m->ntris; t++) {
        const double *q[3];
        for (int k = 0; k < 3; k++) {
            q[k] = m->pos + 3 * (size_t)m->tri[3 * t + k];
            for (int a = 0; a < 3; a++) {
                lo[a] = q[k][a] < lo[a] ? q[k][a] : lo[a];
                hi[a] = q[k][a] > hi[a] ? q[k][a] : hi[a];
            }
        }
        area += ism_tri_area3(q[0], q[1], q[2]);
    }
    double ext = fmax(hi[0] - lo[0], fmax(hi[1] - lo[1], hi[2] - lo[2]));
    if (!isfinite(ext))
        return false;
    c->h = sqrt(CELL_TRIS * area / (double)(m->ntris ? m->ntris : 1));
    if (!(c->h > 0))
        c->h = ext > 0 ? ext : 1;
    for (;;) {
        double cells = 1;
        for (int a = 0; a < 3; a++) {
            c->dim[a] = (int)fmax(1, ceil((hi[a] - lo[a]) / c->h));
            cells *= c->dim[a];
        }
        if (cells <= CELL_MAX && cells <= CELL_PER_TRI * (double)m->ntris + 64)
            break;
        c->h *= 1.25;
    }
    memcpy(c->org, lo, sizeof c->org);
    c->inv_h = 1 / c->h;
    c->ncell = (size_t)c->dim[0] * (size_t)c->dim[1] * (size_t)c->dim[2];
    return true;
}

bool cut_cells_build(cut_state *s)
{
    cut_cells *c = &s->cells;
    free_grid(c);
    c->over = 0;
    c->valid = false;
    double lo[3], hi[3];
    if (!s->m->ntris || !grid_size(s, lo, hi))
        return true; /* nothing to index: every function lists the whole (empty) mesh */
    for (int a = 0; a < 3; a++)
        c->bdim[a] = (c->dim[a] + CELL_BLOCK - 1) / CELL_BLOCK;
    c->nblock = (size_t)c->bdim[0] * (size_t)c->bdim[1] * (size_t)c->bdim[2];
    c->cell = calloc(c->ncell, sizeof *c->cell);
    c->block = calloc(c->nblock, sizeof *c->block);
    if (!c->cell || !c->block)
        return false; /* (valid stays false: the partial grid is freed with the rest) */
    for (size_t b = 0; b < c->nblock; b++)
        for (int a = 0; a < 3; a++) {
            c->block[b].box[a] = INFINITY;
            c->block[b].box[a + 3] = -INFINITY;
        }
    c->built_tris = s->m->ntris;
    for (size_t t = 0; t < s->m->ntris; t++)
        if (!place(s, t))
            return false;
    for (size_t ci = 0; ci < c->ncell; ci++)
        if (c->cell[ci].n)
            note_over(c, ci);
    c->valid = true;
    return true;
}

bool cut_cells_ready(cut_state *s)
{
    const cut_cells *c = &s->cells;
    if (c->valid && (double)s->m->ntris <= CELL_REBUILD_GROWTH * (double)c->built_tris)
        return true;
    return cut_cells_build(s);
}

/* An interval holding g_k over box, widened (CELL_WIDEN); false when g_k has no interval
 * form (a silhouette's ∇f·d, a crease's branches): every cell counts as crossed. */
static bool g_bounds(cut_state *s, size_t k, const double box[6], double *glo, double *ghi)
{
    const ism_cut_fn *fn = &s->ev->fns[k];
    if (fn->kind == ISM_CUT_SILHOUETTE || fn->kind == ISM_CUT_CREASE)
        return false;
    double lo = -fn->c, hi = -fn->c;
    for (int a = 0; a < 3; a++) {
        double u = fn->n[a] * box[a], v = fn->n[a] * box[a + 3];
        lo += fmin(u, v);
        hi += fmax(u, v);
    }
    if (fn->tape) {
        ism_interval x = {box[0], box[3]}, y = {box[1], box[4]}, z = {box[2], box[5]};
        ism_interval g = ism_eval_interval(fn->tape, s->ev->gws[k], x, y, z);
        lo += g.lo;
        hi += g.hi;
    }
    double w = CELL_WIDEN * (fabs(lo) + fabs(hi)) + 2.2250738585072014e-308;
    *glo = lo - w;
    *ghi = hi + w;
    return !isnan(lo) && !isnan(hi);
}

static bool boxes_meet(const double a[6], const double b[6])
{
    for (int i = 0; i < 3; i++)
        if (a[i] > b[i + 3] || b[i] > a[i + 3])
            return false;
    return true;
}

/* Marks ring `ring`: the cells whose bounds meet those of the listed cells [from, end). */
static bool mark_ring(cut_cells *c, size_t from, size_t end, uint8_t ring)
{
    for (size_t li = from; li < end; li++) {
        const cut_cell *a = &c->cell[c->list[li]];
        int lo[3], hi[3], i[3];
        cell_of(c, a->box, lo);
        cell_of(c, a->box + 3, hi);
        for (int d = 0; d < 3; d++) {
            lo[d] = lo[d] - c->over < 0 ? 0 : lo[d] - c->over;
            hi[d] = hi[d] + c->over >= c->dim[d] ? c->dim[d] - 1 : hi[d] + c->over;
        }
        for (i[2] = lo[2]; i[2] <= hi[2]; i[2]++)
            for (i[1] = lo[1]; i[1] <= hi[1]; i[1]++)
                for (i[0] = lo[0]; i[0] <= hi[0]; i[0]++) {
                    size_t ci = cell_index(c, i);
                    cut_cell *b = &c->cell[ci];
                    if (!b->n || b->ring || !boxes_meet(a->box, b->box))
                        continue;
                    if (!ism_grow((void **)&c->list, &c->cap_list, c->nlist + 1,
                                  sizeof *c->list, CUT_FIRST))
                        return false;
                    b->ring = ring;
                    c->list[c->nlist++] = (uint32_t)ci;
                }
    }
    return true;
}

/* The cells crossed by g_k = 0 (all with triangles when g_k has no bounds) and the rings
 * round them into c->list. */
static bool list_cells(cut_state *s, size_t k)
{
    cut_cells *c = &s->cells;
    c->nlist = 0;
    for (size_t bi = 0; bi < c->nblock; bi++) {
        const cut_block *b = &c->block[bi];
        double lo, hi;
        if (!b->n || (g_bounds(s, k, b->box, &lo, &hi) && (lo > 0 || hi < 0)))
            continue;
        for (size_t j = 0; j < b->n; j++) {
            cut_cell *cl = &c->cell[b->cells[j]];
            if (b->n > 1 && g_bounds(s, k, cl->box, &lo, &hi) && (lo > 0 || hi < 0))
                continue;
            if (!ism_grow((void **)&c->list, &c->cap_list, c->nlist + 1, sizeof *c->list,
                          CUT_FIRST))
                return false;
            cl->ring = 1;
            c->list[c->nlist++] = b->cells[j];
        }
    }
    c->ncrossed = c->nlist;
    size_t from = 0;
    for (uint8_t ring = 2; ring <= CELL_RINGS + 1; ring++) {
        size_t end = c->nlist;
        if (!mark_ring(c, from, end, ring))
            return false;
        from = end;
    }
    for (size_t li = 0; li < c->nlist; li++)
        c->cell[c->list[li]].ring = 0;
    return true;
}

/* The triangles of the listed cells [from, end) into *out, ascending (the order a pass over
 * the whole mesh would meet them in): marked in a bitmap, read back word by word. */
static bool cells_triangles(cut_state *s, size_t from, size_t end, uint32_t **out, size_t *n,
                            size_t *cap)
{
    cut_cells *c = &s->cells;
    size_t words = (s->m->ntris + 63) / 64, total = 0;
    *n = 0;
    if (!ism_grow((void **)&c->bits, &c->cap_bits, words + 1, sizeof *c->bits, CUT_FIRST))
        return false;
    memset(c->bits, 0, (words + 1) * sizeof *c->bits);
    for (size_t li = from; li < end; li++) {
        const cut_cell *cl = &c->cell[c->list[li]];
        for (size_t i = 0; i < cl->n; i++)
            ism_bit_set(c->bits, cl->tri[i]);
        total += cl->n;
    }
    if (!ism_grow((void **)out, cap, total + 1, sizeof **out, CUT_FIRST))
        return false;
    ISM_BITS_EACH(c->bits, words, t)
        (*out)[(*n)++] = (uint32_t)t;
    return true;
}

/* The crossed cells' triangles into c->tris, the ring's into c->ring_tris (every triangle
 * in c->tris while the grid is not valid). */
static bool list_triangles(cut_state *s)
{
    cut_cells *c = &s->cells;
    size_t nt = s->m->ntris;
    c->ntris = c->nring = 0;
    if (!c->valid) {
        if (!ism_grow((void **)&c->tris, &c->cap_tris, nt + 1, sizeof *c->tris, CUT_FIRST))
            return false;
        for (size_t t = 0; t < nt; t++)
            c->tris[c->ntris++] = (uint32_t)t;
        return true;
    }
    return cells_triangles(s, 0, c->ncrossed, &c->tris, &c->ntris, &c->cap_tris) &&
           cells_triangles(s, c->ncrossed, c->nlist, &c->ring_tris, &c->nring, &c->cap_ring);
}

static bool grow_stamps(cut_cells *c, size_t nverts)
{
    size_t old = c->cap_vstamp;
    if (!ism_grow((void **)&c->vstamp, &c->cap_vstamp, nverts + 1, sizeof *c->vstamp,
                  CUT_FIRST))
        return false;
    memset(c->vstamp + old, 0, (c->cap_vstamp - old) * sizeof *c->vstamp);
    return true;
}

/* Number of vertices whose g is gathered for one batch evaluation. */
#define CELL_BATCH 256

/* g_k at the vertices in c->verts from the from-th on, into gv and sg. */
static bool evaluate(cut_state *s, size_t k, size_t from)
{
    cut_cells *c = &s->cells;
    double pos[3 * CELL_BATCH], val[CELL_BATCH];
    for (size_t i0 = from; i0 < c->nverts; i0 += CELL_BATCH) {
        size_t n = c->nverts - i0 < CELL_BATCH ? c->nverts - i0 : CELL_BATCH;
        for (size_t i = 0; i < n; i++)
            memcpy(pos + 3 * i, s->m->pos + 3 * (size_t)c->verts[i0 + i], 3 * sizeof *pos);
        if (!ism_cut_g_batch(s->ev, k, pos, n, val))
            return false;
        for (size_t i = 0; i < n; i++) {
            uint32_t v = c->verts[i0 + i];
            s->gv[v] = val[i];
            s->sg[v] = (signed char)((val[i] > 0) - (val[i] < 0));
        }
    }
    return true;
}

/* Lists vertex v in c->verts unless g_k is known there (stamp k + 1). */
static bool want_value(cut_cells *c, uint32_t v, uint32_t stamp)
{
    if (c->vstamp[v] == stamp)
        return true;
    if (!ism_grow((void **)&c->verts, &c->cap_verts, c->nverts + 1, sizeof *c->verts,
                  CUT_FIRST))
        return false;
    c->vstamp[v] = stamp;
    c->verts[c->nverts++] = v;
    return true;
}

bool cut_cells_select(cut_state *s, size_t k)
{
    cut_cells *c = &s->cells;
    const ism_mesh *m = s->m;
    if ((c->valid && !list_cells(s, k)) || !list_triangles(s) || !grow_stamps(c, m->nverts))
        return false;
    uint32_t stamp = (uint32_t)k + 1;
    c->nverts = 0;
    for (size_t i = 0; i < 3 * c->ntris; i++)
        if (!want_value(c, m->tri[3 * (size_t)c->tris[i / 3] + i % 3], stamp))
            return false;
    return evaluate(s, k, 0);
}

bool cut_cells_near_values(cut_state *s)
{
    cut_cells *c = &s->cells;
    size_t from = c->nverts;
    if (!grow_stamps(c, s->m->nverts))
        return false;
    for (size_t i = 0; i < s->n_near; i++)
        if (!want_value(c, s->near_list[i], (uint32_t)s->fn + 1))
            return false;
    return evaluate(s, s->fn, from);
}

signed char cut_sign_of(cut_state *s, uint32_t v)
{
    cut_cells *c = &s->cells;
    if (!grow_stamps(c, s->m->nverts) || c->vstamp[v] != (uint32_t)s->fn + 1) {
        double g = ism_cut_g(s->ev, s->fn, s->m->pos + 3 * (size_t)v, NULL);
        s->gv[v] = g;
        s->sg[v] = (signed char)((g > 0) - (g < 0));
        if (v < c->cap_vstamp)
            c->vstamp[v] = (uint32_t)s->fn + 1;
    }
    return s->sg[v];
}

void cut_on_curve_now(cut_state *s, uint32_t v)
{
    s->gv[v] = 0;
    s->sg[v] = 0;
    if (grow_stamps(&s->cells, s->m->nverts))
        s->cells.vstamp[v] = (uint32_t)s->fn + 1;
}
