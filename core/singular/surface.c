/* surface.c — the phases of one surface in order (see surface.h). Each phase is its own
 * module; this file only sequences them and times them. */
#include "core/singular/surface.h"
#include "core/util/clock.h"

#include <string.h>

void ism_locus_options_from_poly(const ism_poly_options *po, ism_locus_options *lo)
{
    ism_locus_options_default(lo);
    memcpy(lo->box, po->box, sizeof lo->box);
    lo->max_depth = po->max_depth;
    lo->threads = po->threads;
    lo->cancel = po->cancel;
}

enum ism_poly_status ism_mesh_surface(const ism_tape *f, const ism_poly_options *po,
                                      ism_mesh *mesh, ism_locus *locus, ism_poly_stats *ps,
                                      ism_surface_times *times, ism_error *err)
{
    memset(times, 0, sizeof *times);
    ism_locus_options lo;
    ism_locus_options_from_poly(po, &lo);
    (void)locus;
    double t0 = ism_now_ms();
    enum ism_poly_status st = ism_polygonise(f, po, mesh, ps, err);
    times->polygonise_ms = ism_now_ms() - t0;
    return st;
}
