/* analysis.c — the analysis as one call: checks the mesh, builds the edge table, then runs
 * the passes in order (vertex classes by cones of faces, non-manifold curves and points,
 * topology, triangle quality, the figures from f) and releases everything on failure. On
 * more than one thread the connectivity passes (classes to topology: serial union-finds and
 * walks) run on a side thread beside the others, which share no data with them but the
 * mesh, the edge table and the vertices' corners, all read-only by then; the others' pool is
 * then one thread smaller, so the threads option counts every thread the analysis runs.
 * Each pass has its own header, included below and only here; the passes include the
 * low-level headers (edges.h, vertices.h, analysis_types.h, ...), never this driver's. */
#include "core/analysis/analysis.h"
#include "core/analysis/checks.h"
#include "core/analysis/options.h"
#include "core/analysis/edges.h"
#include "core/analysis/vertices.h"
#include "core/analysis/curves.h"
#include "core/analysis/topology.h"
#include "core/analysis/duplicates.h"
#include "core/analysis/quality.h"
#include "core/analysis/implicit.h"
#include "core/analysis/accuracy.h"
#include "core/analysis/blocks.h"
#include "core/util/parallel.h"
#include "core/util/side.h"

#include <stdlib.h>
#include <string.h>

/* Below this many triangles the passes that do not evaluate f run on the calling thread:
 * they take less than starting a thread does (tens of microseconds). */
#define POOL_MIN_TRIANGLES 8192

static void count_collapsed(const ism_mesh *m, ism_analysis *a)
{
    for (size_t t = 0; t < m->ntris; t++)
        a->collapsed_triangles += ism_an_tri_collapsed(m->tri, t);
}

/* The connectivity passes and what they share with the rest (see the top comment). */
typedef struct connectivity {
    const ism_mesh *m;
    const ism_an_edge_table *et;
    ism_an_vertex_facts *vf;
    ism_analysis *a;
    bool ok;
} connectivity;

static void run_connectivity(void *arg)
{
    connectivity *c = arg;
    c->ok = ism_an_classify_vertices(c->m, c->et, c->vf, c->a) &&
            ism_an_find_curves(c->m, c->et, c->vf, c->a) && ism_an_find_points(c->m, c->vf, c->a) &&
            ism_an_topology(c->m, c->et, c->vf, c->a);
    free(c->vf->cone_sets); /* the rest needs only per-vertex facts and the edges */
    c->vf->cone_sets = NULL;
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
    /* the passes' threads, made once for all of them: worth it for a mesh of many
     * triangles, or when f is evaluated at more than one block of vertices (a few
     * evaluations each, far more than the triangle passes' work per item). On several, the
     * connectivity passes take one for their side thread and the pool the others, so that
     * the analysis runs o->threads threads in all (the CLI's --threads, a daemon worker's
     * limit) */
    bool evaluates = f && (o->curvature || o->accuracy) && m->nverts > ISM_AN_EVAL_BLOCK;
    bool worth = m->ntris >= POOL_MIN_TRIANGLES || evaluates;
    int threads = ism_threads_resolve(o->threads);
    bool side_thread = worth && threads > 1;
    ism_pool *pool = ism_an_pool_new(side_thread ? threads - 1 : threads, worth);
    bool ok = ism_an_edge_table_build_on(m, pool, &et) && ism_an_count_corners(m, &vf);
    connectivity c = {m, &et, &vf, a, false};
    ism_side side;
    bool beside = ok; /* the side job was started (and must be joined) */
    if (beside)
        ism_side_start(&side, side_thread, run_connectivity, &c);
    ok = ok && ism_an_count_duplicates(m, &et, pool, a) && ism_an_triangle_quality(m, pool, a);
    ok = ok && ism_an_implicit_figures(m, f, o, &vf, pool, a);
    if (ok && f && o->accuracy)
        ok = ism_an_between_vertices(m, f, &et, o->max_error, pool, a);
    if (beside) {
        ism_side_join(&side);
        ok = ok && c.ok;
    }
    ism_pool_free(pool);
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
                      a->point_kind, a->point_pos, a->component, a->boundary_start,
                      a->boundary_verts, a->mean_curvature,
                      a->gauss_curvature, a->k1, a->k2, a->singular, a->vertex_area,
                      a->triangle_min_angle, a->distance};
    for (size_t i = 0; i < sizeof arrays / sizeof *arrays; i++)
        free(arrays[i]);
    memset(a, 0, sizeof *a);
    a->genus = -1;
}
