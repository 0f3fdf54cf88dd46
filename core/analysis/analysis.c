/* analysis.c — the analysis as one call: checks the mesh, builds the edge table, then runs
 * the passes in order (vertex classes by cones of faces, non-manifold curves and points,
 * topology, triangle quality, the figures from f) and releases everything on failure. */
#include "core/analysis/analysis_internal.h"

#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define MAX_COORD 1e100 /* larger coordinates would overflow squared lengths */

void ism_analysis_options_default(ism_analysis_options *o)
{
    memset(o, 0, sizeof *o);
    o->curvature = true;
    o->accuracy = true;
    o->project = false;
    o->threads = 0;
    o->singular_rel = 1e-6;
    o->newton_steps = 4;
}


/* Bad input gets a message naming the first offending vertex or triangle. */
bool ism_an_check_mesh(const ism_mesh *m, ism_error *err)
{
    if (m->nverts >= UINT32_MAX)
        return ism_an_fail(err, "analysis: %zu vertices, at most %u allowed", m->nverts,
                           UINT32_MAX - 1);
    if (m->ntris > (UINT32_MAX - 3) / 3)
        return ism_an_fail(err, "analysis: %zu triangles, at most %u allowed", m->ntris,
                           (UINT32_MAX - 3) / 3);
    for (size_t i = 0; i < 3 * m->nverts; i++)
        if (!(fabs(m->pos[i]) <= MAX_COORD))
            return ism_an_fail(err, "analysis: vertex %zu has a coordinate that is not "
                               "a finite number below 1e100", i / 3);
    for (size_t i = 0; i < 3 * m->ntris; i++)
        if (m->tri[i] >= m->nverts)
            return ism_an_fail(err, "analysis: triangle %zu uses vertex %u, but the "
                               "mesh has %zu vertices", i / 3, m->tri[i], m->nverts);
    return true;
}

bool ism_an_check_options(const ism_analysis_options *o, ism_error *err)
{
    if (!(o->singular_rel >= 0 && o->singular_rel < 1))
        return ism_an_fail(err, "analysis: singular_rel must be in [0, 1)");
    if (o->newton_steps < 0 || o->newton_steps > 100)
        return ism_an_fail(err, "analysis: newton_steps must be in 0..100");
    if (o->threads < 0 || o->threads > 64)
        return ism_an_fail(err, "analysis: threads must be in 0..64");
    return true;
}

static void count_collapsed(const ism_mesh *m, ism_analysis *a)
{
    for (size_t t = 0; t < m->ntris; t++)
        a->collapsed_triangles += ism_an_tri_collapsed(m->tri, t);
}

bool ism_analyse(const ism_mesh *m, const ism_tape *f, const ism_analysis_options *o,
                 ism_analysis *a, ism_error *err)
{
    ism_analysis_options defaults;
    if (!o) {
        ism_analysis_options_default(&defaults);
        o = &defaults;
    }
    memset(a, 0, sizeof *a);
    if (!ism_an_check_options(o, err) || !ism_an_check_mesh(m, err))
        return false;
    a->nverts = m->nverts;
    a->genus = -1;
    count_collapsed(m, a);
    ism_an_edge_table et;
    ism_an_vertex_facts vf = {0};
    bool ok = ism_an_edge_table_build(m, &et);
    ok = ok && ism_an_classify_vertices(m, &et, &vf, a) && ism_an_find_curves(m, &et, &vf, a) &&
         ism_an_find_points(m, &vf, a) && ism_an_topology(m, &et, &vf, a) &&
         ism_an_count_duplicates(m, &et, a) && ism_an_triangle_quality(m, a);
    free(vf.cone_sets); /* the rest needs only per-vertex facts and the edges */
    vf.cone_sets = NULL;
    ok = ok && ism_an_implicit_figures(m, f, o, &vf, a);
    if (ok && f && o->accuracy)
        ok = ism_an_between_vertices(m, f, &et, o->threads, a);
    ism_an_edge_table_free(&et);
    ism_an_vertex_facts_free(&vf);
    if (!ok) {
        ism_analysis_free(a);
        return ism_an_fail(err, "analysis: out of memory (mesh of %zu vertices, %zu "
                           "triangles)", m->nverts, m->ntris);
    }
    return true;
}

void ism_analysis_free(ism_analysis *a)
{
    void *arrays[] = {a->vertex_class, a->curve_start, a->curve_verts, a->points,
                      a->point_kind, a->point_pos, a->component, a->mean_curvature,
                      a->gauss_curvature, a->k1, a->k2, a->singular, a->vertex_area,
                      a->triangle_min_angle, a->distance};
    for (size_t i = 0; i < sizeof arrays / sizeof *arrays; i++)
        free(arrays[i]);
    memset(a, 0, sizeof *a);
    a->genus = -1;
}
