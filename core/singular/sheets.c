/* sheets.c — the double-sheet stage (see sheets.h), a funnel over the finest lattice cells:
 *
 *   sheet_cells     interval octree, then per block of 8 cells: interval holds 0, f without
 *                   a sign change at the corners, two corner gradients apart
 *   sheet_field     the Hessian's dominant direction n at the candidates' corners,
 *   sheet_orient    oriented consistently between neighbours; ψ = (∇f·n)/λ
 *   sheet_mesh      marching tetrahedra on ψ, crossings projected onto f = 0; a cell whose
 *                   crossings do not all land emits nothing
 *   sheet_assemble  connected sheets appended to the mesh and recorded in the locus
 *
 * Each step evaluates only what the cells that passed the one before need. */
#include "core/singular/sheets.h"
#include "core/singular/lattice_key.h"
#include "core/singular/sheet_assemble.h"
#include "core/singular/sheet_field.h"
#include "core/singular/sheet_mesh.h"
#include "core/singular/sheet_orient.h"
#include "core/singular/sheet_cells.h"
#include "core/util/clock.h"
#include "core/util/parallel.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* A search box is a finest cell of the lattice when its corners are lattice points to
 * within this fraction of a step (both are computed as lo + i·step, so they agree to a few
 * ulps). */
#define SHEET_BOX_MATCH 1e-9
/* Open pieces of a sheet smaller than this many cell faces (a 4 × 4 patch) are below the
 * lattice's resolution and left out: the scraps of one to a few cells that appear along a
 * crossing with a sign-changing surface (g²·h by h = 0, where the Hessian's direction turns
 * within two cells of the crossing, from ∇g toward ∇h). A closed sheet of any size, and
 * any larger piece, stays. */
#define SHEET_SCRAP_CELLS 16.0

typedef struct stage {
    const ism_locus_options *o;
    ism_locus *io;
    ism_grid grid;
    ism_sheet_field sf;
    uint64_t *cells;          /* the candidate cells' lattice keys */
    uint32_t (*corners)[8];   /* and their corners' vertex indices */
    size_t ncells;
    ism_key_map boxes;        /* finest unexplained io->boxes: cell key -> */
    uint32_t *box_index;      /* index in io->boxes */
    size_t cap_index;
} stage;

static bool push_index(stage *s, uint32_t i)
{
    if (s->boxes.n > s->cap_index) {
        size_t c = s->cap_index ? 2 * s->cap_index : 256;
        uint32_t *v = realloc(s->box_index, c * sizeof *v);
        if (!v)
            return false;
        s->box_index = v;
        s->cap_index = c;
    }
    s->box_index[s->boxes.n - 1] = i;
    return true;
}

static void set_incomplete(ism_locus *io, const char *why)
{
    if (io->incomplete)
        return;
    io->incomplete = true;
    snprintf(io->incomplete_why, sizeof io->incomplete_why, "double sheets: %s", why);
}

/* True when the stage must stop (cancel or deadline, now or seen by a task); says so in
 * io. */
static bool interrupted(stage *s)
{
    ism_sheet_field_should_stop(&s->sf);
    if (s->o->cancel && *s->o->cancel) {
        set_incomplete(s->io, "cancelled");
        return true;
    }
    if (atomic_load(&s->sf.stopped)) {
        set_incomplete(s->io, "deadline passed");
        return true;
    }
    return false;
}

static bool check_options(const ism_locus_options *o, ism_error *err)
{
    if (o->max_depth < 0 || o->max_depth > ISM_GRID_MAX_DEPTH)
        return ism_error_set(err, "max_depth must be 0..%d", ISM_GRID_MAX_DEPTH);
    for (int k = 0; k < 3; k++)
        if (!isfinite(o->box[k]) || !isfinite(o->box[k + 3]) || !(o->box[k] < o->box[k + 3]))
            return ism_error_set(err, "box must be finite with min < max on every axis");
    return true;
}

/* The finest boxes of io->boxes (an earlier search on the same lattice) not yet explained,
 * as lattice cell keys mapped to their box index. */
static bool map_boxes(stage *s)
{
    const ism_grid *g = &s->grid;
    for (size_t i = 0; i < s->io->nboxes; i++) {
        const ism_lbox *b = &s->io->boxes[i];
        int32_t v[3];
        bool cell = !(b->flags & ISM_LBOX_USED);
        for (int a = 0; cell && a < 3; a++) {
            double u = (b->lo[a] - g->lo[a]) / g->step[a];
            v[a] = (int32_t)llround(u);
            cell = v[a] >= 0 && v[a] < (1 << g->depth)
                && fabs(b->lo[a] - ism_grid_coord(g, a, v[a])) <= SHEET_BOX_MATCH * g->step[a]
                && fabs(b->hi[a] - ism_grid_coord(g, a, v[a] + 1)) <= SHEET_BOX_MATCH * g->step[a];
        }
        bool added;
        if (cell && ism_key_map_add(&s->boxes, ism_lkey(v[0], v[1], v[2]), &added) == ISM_KEY_NONE)
            return false;
        if (cell && added && !push_index(s, (uint32_t)i))
            return false;
    }
    return true;
}

enum { CELLS_OK, CELLS_CUT, CELLS_NO_MEMORY };

/* The candidate cells (from the octree, or from the mapped boxes) as corner index octets;
 * CELLS_CUT when cut short (io says why). */
static int find_cells(stage *s, const ism_tape *f, int threads, bool from_boxes)
{
    ism_sheet_cells_params cp = {f, &s->grid, threads, s->o->max_boxes, s->o->cancel,
                                 s->o->deadline_ms};
    ism_sheet_cells sc;
    enum ism_sc_status st = from_boxes
                                ? ism_sheet_cells_filter(&cp, s->boxes.keys, s->boxes.n, &sc)
                                : ism_sheet_cells_find(&cp, &sc);
    s->io->boxes_visited += sc.intervals;
    s->io->evals_interval += sc.intervals + sc.gradient_boxes;
    int r = st == ISM_SC_OK ? CELLS_OK : st == ISM_SC_NO_MEMORY ? CELLS_NO_MEMORY : CELLS_CUT;
    if (r == CELLS_CUT)
        set_incomplete(s->io, st == ISM_SC_BUDGET      ? "candidate cell budget exceeded"
                              : st == ISM_SC_CANCELLED ? "cancelled"
                                                       : "deadline passed");
    if (r == CELLS_OK && (!(s->corners = malloc((sc.n ? sc.n : 1) * sizeof *s->corners))
                          || !(s->cells = malloc((sc.n ? sc.n : 1) * sizeof *s->cells))))
        r = CELLS_NO_MEMORY;
    for (size_t i = 0; r == CELLS_OK && i < sc.n; i++) {
        s->cells[i] = sc.cells[i];
        for (int c = 0; r == CELLS_OK && c < 8; c++) {
            uint64_t key = ism_lkey_step(sc.cells[i], c & 1, (c >> 1) & 1, (c >> 2) & 1);
            if ((s->corners[i][c] = ism_sheet_field_vertex(&s->sf, key)) == ISM_KEY_NONE)
                r = CELLS_NO_MEMORY;
        }
    }
    s->ncells = r == CELLS_OK ? sc.n : 0;
    free(sc.cells);
    return r;
}

static double min_face(const ism_grid *g)
{
    double a = g->step[0] * g->step[1], b = g->step[1] * g->step[2], c = g->step[0] * g->step[2];
    return fmin(a, fmin(b, c));
}

static double cell_diagonal(const ism_grid *g)
{
    return sqrt(g->step[0] * g->step[0] + g->step[1] * g->step[1] + g->step[2] * g->step[2]);
}

/* Flags ISM_LBOX_USED on the search boxes whose cells gave sheet triangles. */
static void mark_boxes(stage *s, const uint8_t *emitted)
{
    for (size_t i = 0; i < s->ncells; i++) {
        uint32_t k = emitted[i] ? ism_key_map_find(&s->boxes, s->cells[i]) : ISM_KEY_NONE;
        if (k != ISM_KEY_NONE)
            s->io->boxes[s->box_index[k]].flags |= ISM_LBOX_USED;
    }
}

/* Jets at the candidates' corners, orientation, triangles, sheets. False only when out of
 * memory. */
static bool mesh_sheets(stage *s, ism_mesh *mesh)
{
    if (!ism_sheet_field_jets(&s->sf, &s->corners[0][0], 8 * s->ncells)
        || !ism_sheet_orient(&s->sf))
        return false;
    if (interrupted(s))
        return true;
    ism_sheet_tris t;
    ism_sheet_tris_init(&t);
    uint8_t *emitted = malloc(s->ncells ? s->ncells : 1);
    bool ok = emitted && ism_sheet_mesh_cells(&s->sf, (const uint32_t(*)[8])s->corners,
                                              s->ncells, cell_diagonal(&s->grid), &t, emitted);
    if (ok && !interrupted(s)) {
        ok = ism_sheet_assemble(&t, SHEET_SCRAP_CELLS * min_face(&s->grid), mesh, s->io);
        mark_boxes(s, emitted);
    }
    free(emitted);
    ism_sheet_tris_free(&t);
    return ok;
}

static bool run_stage(const ism_tape *f, const ism_locus_options *o, ism_locus *io,
                      ism_mesh *mesh, ism_error *err, bool from_boxes)
{
    if (!check_options(o, err))
        return false;
    double t0 = ism_now_ms();
    int threads = ism_threads_resolve(o->threads);
    stage s = {.o = o, .io = io};
    ism_key_map_init(&s.boxes);
    /* one finest cell per box is no lattice to contour on: depth 0 runs as depth 1 */
    ism_grid_init(&s.grid, o->box, o->max_depth < 1 ? 1 : o->max_depth);
    bool ok = ism_sheet_field_init(&s.sf, f, &s.grid, threads) && map_boxes(&s);
    s.sf.cancel = o->cancel;
    s.sf.deadline_ms = o->deadline_ms;
    if (ok) {
        int r = find_cells(&s, f, threads, from_boxes);
        ok = r != CELLS_NO_MEMORY && (r == CELLS_CUT || mesh_sheets(&s, mesh));
    }
    if (!ok)
        ism_error_set(err, "double sheets: out of memory");
    io->evals_jet += s.sf.evals_jet;
    io->time_ms += ism_now_ms() - t0;
    free(s.corners);
    free(s.cells);
    free(s.box_index);
    ism_key_map_free(&s.boxes);
    ism_sheet_field_free(&s.sf);
    return ok;
}

bool ism_sing_double_sheets(const ism_tape *f, const ism_locus_options *o, ism_locus *io,
                            ism_mesh *mesh, ism_error *err)
{
    return run_stage(f, o, io, mesh, err, false);
}

bool ism_sing_double_sheets_from_search(const ism_tape *f, const ism_locus_options *o,
                                        ism_locus *io, ism_mesh *mesh, ism_error *err)
{
    return run_stage(f, o, io, mesh, err, true);
}
