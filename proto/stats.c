/* stats.c — writes the stats JSON (layout in stats.h) from the polygoniser's and the
 * analysis's structures, naming every field after its C counterpart so that the numbers can
 * be traced back to the code that counted them. */
#include "proto/stats.h"
#include "proto/features.h"
#include "proto/request.h"
#include "proto/json_writer.h"
#include "core/version.h"

#include <math.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static void kv_u(ism_jw *w, const char *k, uint64_t v)
{
    ism_jw_key(w, k);
    ism_jw_uint(w, v);
}

/* Milliseconds to the microsecond (more digits would be noise). */
static void kv_ms(ism_jw *w, const char *k, double v)
{
    ism_jw_key(w, k);
    ism_jw_number(w, round(v * 1e3) / 1e3);
}

/* One number of a stats object: its JSON key, where it lives in the C structure and how it is
 * written (a 64-bit unsigned count, a double, or milliseconds). The tables below list each
 * object's plain numbers in output order; what is not a plain number (nested objects, nulls,
 * arrays) is written around them. KIND_OF has no default: a member of any other type (an int,
 * a bool, a narrower count) does not compile, so every count is read as 64 bits. */
enum field_kind { FIELD_COUNT, FIELD_DOUBLE, FIELD_MS };

typedef struct stat_field {
    const char *key;
    size_t offset;
    enum field_kind kind;
} stat_field;

_Static_assert(sizeof(unsigned long) == sizeof(uint64_t) &&
               sizeof(unsigned long long) == sizeof(uint64_t), "counts are read as 64 bits");
#define KIND_OF(type, member) \
    _Generic(((type *)0)->member, double: FIELD_DOUBLE, unsigned long: FIELD_COUNT, \
             unsigned long long: FIELD_COUNT)
/* The member's own name as the key; NAMED when the JSON says it otherwise. */
#define NAMED(key, type, member) {key, offsetof(type, member), KIND_OF(type, member)}
#define FIELD(type, member) NAMED(#member, type, member)
#define MS(key, type, member) {key, offsetof(type, member), FIELD_MS}
#define NFIELDS(t) (sizeof(t) / sizeof(t[0]))

static void write_fields(ism_jw *w, const void *base, const stat_field *f, size_t n)
{
    for (size_t i = 0; i < n; i++) {
        const unsigned char *at = (const unsigned char *)base + f[i].offset;
        if (f[i].kind == FIELD_COUNT) {
            uint64_t v;
            memcpy(&v, at, sizeof v);
            kv_u(w, f[i].key, v);
            continue;
        }
        double v;
        memcpy(&v, at, sizeof v);
        if (f[i].kind == FIELD_MS) {
            kv_ms(w, f[i].key, v);
        } else {
            ism_jw_key(w, f[i].key);
            ism_jw_number(w, v);
        }
    }
}

#define P(m) FIELD(ism_poly_stats, m)
static const stat_field poly_fields[] = {
    P(nodes_visited), P(nodes_excluded), P(plotting_nodes), P(unresolved_nodes),
    P(unflat_nodes), P(unflat_worst),
    P(thin_searched), P(thin_found), P(thin_undecided), P(deep_leaves),
    P(leaf_tapes), P(short_tape_leaves), P(tape_misses),
    P(error_missed_nodes), P(error_worst), P(error_rounds),
    P(edges_single_root), P(edges_double_root), P(edges_touching), P(edges_many_roots),
    P(zero_vertices), P(polygons), P(two_polygon_nodes), P(degenerate_polygons),
    P(nonmanifold_lines), P(open_chains), P(cracks_repaired), P(singular_points),
    P(crossed_faces), P(lifted_polygons), P(lifted_chords),
    P(evals_point), P(evals_interval), P(evals_gradient), P(triangles), P(vertices),
};
#undef P

#define A(m) FIELD(ism_analysis, m)
static const stat_field accuracy_fields[] = {
    A(max_dist_vertex), A(mean_dist_vertex), A(p99_dist_vertex),
    A(max_dist_midpoint), A(mean_dist_midpoint), A(p99_dist_midpoint),
    A(max_dist_centroid), A(mean_dist_centroid), A(p99_dist_centroid),
    A(max_newton_dist), A(mean_newton_dist), NAMED("skipped", ism_analysis, accuracy_skipped),
};

static const stat_field edge_fields[] = {
    A(edges), A(boundary_edges), A(manifold_edges), A(nonmanifold_edges), A(nonmanifold_vertices),
};

static const stat_field component_fields[] = {
    NAMED("nonmanifold_curves", ism_analysis, ncurves),
    NAMED("nonmanifold_points", ism_analysis, npoints),
};

static const stat_field topology_fields[] = {
    A(components), A(vertex_components), A(boundary_loops), A(boundary_chains),
};

static const stat_field measure_fields[] = {
    A(vertices_used), A(triangles_used), A(collapsed_triangles), A(area), A(total_gauss),
    A(total_abs_gauss), A(singular_vertices), A(gradient_scale),
};

static const stat_field quality_fields[] = {
    A(min_angle), A(median_angle), A(share_under_10), A(degenerate_triangles), A(aspect_max),
    A(aspect_mean), A(aspect_p99),
};
#undef A

#define C(m) FIELD(ism_conform_stats, m)
static const stat_field conform_fields[] = {
    C(points_conformed), C(points_failed), C(points_short_cones), C(curves_conformed),
    C(curves_kept), C(curves_failed), C(loops_fallback), C(triangles_removed), C(triangles_added),
    MS("time_ms", ism_conform_stats, time_ms),
};
#undef C

#define R(m) FIELD(ism_remesh_stats, m)
static const stat_field remesh_fields[] = {
    R(flips), R(moves), R(collapses), R(inserts), R(locked_vertices), R(min_angle_before),
    R(min_angle_after),
    MS("time_ms", ism_remesh_stats, time_ms),
};
#undef R

#define S(m) FIELD(ism_simplify_stats, m)
static const stat_field simplify_fields[] = {
    S(triangles_before), S(triangles_after), S(collapses), S(flips), S(moves), S(rounds),
    S(locked_vertices), S(min_angle_before), S(min_angle_after),
    MS("time_ms", ism_simplify_stats, time_ms),
};
#undef S

static void write_poly(ism_jw *w, const ism_poly_stats *s)
{
    static const char *const phase[ISM_PHASE_COUNT] = {"octree", "polygons", "cracks", "mesh"};
    ism_jw_object(w);
    ism_jw_key(w, "mesher"); /* which one made the mesh, and why not the dual one */
    ism_jw_string(w, ism_mesher_name(s->mesher));
    ism_jw_key(w, "dual_declined");
    if (s->dual_declined == ISM_DUAL_WHY_NONE)
        ism_jw_null(w);
    else
        ism_jw_string(w, ism_dual_reason_name(s->dual_declined));
    write_fields(w, s, poly_fields, NFIELDS(poly_fields));
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
    write_fields(w, a, accuracy_fields, NFIELDS(accuracy_fields));
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

static void write_quality(ism_jw *w, const ism_analysis *a)
{
    ism_jw_key(w, "quality");
    ism_jw_object(w);
    write_fields(w, a, quality_fields, NFIELDS(quality_fields));
    ism_jw_key(w, "angle_hist");
    ism_jw_array(w);
    for (int i = 0; i < ISM_ANGLE_BINS; i++)
        ism_jw_uint(w, a->angle_hist[i]);
    ism_jw_array_end(w);
    ism_jw_object_end(w);
}

static void write_analysis(ism_jw *w, const ism_analysis *a, double max_error)
{
    static const char *const cls[ISM_VERTEX_CLASSES] = {"manifold", "boundary",
                                                        "nonmanifold_edge",
                                                        "nonmanifold_point", "isolated"};
    ism_jw_object(w);
    write_fields(w, a, edge_fields, NFIELDS(edge_fields));
    ism_jw_key(w, "vertex_classes");
    ism_jw_object(w);
    for (int i = 0; i < ISM_VERTEX_CLASSES; i++)
        kv_u(w, cls[i], a->class_count[i]);
    ism_jw_object_end(w);
    write_fields(w, a, component_fields, NFIELDS(component_fields));
    ism_jw_key(w, "euler");
    ism_jw_int(w, a->euler);
    write_fields(w, a, topology_fields, NFIELDS(topology_fields));
    ism_jw_key(w, "orientable");
    ism_jw_bool(w, a->orientable);
    ism_jw_key(w, "inconsistent_edges");
    ism_jw_uint(w, a->inconsistent_edges);
    ism_jw_key(w, "genus");
    ism_jw_int(w, a->genus);
    write_fields(w, a, measure_fields, NFIELDS(measure_fields));
    write_quality(w, a);
    write_accuracy(w, a, max_error);
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
        ism_jw_object(w);
        write_fields(w, cs, conform_fields, NFIELDS(conform_fields));
        ism_jw_object_end(w);
    }
    ism_jw_object_end(w);
}

static void write_remesh(ism_jw *w, const ism_remesh_stats *s)
{
    ism_jw_object(w);
    write_fields(w, s, remesh_fields, NFIELDS(remesh_fields));
    ism_jw_object_end(w);
}

static void write_simplify(ism_jw *w, const ism_simplify_stats *s)
{
    ism_jw_object(w);
    write_fields(w, s, simplify_fields, NFIELDS(simplify_fields));
    ism_jw_key(w, "stopped");
    ism_jw_bool(w, s->stopped);
    ism_jw_object_end(w);
}

/* The stages a preview ("preview": true) does not run: the stages by their names in
 * timings_ms, and the request's curves and quality, which a preview refuses; and how it
 * searched for hidden pieces (ism_poly_options.thin_coarse: "coarse"). */
static void write_preview(ism_jw *w)
{
    static const char *const skipped[] = {"singular", "curves", "quality", "analysis",
                                          "features"};
    ism_jw_key(w, "preview");
    ism_jw_object(w);
    ism_jw_key(w, "skipped");
    ism_jw_array(w);
    for (size_t i = 0; i < sizeof skipped / sizeof *skipped; i++)
        ism_jw_string(w, skipped[i]);
    ism_jw_array_end(w);
    ism_jw_key(w, "thin_search");
    ism_jw_string(w, "coarse");
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

/* worst (> e) to the fewest significant digits, at least 3, that still read as more than e:
 * "up to 0.00451", never "up to 0.004" beside max_error 0.004, nor 17 digits of noise. */
static void format_beyond(double worst, double e, char *buf, size_t n)
{
    for (int digits = 3; digits <= 17; digits++) {
        snprintf(buf, n, "%.*g", digits, worst);
        if (strtod(buf, NULL) > e)
            return;
    }
}

/* The bound e as given when that takes at most BOUND_DIGITS significant digits (0.004), else
 * to 3, rounded down (the default bound, 1e-3 x the box diagonal, is 0.05542562584220407 for
 * the horn cyclide: "0.0554"): never above e, so a worst distance shown above e reads above
 * it too. Six digits: a bound anyone types reads back as itself. */
#define BOUND_DIGITS 6
static void format_bound(double e, char buf[32])
{
    for (int digits = 1; digits <= BOUND_DIGITS; digits++) {
        snprintf(buf, 32, "%.*g", digits, e);
        if (strtod(buf, NULL) == e)
            return;
    }
    ism_three_digits(e, -1, buf);
}

/* Under an error bound, one warning and only when the bound was not met: by the analysed
 * mesh when there is an analysis, else by the polygoniser's measurements of the cells it
 * could not split further. When no cell was left beyond the bound, the far triangles are not
 * the octree's (the conformance round singular points and curves makes them): a larger
 * depth.max would not help, and the warning says so instead of suggesting it. */
static void write_error_warning(ism_jw *w, const ism_stats_input *in)
{
    const ism_poly_stats *s = in->poly;
    uint64_t cells = s ? s->error_missed_nodes : 0;
    double worst = in->analysis ? worst_distance(in->analysis) : s ? s->error_worst : 0;
    if (worst <= in->max_error && (in->analysis || cells == 0))
        return;
    char msg[512], e[32], x[32], tail[320];
    format_bound(in->max_error, e);
    format_beyond(worst, in->max_error, x, sizeof x);
    if (cells)
        snprintf(tail, sizeof tail, "; %llu cells could not be split further (at depth.max, or "
                 "after the last refinement round): a larger depth.max may reach it (depth.max "
                 "is only a limit, max_error sets the accuracy: a larger max_error, or null for "
                 "no bound, asks for less)",
                 (unsigned long long)cells);
    else
        snprintf(tail, sizeof tail, ", though every octree cell met it: the triangles beyond "
                 "it were made where the mesh conforms to singular points and curves, and a "
                 "larger depth.max does not change them");
    snprintf(msg, sizeof msg, "max_error %s was not met: the mesh is up to %s from the "
             "surface%s", e, x, tail);
    ism_jw_string(w, msg);
}

/* Without an error bound, only the cells at depth.max a larger depth.max could improve:
 * not on a crease nor the singular locus (their non-flatness is the feature, at every
 * depth) and measured beyond the flatness test's tolerance (ism_poly_stats.unflat_nodes),
 * with the worst distance reached so a user can judge it. */
static void write_flatness_warning(ism_jw *w, const ism_poly_stats *s)
{
    char msg[300], mid[96] = ":"; /* the clause between the count and the advice */
    if (s->unflat_worst > 0)
        snprintf(mid, sizeof mid, ": their triangles are up to %.3g from the surface;",
                 s->unflat_worst);
    snprintf(msg, sizeof msg, "%llu cells at the maximum depth were not flat enough%s a larger "
             "depth.max or a max_error would bring them closer",
             (unsigned long long)s->unflat_nodes, mid);
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
    else if (s && s->unflat_nodes)
        write_flatness_warning(w, s);
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
    if (in->simplify) {
        ism_jw_key(&w, "simplify");
        write_simplify(&w, in->simplify);
    }
    if (in->remesh) {
        ism_jw_key(&w, "remesh");
        write_remesh(&w, in->remesh);
    }
    if (in->preview)
        write_preview(&w);
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
