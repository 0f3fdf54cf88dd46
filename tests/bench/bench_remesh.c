/* bench_remesh.c — the quality pass on a preset in its own box and in boxes shifted off the
 * octree lattice: for each box, the polygoniser's mesh (with the singular locus and its
 * conformance, as the CLI runs it) and the mesh after the pass, measured by the analysis:
 * smallest angle, triangles under 10°, largest distance from f = 0 at centroids, edge
 * midpoints and vertices, χ, non-manifold edges and points, components, boundary loops; and
 * the pass's flips, moves and time; and a census of the triangles under 10° by what they
 * touch (a singular point, the double curve, the boundary, nothing) and of the folded edges.
 * Asserts nothing.
 *
 *   bench_remesh PRESET [SHIFT...]     SHIFT: fractions of a finest cell (default 0 1e-3 and
 *                                      √2 − 1, tests/unit/placements.h)
 *   bench_remesh --max-error off|E PRESET [SHIFT...]
 *                                      the request's max_error (default: the request's own,
 *                                      1e-3 × the box diagonal; off: the depth-driven mesh
 *                                      every figure in core/README.md's quality pass before
 *                                      session 15's default bound was measured on)
 *   CENSUS_VERBOSE=1 bench_remesh ...  also lists each needle (angle, centroid, distance to
 *                                      the nearest point, what its corners touch) and each
 *                                      turned-over fold's end points
 */
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "core/analysis/analysis.h"
#include "core/analysis/edges.h"
#include "core/remesh/quality_pass.h"
#include "core/remesh/rm_mesh.h"
#include "core/singular/surface.h"
#include "proto/request.h"
#include "tests/unit/placements.h"

/* The (unnormalised) normal of triangle t from its winding. */
static void normal_of(const ism_mesh *m, size_t t, double n[3])
{
    const uint32_t *v = m->tri + 3 * t;
    rm_cross(m->pos + 3 * (size_t)v[0], m->pos + 3 * (size_t)v[1], m->pos + 3 * (size_t)v[2], n);
}

/* Normals n1 and n2 lie on opposite sides of ∇f at p (a triangle turned over against the
 * surface's orientation, not a crease, where both face ∇f's side); false where ∇f vanishes. */
static bool turned(const ism_tape *t, ism_eval_ws *ws, const double *p, const double *n1,
                   const double *n2)
{
    double g[3];
    ism_eval_gradient(t, ws, p[0], p[1], p[2], g);
    double a = n1[0] * g[0] + n1[1] * g[1] + n1[2] * g[2];
    double b = n2[0] * g[0] + n2[1] * g[1] + n2[2] * g[2];
    return (a > 0 && b < 0) || (a < 0 && b > 0);
}

/* The needles (triangles under 10°) by what they touch: a vertex at one of the locus's points
 * (allowed by issue 15), else a vertex of a non-manifold edge (the double curve), else a
 * boundary vertex, else nothing; and the folds: edges of two triangles whose normals meet at
 * more than 90°, all of them, those with no end on a non-manifold edge or at a point, and of
 * those the ones turned over against ∇f at both ends (not creases). */
static void census(const ism_mesh *m, const ism_locus *l, const ism_tape *tape,
                   const float *angle)
{
    ism_an_edge_table et;
    uint8_t *mark = calloc(m->nverts ? m->nverts : 1, 1); /* 1 point, 2 nm edge, 4 boundary */
    bool have_edges = mark && ism_an_edge_table_build(m, &et);
    if (!have_edges)
        goto out;
    for (uint32_t e = 0; e < et.nedges; e++) {
        uint32_t n = ism_an_edge_count(&et, e), lo, hi;
        ism_an_edge_ends(m, &et, e, &lo, &hi);
        mark[lo] |= n == 1 ? 4 : n > 2 ? 2 : 0;
        mark[hi] |= n == 1 ? 4 : n > 2 ? 2 : 0;
    }
    double far = 0;
    for (size_t i = 0; i < l->npoints; i++) {
        size_t best = 0;
        double bd = INFINITY;
        for (size_t v = 0; v < m->nverts; v++) {
            const double *p = m->pos + 3 * v, *q = l->points[i].p;
            double d = hypot(hypot(p[0] - q[0], p[1] - q[1]), p[2] - q[2]);
            if (d < bd)
                bd = d, best = v;
        }
        if (m->nverts)
            mark[best] |= 1, far = fmax(far, bd);
    }
    size_t by[4] = {0}, folds = 0, away = 0, flipped = 0;
    ism_eval_ws *ws = ism_eval_ws_new(tape);
    for (size_t t = 0; t < m->ntris; t++) {
        if (!(angle[t] > 0 && angle[t] < 10))
            continue;
        uint8_t any = mark[m->tri[3 * t]] | mark[m->tri[3 * t + 1]] | mark[m->tri[3 * t + 2]];
        by[any & 1 ? 0 : any & 2 ? 1 : any & 4 ? 2 : 3]++;
        if (getenv("CENSUS_VERBOSE")) {
            const uint32_t *v = m->tri + 3 * t;
            double c[3], pd = INFINITY;
            for (int j = 0; j < 3; j++)
                c[j] = (m->pos[3 * v[0] + j] + m->pos[3 * v[1] + j] + m->pos[3 * v[2] + j]) / 3;
            for (size_t i = 0; i < l->npoints; i++)
                pd = fmin(pd, hypot(hypot(c[0] - l->points[i].p[0], c[1] - l->points[i].p[1]),
                                    c[2] - l->points[i].p[2]));
            printf("   T%zu %.2f° (%.4f %.4f %.4f) pt %.4f marks %d %d %d\n", t, angle[t],
                   c[0], c[1], c[2], pd, mark[v[0]], mark[v[1]], mark[v[2]]);
        }
    }
    for (uint32_t e = 0; e < et.nedges; e++) {
        if (ism_an_edge_count(&et, e) != 2)
            continue;
        uint32_t a, b;
        ism_an_edge_ends(m, &et, e, &a, &b);
        double n1[3], n2[3];
        normal_of(m, et.edge_he[et.edge_start[e]] / 3, n1);
        normal_of(m, et.edge_he[et.edge_start[e] + 1] / 3, n2);
        if (n1[0] * n2[0] + n1[1] * n2[1] + n1[2] * n2[2] < 0) {
            bool clear = !((mark[a] | mark[b]) & 3);
            folds++;
            away += clear;
            bool over = clear && ws && turned(tape, ws, m->pos + 3 * a, n1, n2) &&
                        turned(tape, ws, m->pos + 3 * b, n1, n2);
            flipped += over;
            if (over && getenv("CENSUS_VERBOSE"))
                printf("   F (%.4f %.4f %.4f)-(%.4f %.4f %.4f)\n", m->pos[3 * a],
                       m->pos[3 * a + 1], m->pos[3 * a + 2], m->pos[3 * b], m->pos[3 * b + 1],
                       m->pos[3 * b + 2]);
        }
    }
    ism_eval_ws_free(ws);
    printf("      needles at a point %zu, on the double curve %zu, at the boundary %zu, "
           "elsewhere %zu; folds %zu (%zu away from features, %zu of them turned over); point "
           "vertices within %.2g\n",
           by[0], by[1], by[2], by[3], folds, away, flipped, far);
out:
    if (have_edges)
        ism_an_edge_table_free(&et);
    free(mark);
}

static void row(const char *tag, const ism_mesh *m, const ism_tape *t, const ism_locus *l)
{
    ism_analysis a;
    ism_error err;
    memset(&a, 0, sizeof a);
    if (!ism_analyse(m, t, NULL, &a, &err)) {
        printf("%-5s analysis failed: %s\n", tag, err.message);
        return;
    }
    size_t under = 0;
    for (size_t i = 0; i < m->ntris; i++)
        under += a.triangle_min_angle[i] > 0 && a.triangle_min_angle[i] < 10;
    printf("%-5s %8zu %7.2f %6zu %10.3g %10.3g %10.3g %4ld %5zu %4zu %5zu %3zu\n", tag, m->ntris,
           a.min_angle, under, a.max_dist_centroid, a.max_dist_midpoint, a.max_dist_vertex,
           a.euler, a.nonmanifold_edges, a.npoints, a.components, a.boundary_loops);
    census(m, l, t, a.triangle_min_angle);
    ism_analysis_free(&a);
}

/* Meshes the preset in its box moved by shift finest cells (y the other way) and prints the
 * raw and good rows. False when the preset or the meshing fails. */
static bool run(const char *name, const char *max_error, double shift)
{
    char json[256];
    if (max_error)
        snprintf(json, sizeof json, "{\"preset\": \"%s\", \"max_error\": %s}", name,
                 strcmp(max_error, "off") ? max_error : "null");
    else
        snprintf(json, sizeof json, "{\"preset\": \"%s\"}", name);
    ism_request req;
    ism_req_error rerr;
    if (!ism_request_decode(json, strlen(json), NULL, &req, &rerr)) {
        fprintf(stderr, "bench_remesh: %s\n", rerr.message);
        return false;
    }
    double *box = req.poly.box, cell = (box[3] - box[0]) / (1 << req.poly.max_depth);
    for (int k = 0; k < 6; k++)
        box[k] += shift * cell * (k % 3 == 1 ? -1 : 1);
    ism_tape *t = ism_request_compile(&req, &rerr);
    ism_poly_options o;
    ism_request_poly_options(&req, &o);
    o.threads = 1;
    ism_mesh m;
    ism_mesh_init(&m);
    ism_locus l;
    ism_locus_init(&l);
    ism_poly_stats ps;
    ism_conform_stats cs;
    ism_surface_times tm;
    ism_error err;
    ism_remesh_stats rs;
    bool ok = t && ism_mesh_surface(t, &o, &m, &l, &ps, &cs, &tm, &err) == ISM_POLY_OK;
    if (ok) {
        printf("%s, box shifted by %g of a finest cell\n", name, shift);
        row("raw", &m, t, &l);
        ok = ism_quality_pass(t, &l, NULL, o.max_error, NULL, &m, &rs, &err);
    }
    if (ok) {
        row("good", &m, t, &l);
        printf("      flips %zu, moves %zu, collapses %zu, inserts %zu, locked vertices %zu, "
               "%.0f ms\n", rs.flips, rs.moves, rs.collapses, rs.inserts, rs.locked_vertices,
               rs.time_ms);
    }
    ism_locus_free(&l);
    ism_mesh_free(&m);
    ism_tape_free(t);
    ism_request_free(&req);
    return ok;
}

int main(int argc, char **argv)
{
    const char *max_error = NULL;
    if (argc >= 3 && !strcmp(argv[1], "--max-error")) {
        max_error = argv[2];
        argv += 2;
        argc -= 2;
    }
    if (argc < 2) {
        fprintf(stderr, "usage: bench_remesh [--max-error off|E] PRESET [SHIFT...]\n");
        return 2;
    }
    static const double shifts[] = {0, 1e-3, PF_IRR};
    printf("%-5s %8s %7s %6s %10s %10s %10s %4s %5s %4s %5s %3s\n", "", "tris", "min°",
           "<10°", "centroid", "midpoint", "vertex", "χ", "nm e", "nm p", "comp", "bl");
    bool ok = true;
    if (argc == 2)
        for (size_t i = 0; i < sizeof shifts / sizeof shifts[0]; i++)
            ok = run(argv[1], max_error, shifts[i]) && ok;
    for (int i = 2; i < argc; i++)
        ok = run(argv[1], max_error, atof(argv[i])) && ok;
    return ok ? 0 : 1;
}
