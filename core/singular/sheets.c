/* sheets.c — the double-sheet stage (see sheets.h), a funnel over the finest lattice cells:
 *
 *   zero_cells    interval octree: cells whose interval of f holds 0
 *   quiet         f does not change sign at the 8 corners (else the polygoniser's)
 *   opposed       two corner gradients point apart (∇f = 2g∇g flips across g = 0; a
 *                 sign-changing surface nearby has nearly parallel gradients and stops here)
 *   jets          Hessian's dominant direction n at the corners, oriented (sheet_orient.h)
 *   sheet_mesh    ψ = ∇f·n changes sign: marching tetrahedra, crossings projected onto
 *                 f = 0; a cell whose crossings do not all land emits nothing
 *   assemble      connected sheets appended to the mesh and recorded in the locus
 *
 * Each step evaluates only the corners of the cells that passed the one before. */
#include "core/singular/sheets.h"
#include "core/singular/lattice_key.h"
#include "core/singular/sheet_assemble.h"
#include "core/singular/sheet_field.h"
#include "core/singular/sheet_mesh.h"
#include "core/singular/sheet_orient.h"
#include "core/singular/zero_cells.h"
#include "core/util/clock.h"
#include "core/util/parallel.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* Corner values of one sign smaller than this fraction of the cell's largest |f| are
 * rounding noise, not a sign change: f = g² written out as a polynomial comes out as
 * -1e-17 next to its double zero, where one cell away it is ~1e-5 at depth 9. */
#define SHEET_SIGN_NOISE 1e-9
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

/* The zero cells as corner index octets. False when out of memory or cut short (io says). */
static bool find_cells(stage *s, const ism_tape *f, int threads, ism_error *err)
{
    ism_zero_cells_params zp = {f, &s->grid, threads, s->o->max_boxes, s->o->cancel,
                                s->o->deadline_ms};
    ism_zero_cells zc;
    enum ism_zc_status st = ism_zero_cells_find(&zp, &zc);
    s->io->boxes_visited += zc.visited;
    s->io->evals_interval += zc.visited;
    bool ok = st == ISM_ZC_OK;
    if (st == ISM_ZC_NO_MEMORY)
        ism_error_set(err, "double sheets: out of memory");
    else if (!ok)
        set_incomplete(s->io, st == ISM_ZC_BUDGET      ? "candidate cell budget exceeded"
                              : st == ISM_ZC_CANCELLED ? "cancelled"
                                                       : "deadline passed");
    if (ok && !(s->corners = malloc((zc.n ? zc.n : 1) * sizeof *s->corners))) {
        ok = false;
        ism_error_set(err, "double sheets: out of memory");
    }
    for (size_t i = 0; ok && i < zc.n; i++)
        for (int c = 0; ok && c < 8; c++) {
            uint64_t key = ism_lkey_step(zc.cells[i], c & 1, (c >> 1) & 1, (c >> 2) & 1);
            if ((s->corners[i][c] = ism_sheet_field_vertex(&s->sf, key)) == ISM_KEY_NONE) {
                ok = false;
                ism_error_set(err, "double sheets: out of memory");
            }
        }
    s->ncells = ok ? zc.n : 0;
    free(zc.cells);
    return ok;
}

static bool quiet(const ism_sheet_field *sf, const uint32_t c[8])
{
    double lo = INFINITY, hi = -INFINITY, big = 0;
    for (int i = 0; i < 8; i++) {
        double f = sf->v[c[i]].f;
        lo = fmin(lo, f);
        hi = fmax(hi, f);
        big = fmax(big, fabs(f));
    }
    return !(lo < -SHEET_SIGN_NOISE * big && hi > SHEET_SIGN_NOISE * big);
}

static bool opposed(const ism_sheet_field *sf, const uint32_t c[8])
{
    for (int i = 0; i < 8; i++)
        for (int j = i + 1; j < 8; j++) {
            const double *a = sf->v[c[i]].g, *b = sf->v[c[j]].g;
            if (a[0] * b[0] + a[1] * b[1] + a[2] * b[2] <= 0)
                return true;
        }
    return false;
}

/* Makes the cells' corners know `what`, then keeps the cells that pass `keep`. */
static bool narrow(stage *s, int what, bool (*keep)(const ism_sheet_field *, const uint32_t *))
{
    if (!ism_sheet_field_need(&s->sf, &s->corners[0][0], 8 * s->ncells, what))
        return false;
    size_t m = 0;
    for (size_t i = 0; i < s->ncells; i++)
        if (keep(&s->sf, s->corners[i]))
            memcpy(s->corners[m++], s->corners[i], sizeof s->corners[i]);
    s->ncells = m;
    return true;
}

static double cell_diagonal(const ism_grid *g)
{
    return sqrt(g->step[0] * g->step[0] + g->step[1] * g->step[1] + g->step[2] * g->step[2]);
}

/* The funnel after the cell search; false only when out of memory. */
static bool mesh_sheets(stage *s, ism_mesh *mesh)
{
    if (!narrow(s, ISM_SF_F, quiet))
        return false;
    if (interrupted(s))
        return true;
    if (!narrow(s, ISM_SF_GRAD, opposed))
        return false;
    if (interrupted(s))
        return true;
    if (!ism_sheet_field_need(&s->sf, &s->corners[0][0], 8 * s->ncells, ISM_SF_JET)
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
    ism_grid_init(&s.grid, o->box, o->max_depth);
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
