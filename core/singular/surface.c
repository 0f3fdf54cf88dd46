/* surface.c — the phases of one surface in order (see surface.h). Each phase is its own
 * module; this file only sequences them and times them. */
#include "core/singular/surface.h"
#include "core/singular/conform.h"
#include "core/singular/covered.h"
#include "core/singular/find.h"
#include "core/singular/sheets.h"
#include "core/util/clock.h"

#include <stdlib.h>
#include <string.h>

void ism_locus_options_from_poly(const ism_poly_options *po, ism_locus_options *lo)
{
    ism_locus_options_default(lo);
    memcpy(lo->box, po->box, sizeof lo->box);
    lo->max_depth = po->max_depth;
    lo->threads = po->threads;
    lo->cancel = po->cancel;
}

/* Share of the conformance pass's smallest ball in which the polygoniser does not chase
 * hidden pieces: the ball's rim, where the refill meets the polygoniser's mesh, must lie in
 * cells that were chased (the pass widens its cut from there, never narrows it). */
#define QUIET_SHARE 0.8

/* The balls around the locus's points where hidden pieces are not chased (see
 * ism_poly_options): malloc'd, NULL when there are none or memory ran out. */
static double (*quiet_balls(const ism_locus *l, const ism_locus_options *lo, size_t *n))[4]
{
    *n = 0;
    if (l->npoints == 0)
        return NULL;
    double (*b)[4] = malloc(l->npoints * sizeof *b);
    if (!b)
        return NULL;
    double r = QUIET_SHARE * ism_conform_min_radius(lo);
    for (size_t i = 0; i < l->npoints; i++) {
        memcpy(b[i], l->points[i].p, sizeof l->points[i].p);
        b[i][3] = r;
    }
    *n = l->npoints;
    return b;
}

enum ism_poly_status ism_mesh_surface(const ism_tape *f, const ism_poly_options *po,
                                      ism_mesh *mesh, ism_locus *locus, ism_poly_stats *ps,
                                      ism_conform_stats *cs, ism_surface_times *times,
                                      ism_error *err)
{
    memset(times, 0, sizeof *times);
    memset(cs, 0, sizeof *cs);
    if (!ism_poly_options_check(po, err))
        return ISM_POLY_BAD_OPTIONS;
    ism_locus_options lo;
    ism_locus_options_from_poly(po, &lo);
    double t0 = ism_now_ms();
    if (!ism_locus_find(f, &lo, locus, err))
        return ISM_POLY_NO_MEMORY;
    double t1 = ism_now_ms();
    ism_poly_options pq = *po;
    double (*balls)[4] = quiet_balls(locus, &lo, &pq.nquiet);
    if (locus->npoints && !balls)
        return ISM_POLY_NO_MEMORY;
    pq.quiet = (const double (*)[4])balls;
    enum ism_poly_status st = ism_polygonise(f, &pq, mesh, ps, err);
    free(balls);
    double t2 = ism_now_ms();
    times->polygonise_ms = t2 - t1;
    if (st != ISM_POLY_OK)
        return st;
    if (po->cancel && *po->cancel)
        return ISM_POLY_CANCELLED;
    /* Conform first: it may remove and renumber the polygoniser's triangles, while the
     * double sheets are appended after them and recorded as triangle ranges; they leave out
     * the boxes the polygoniser already meshed (a double sheet on a lattice plane). */
    if (!ism_conform_mesh(f, &lo, locus, mesh, cs, err) ||
        !ism_locus_mark_covered(locus, &lo, mesh) ||
        !ism_sing_double_sheets_from_search(f, &lo, locus, mesh, err) ||
        !ism_mesh_drop_loose(mesh))
        return ISM_POLY_NO_MEMORY;
    times->singular_ms = (t1 - t0) + (ism_now_ms() - t2);
    locus->time_ms = times->singular_ms;
    return ISM_POLY_OK;
}
