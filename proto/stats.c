/* stats.c — writes the stats JSON (layout in stats.h) from the polygoniser's and the
 * analysis's structures, naming every field after its C counterpart so that the numbers can
 * be traced back to the code that counted them. */
#include "proto/stats.h"
#include "proto/features.h"
#include "proto/json_writer.h"
#include "core/version.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>

static void kv_u(ism_jw *w, const char *k, uint64_t v)
{
    ism_jw_key(w, k);
    ism_jw_uint(w, v);
}

static void kv_d(ism_jw *w, const char *k, double v)
{
    ism_jw_key(w, k);
    ism_jw_number(w, v);
}

/* Milliseconds to the microsecond (more digits would be noise). */
static void kv_ms(ism_jw *w, const char *k, double v)
{
    ism_jw_key(w, k);
    ism_jw_number(w, round(v * 1e3) / 1e3);
}

static void write_poly(ism_jw *w, const ism_poly_stats *s)
{
    static const char *const phase[ISM_PHASE_COUNT] = {"octree", "polygons", "cracks", "mesh"};
    ism_jw_object(w);
    kv_u(w, "nodes_visited", s->nodes_visited);
    kv_u(w, "nodes_excluded", s->nodes_excluded);
    kv_u(w, "plotting_nodes", s->plotting_nodes);
    kv_u(w, "unresolved_nodes", s->unresolved_nodes);
    kv_u(w, "thin_searched", s->thin_searched);
    kv_u(w, "thin_found", s->thin_found);
    kv_u(w, "thin_undecided", s->thin_undecided);
    kv_u(w, "deep_leaves", s->deep_leaves);
    kv_u(w, "error_missed_nodes", s->error_missed_nodes);
    kv_d(w, "error_worst", s->error_worst);
    kv_u(w, "error_rounds", s->error_rounds);
    kv_u(w, "edges_single_root", s->edges_single_root);
    kv_u(w, "edges_double_root", s->edges_double_root);
    kv_u(w, "edges_touching", s->edges_touching);
    kv_u(w, "edges_many_roots", s->edges_many_roots);
    kv_u(w, "zero_vertices", s->zero_vertices);
    kv_u(w, "polygons", s->polygons);
    kv_u(w, "two_polygon_nodes", s->two_polygon_nodes);
    kv_u(w, "degenerate_polygons", s->degenerate_polygons);
    kv_u(w, "nonmanifold_lines", s->nonmanifold_lines);
    kv_u(w, "open_chains", s->open_chains);
    kv_u(w, "cracks_repaired", s->cracks_repaired);
    kv_u(w, "singular_points", s->singular_points);
    kv_u(w, "crossed_faces", s->crossed_faces);
    kv_u(w, "lifted_polygons", s->lifted_polygons);
    kv_u(w, "lifted_chords", s->lifted_chords);
    kv_u(w, "evals_point", s->evals_point);
    kv_u(w, "evals_interval", s->evals_interval);
    kv_u(w, "evals_gradient", s->evals_gradient);
    kv_u(w, "triangles", s->triangles);
    kv_u(w, "vertices", s->vertices);
    ism_jw_key(w, "threads");
    ism_jw_int(w, s->threads);
    ism_jw_key(w, "time_ms");
    ism_jw_object(w);
    for (int i = 0; i < ISM_PHASE_COUNT; i++)
        kv_ms(w, phase[i], s->time_ms[i]);
    kv_ms(w, "total", s->total_ms);
    ism_jw_object_end(w);
    ism_jw_object_end(w);
}

/* The largest distance measured anywhere on the mesh: vertices, edge midpoints, centroids. */
static double worst_distance(const ism_analysis *a)
{
    return fmax(a->max_dist_vertex, fmax(a->max_dist_midpoint, a->max_dist_centroid));
}

static void write_accuracy(ism_jw *w, const ism_analysis *a, double max_error)
{
    ism_jw_key(w, "accuracy");
    ism_jw_object(w);
    kv_d(w, "max_dist_vertex", a->max_dist_vertex);
    kv_d(w, "mean_dist_vertex", a->mean_dist_vertex);
    kv_d(w, "p99_dist_vertex", a->p99_dist_vertex);
    kv_d(w, "max_dist_midpoint", a->max_dist_midpoint);
    kv_d(w, "mean_dist_midpoint", a->mean_dist_midpoint);
    kv_d(w, "p99_dist_midpoint", a->p99_dist_midpoint);
    kv_d(w, "max_dist_centroid", a->max_dist_centroid);
    kv_d(w, "mean_dist_centroid", a->mean_dist_centroid);
    kv_d(w, "p99_dist_centroid", a->p99_dist_centroid);
    kv_d(w, "max_newton_dist", a->max_newton_dist);
    kv_d(w, "mean_newton_dist", a->mean_newton_dist);
    kv_u(w, "skipped", a->accuracy_skipped);
    ism_jw_key(w, "max_error");
    if (max_error > 0)
        ism_jw_number(w, max_error);
    else
        ism_jw_null(w);
    ism_jw_key(w, "met");
    if (max_error > 0)
        ism_jw_bool(w, worst_distance(a) <= max_error);
    else
        ism_jw_null(w);
    ism_jw_object_end(w);
}

static void write_analysis(ism_jw *w, const ism_analysis *a, double max_error)
{
    static const char *const cls[ISM_VERTEX_CLASSES] = {"manifold", "boundary",
                                                        "nonmanifold_edge",
                                                        "nonmanifold_point", "isolated"};
    ism_jw_object(w);
    kv_u(w, "edges", a->edges);
    kv_u(w, "boundary_edges", a->boundary_edges);
    kv_u(w, "manifold_edges", a->manifold_edges);
    kv_u(w, "nonmanifold_edges", a->nonmanifold_edges);
    kv_u(w, "nonmanifold_vertices", a->nonmanifold_vertices);
    ism_jw_key(w, "vertex_classes");
    ism_jw_object(w);
    for (int i = 0; i < ISM_VERTEX_CLASSES; i++)
        kv_u(w, cls[i], a->class_count[i]);
    ism_jw_object_end(w);
    kv_u(w, "nonmanifold_curves", a->ncurves);
    kv_u(w, "nonmanifold_points", a->npoints);
    ism_jw_key(w, "euler");
    ism_jw_int(w, a->euler);
    kv_u(w, "components", a->components);
    kv_u(w, "vertex_components", a->vertex_components);
    kv_u(w, "boundary_loops", a->boundary_loops);
    kv_u(w, "boundary_chains", a->boundary_chains);
    ism_jw_key(w, "orientable");
    ism_jw_bool(w, a->orientable);
    ism_jw_key(w, "genus");
    ism_jw_int(w, a->genus);
    kv_u(w, "vertices_used", a->vertices_used);
    kv_u(w, "triangles_used", a->triangles_used);
    kv_u(w, "collapsed_triangles", a->collapsed_triangles);
    kv_d(w, "area", a->area);
    kv_d(w, "total_gauss", a->total_gauss);
    kv_d(w, "total_abs_gauss", a->total_abs_gauss);
    kv_u(w, "singular_vertices", a->singular_vertices);
    kv_d(w, "gradient_scale", a->gradient_scale);
    ism_jw_key(w, "quality");
    ism_jw_object(w);
    kv_d(w, "min_angle", a->min_angle);
    kv_d(w, "median_angle", a->median_angle);
    kv_d(w, "share_under_10", a->share_under_10);
    kv_u(w, "degenerate_triangles", a->degenerate_triangles);
    kv_d(w, "aspect_max", a->aspect_max);
    kv_d(w, "aspect_mean", a->aspect_mean);
    kv_d(w, "aspect_p99", a->aspect_p99);
    ism_jw_key(w, "angle_hist");
    ism_jw_array(w);
    for (int i = 0; i < ISM_ANGLE_BINS; i++)
        ism_jw_uint(w, a->angle_hist[i]);
    ism_jw_array_end(w);
    ism_jw_object_end(w);
    write_accuracy(w, a, max_error);
    ism_jw_object_end(w);
}

static void write_conform(ism_jw *w, const ism_conform_stats *s)
{
    ism_jw_object(w);
    kv_u(w, "points_conformed", s->points_conformed);
    kv_u(w, "points_failed", s->points_failed);
    kv_u(w, "points_short_cones", s->points_short_cones);
    kv_u(w, "curves_conformed", s->curves_conformed);
    kv_u(w, "curves_failed", s->curves_failed);
    kv_u(w, "loops_fallback", s->loops_fallback);
    kv_u(w, "triangles_removed", s->triangles_removed);
    kv_u(w, "triangles_added", s->triangles_added);
    kv_ms(w, "time_ms", s->time_ms);
    ism_jw_object_end(w);
}

static void write_singular(ism_jw *w, const ism_locus *l, const ism_locus_check *c,
                           const ism_conform_stats *cs)
{
    ism_jw_object(w);
    ism_locus_counts_json(w, l);
    ism_jw_key(w, "artefacts");
    if (c)
        ism_jw_uint(w, c->artefacts);
    else
        ism_jw_null(w);
    kv_u(w, "nonmanifold_edges_off", c ? c->nonmanifold_edges_off : 0);
    kv_u(w, "nonmanifold_points_off", c ? c->nonmanifold_points_off : 0);
    ism_jw_key(w, "incomplete");
    ism_jw_bool(w, l->incomplete);
    kv_u(w, "boxes_visited", l->boxes_visited);
    kv_u(w, "evals_interval", l->evals_interval);
    kv_u(w, "evals_jet", l->evals_jet);
    kv_ms(w, "time_ms", l->time_ms);
    if (cs) {
        ism_jw_key(w, "conform");
        write_conform(w, cs);
    }
    ism_jw_object_end(w);
}

static void write_remesh(ism_jw *w, const ism_remesh_stats *s)
{
    ism_jw_object(w);
    kv_u(w, "flips", s->flips);
    kv_u(w, "moves", s->moves);
    kv_u(w, "locked_vertices", s->locked_vertices);
    kv_d(w, "min_angle_before", s->min_angle_before);
    kv_d(w, "min_angle_after", s->min_angle_after);
    kv_ms(w, "time_ms", s->time_ms);
    ism_jw_object_end(w);
}

/* What the singular stage could not do, or where the mesh disagrees with it. */
static void singular_warnings(ism_jw *w, const ism_locus *l, const ism_locus_check *c)
{
    char msg[240];
    size_t uncertified = 0;
    for (size_t i = 0; l && i < l->npoints; i++)
        uncertified += !l->points[i].certified;
    if (l && l->incomplete) {
        snprintf(msg, sizeof msg, "the singular locus is incomplete (%s): singular points or "
                 "curves may be missing", l->incomplete_why);
        ism_jw_string(w, msg);
    }
    if (uncertified) {
        snprintf(msg, sizeof msg, "%zu singular points could not be certified (see their "
                 "residuals in the features)", uncertified);
        ism_jw_string(w, msg);
    }
    if (c && c->artefacts) {
        snprintf(msg, sizeof msg, "%zu non-manifold mesh edges and %zu non-manifold mesh points "
                 "are not on the singular locus found from f: artefacts of the polygoniser",
                 c->nonmanifold_edges_off, c->nonmanifold_points_off);
        ism_jw_string(w, msg);
    }
}

/* Under an error bound, one warning and only when the bound was not met: by the analysed
 * mesh when there is an analysis, else by the polygoniser's measurements of the cells it
 * could not split further. */
static void write_error_warning(ism_jw *w, const ism_stats_input *in)
{
    const ism_poly_stats *s = in->poly;
    uint64_t cells = s ? s->error_missed_nodes : 0;
    double worst = in->analysis ? worst_distance(in->analysis) : s ? s->error_worst : 0;
    if (worst <= in->max_error && (in->analysis || cells == 0))
        return;
    char msg[300], e[32], x[32];
    ism_jw_format_double(in->max_error, e);
    ism_jw_format_double(worst, x);
    snprintf(msg, sizeof msg, "max_error %s was not met: the mesh is up to %s from the "
             "surface; %llu cells could not be split further (at depth.max, or after the last "
             "refinement round): a larger depth.max may reach it", e, x,
             (unsigned long long)cells);
    ism_jw_string(w, msg);
}

/* What the polygoniser could not resolve, said in words (DESIGN.md: say so in the stats
 * instead of producing silent garbage). */
static void write_warnings(ism_jw *w, const ism_stats_input *in)
{
    const ism_poly_stats *s = in->poly;
    char msg[200];
    ism_jw_array(w);
    singular_warnings(w, in->locus, in->check);
    if (s && s->edges_many_roots) {
        snprintf(msg, sizeof msg, "%llu cell edges may hold more than two roots (the paper's "
                 "known failure case): parts of the surface may be missing there",
                 (unsigned long long)s->edges_many_roots);
        ism_jw_string(w, msg);
    }
    if (in->max_error > 0)
        write_error_warning(w, in);
    else if (s && s->unresolved_nodes) {
        snprintf(msg, sizeof msg, "%llu cells at the maximum depth were not flat enough: "
                 "a larger depth.max may show more detail",
                 (unsigned long long)s->unresolved_nodes);
        ism_jw_string(w, msg);
    }
    if (s && s->open_chains) {
        snprintf(msg, sizeof msg, "%llu line chains could not be closed into polygons",
                 (unsigned long long)s->open_chains);
        ism_jw_string(w, msg);
    }
    ism_jw_array_end(w);
}

char *ism_stats_surface_json(const ism_stats_input *in, size_t *len)
{
    ism_jw w;
    ism_jw_init(&w);
    ism_jw_object(&w);
    if (in->poly) {
        ism_jw_key(&w, "polygoniser");
        write_poly(&w, in->poly);
    }
    if (in->analysis) {
        ism_jw_key(&w, "analysis");
        write_analysis(&w, in->analysis, in->max_error);
    }
    if (in->locus) {
        ism_jw_key(&w, "singular");
        write_singular(&w, in->locus, in->check, in->conform);
    }
    if (in->remesh) {
        ism_jw_key(&w, "remesh");
        write_remesh(&w, in->remesh);
    }
    ism_jw_key(&w, "warnings");
    write_warnings(&w, in);
    ism_jw_object_end(&w);
    return ism_jw_take(&w, len);
}

char *ism_stats_json(const ism_stats_input *in, size_t *len)
{
    static const char *const timing[ISM_TIME_COUNT] = {"decode", "compile", "singular", "polygonise",
                                                    "analyse", "features", "encode", "total"};
    size_t slen = in->surface_len;
    char *own = in->surface ? NULL : ism_stats_surface_json(in, &slen);
    const char *surface = in->surface ? in->surface : own;
    if (!surface)
        return NULL;
    ism_jw w;
    ism_jw_init(&w);
    ism_jw_object(&w);
    ism_jw_key(&w, "key");
    ism_jw_string(&w, in->key ? in->key : "");
    ism_jw_key(&w, "mesher");
    ism_jw_string(&w, ISM_MESHER_VERSION);
    ism_jw_key(&w, "version");
    ism_jw_string(&w, ISM_VERSION);
    ism_jw_key(&w, "format");
    ism_jw_string(&w, in->format ? in->format : "");
    kv_u(&w, "bytes", in->bytes);
    kv_u(&w, "features_bytes", in->features_bytes);
    ism_jw_key(&w, "empty");
    ism_jw_bool(&w, in->empty);
    ism_jw_key(&w, "mesh");
    ism_jw_object(&w);
    kv_u(&w, "vertices", in->vertices);
    kv_u(&w, "triangles", in->triangles);
    kv_u(&w, "encoded_points", in->encoded_points);
    kv_u(&w, "encoded_faces", in->encoded_faces);
    ism_jw_object_end(&w);
    ism_jw_key(&w, "timings_ms");
    ism_jw_object(&w);
    for (int i = 0; i < ISM_TIME_COUNT; i++)
        kv_ms(&w, timing[i], in->timings_ms[i]);
    ism_jw_object_end(&w);
    ism_jw_members(&w, surface, slen);
    ism_jw_object_end(&w);
    free(own);
    return ism_jw_take(&w, len);
}
