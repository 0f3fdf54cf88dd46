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

/* Threads one request may use (as the polygoniser). */
#define SHEET_MAX_THREADS 64

typedef struct stage {
    const ism_locus_options *o;
    ism_locus *io;
    ism_grid grid;
    ism_sheet_field sf;
    uint32_t (*corners)[8];   /* of the cells still in the funnel */
    size_t ncells;
} stage;

static void set_incomplete(ism_locus *io, const char *why)
{
    if (io->incomplete)
        return;
    io->incomplete = true;
    snprintf(io->incomplete_why, sizeof io->incomplete_why, "double sheets: %s", why);
}

/* True when the stage must stop (cancel or deadline); says so in io. */
static bool interrupted(stage *s)
{
    if (s->o->cancel && *s->o->cancel) {
        set_incomplete(s->io, "cancelled");
        return true;
    }
    if (s->o->deadline_ms > 0 && ism_now_ms() > s->o->deadline_ms) {
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

/* The candidate cells as corner index octets. False when out of memory or cut short (io
 * says which). */
static bool find_cells(stage *s, const ism_tape *f, int threads, ism_error *err)
{
    ism_sheet_cells_params cp = {f, &s->grid, threads, s->o->max_boxes, s->o->cancel,
                                 s->o->deadline_ms};
    ism_sheet_cells sc;
    enum ism_sc_status st = ism_sheet_cells_find(&cp, &sc);
    s->io->boxes_visited += sc.intervals;
    s->io->evals_interval += sc.intervals;
    bool ok = st == ISM_SC_OK;
    if (st == ISM_SC_NO_MEMORY)
        ism_error_set(err, "double sheets: out of memory");
    else if (!ok)
        set_incomplete(s->io, st == ISM_SC_BUDGET      ? "candidate cell budget exceeded"
                              : st == ISM_SC_CANCELLED ? "cancelled"
                                                       : "deadline passed");
    if (ok && !(s->corners = malloc((sc.n ? sc.n : 1) * sizeof *s->corners))) {
        ok = false;
        ism_error_set(err, "double sheets: out of memory");
    }
    for (size_t i = 0; ok && i < sc.n; i++)
        for (int c = 0; ok && c < 8; c++) {
            uint64_t key = ism_lkey_step(sc.cells[i], c & 1, (c >> 1) & 1, (c >> 2) & 1);
            if ((s->corners[i][c] = ism_sheet_field_vertex(&s->sf, key)) == ISM_KEY_NONE) {
                ok = false;
                ism_error_set(err, "double sheets: out of memory");
            }
        }
    s->ncells = ok ? sc.n : 0;
    free(sc.cells);
    return ok;
}

static double cell_diagonal(const ism_grid *g)
{
    return sqrt(g->step[0] * g->step[0] + g->step[1] * g->step[1] + g->step[2] * g->step[2]);
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
    bool ok = ism_sheet_mesh_cells(&s->sf, (const uint32_t(*)[8])s->corners, s->ncells,
                                   cell_diagonal(&s->grid), &t);
    if (ok && !interrupted(s))
        ok = ism_sheet_assemble(&t, mesh, s->io);
    ism_sheet_tris_free(&t);
    return ok;
}

bool ism_sing_double_sheets(const ism_tape *f, const ism_locus_options *o, ism_locus *io,
                            ism_mesh *mesh, ism_error *err)
{
    if (!check_options(o, err))
        return false;
    double t0 = ism_now_ms();
    int threads = o->threads > 0 ? o->threads : ism_cpu_count();
    if (threads > SHEET_MAX_THREADS)
        threads = SHEET_MAX_THREADS;
    stage s = {.o = o, .io = io};
    /* one finest cell per box is no lattice to contour on: depth 0 runs as depth 1 */
    ism_grid_init(&s.grid, o->box, o->max_depth < 1 ? 1 : o->max_depth);
    if (!ism_sheet_field_init(&s.sf, f, &s.grid, threads))
        return ism_error_set(err, "double sheets: out of memory");
    bool ok = true;
    if (find_cells(&s, f, threads, err))
        ok = mesh_sheets(&s, mesh);
    else
        ok = io->incomplete && !s.corners; /* cut short: fine; out of memory: not */
    if (!ok && !err->message[0])
        ism_error_set(err, "double sheets: out of memory");
    io->evals_jet += s.sf.evals_jet;
    io->time_ms += ism_now_ms() - t0;
    free(s.corners);
    ism_sheet_field_free(&s.sf);
    return ok;
}
