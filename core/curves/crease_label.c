/* crease_label.c — labelling the vertices with f's branch (crease_label.h). Shortening f's
 * tape over one vertex costs an interval pass over the whole tape (a sixth of the gyroid
 * ball's crease stage at depth 7, for every one of its 47,074 vertices). The vertices are
 * binned in a grid of cells a few edges wide; the first time a vertex of a cell is labelled,
 * the tape is shortened over the cell's vertices' bounding box, and when that decides every
 * min/max (the box lies off the creases, as most do) all the cell's vertices take its
 * branch; in the cells the creases cross each vertex is labelled alone. A box's decision
 * holds at each point inside it (its intervals hold the point's), so the labels are the
 * point-wise ones, and visiting the vertices in order keeps the branches' numbering. */
#include "core/curves/crease_label.h"
#include <math.h>
#include <stdlib.h>
#include "core/util/vec3.h"

/* A cell's side in mean edge lengths: ~16-25 surface vertices a cell, where a box of that
 * size is still decided away from the creases. */
#define LABEL_CELL_EDGES 4.0
/* At most this many cells (the side grows until the grid fits). */
#define LABEL_MAX_CELLS (1u << 21)
/* A cell's state before its box is tried, and after a box that decides nothing. */
#define CELL_UNTRIED (ISM_BRANCH_NONE - 1)
#define CELL_MIXED ISM_BRANCH_NONE

typedef struct label_grid {
    double org[3], inv;
    int dim[3];
    size_t ncell;
} label_grid;

/* The grid over the vertices' bounds, its side LABEL_CELL_EDGES mean edges. False when the
 * mesh has no extent or no triangles to measure. */
static bool grid_init(const ism_mesh *m, label_grid *g)
{
    double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
    for (size_t v = 0; v < m->nverts; v++)
        for (int a = 0; a < 3; a++) {
            lo[a] = fmin(lo[a], m->pos[3 * v + a]);
            hi[a] = fmax(hi[a], m->pos[3 * v + a]);
        }
    double len = 0;
    for (size_t t = 0; t < m->ntris; t++)
        for (int i = 0; i < 3; i++)
            len += ism_dist3(m->pos + 3 * (size_t)m->tri[3 * t + i],
                             m->pos + 3 * (size_t)m->tri[3 * t + (i + 1) % 3]);
    double side = LABEL_CELL_EDGES * len / (3.0 * (double)(m->ntris ? m->ntris : 1));
    if (!(side > 0) || !isfinite(side) || !isfinite(hi[0] - lo[0]))
        return false;
    for (;; side *= 1.25) {
        double cells = 1;
        for (int a = 0; a < 3; a++) {
            g->dim[a] = (int)fmin(fmax(1, ceil((hi[a] - lo[a]) / side)), LABEL_MAX_CELLS);
            cells *= g->dim[a];
        }
        if (cells <= LABEL_MAX_CELLS)
            break;
    }
    for (int a = 0; a < 3; a++)
        g->org[a] = lo[a];
    g->inv = 1 / side;
    g->ncell = (size_t)g->dim[0] * (size_t)g->dim[1] * (size_t)g->dim[2];
    return true;
}

static size_t cell_of(const label_grid *g, const double p[3])
{
    size_t at = 0;
    for (int a = 2; a >= 0; a--) {
        double x = floor((p[a] - g->org[a]) * g->inv);
        int i = !(x > 0) ? 0 : x >= g->dim[a] - 1 ? g->dim[a] - 1 : (int)x;
        at = at * (size_t)g->dim[a] + (size_t)i;
    }
    return at;
}

bool cut_crease_label(ism_branches *b, const ism_mesh *m, uint32_t *label)
{
    label_grid g;
    if (!grid_init(m, &g)) { /* no cells: one by one */
        for (size_t v = 0; v < m->nverts; v++)
            if (!ism_branches_at(b, m->pos + 3 * v, &label[v]))
                return false;
        return true;
    }
    double (*box)[6] = malloc(g.ncell * sizeof *box);
    uint32_t *state = malloc(g.ncell * sizeof *state), *cell = malloc((m->nverts + 1) *
                                                                       sizeof *cell);
    bool ok = box && state && cell;
    for (size_t c = 0; ok && c < g.ncell; c++) {
        state[c] = CELL_UNTRIED;
        for (int a = 0; a < 3; a++) {
            box[c][a] = INFINITY;
            box[c][a + 3] = -INFINITY;
        }
    }
    for (size_t v = 0; ok && v < m->nverts; v++) {
        const double *p = m->pos + 3 * v;
        cell[v] = (uint32_t)cell_of(&g, p);
        for (int a = 0; a < 3; a++) {
            box[cell[v]][a] = fmin(box[cell[v]][a], p[a]);
            box[cell[v]][a + 3] = fmax(box[cell[v]][a + 3], p[a]);
        }
    }
    for (size_t v = 0; ok && v < m->nverts; v++) {
        uint32_t *st = &state[cell[v]];
        if (*st == CELL_UNTRIED)
            ok = ism_branches_in_box(b, box[cell[v]], box[cell[v]] + 3, st);
        if (ok && *st != CELL_MIXED)
            label[v] = *st;
        else if (ok)
            ok = ism_branches_at(b, m->pos + 3 * v, &label[v]);
    }
    free(box);
    free(state);
    free(cell);
    return ok;
}
