/* bench_remesh.c — the quality pass on a preset in its own box and in boxes shifted off the
 * octree lattice: for each box, the polygoniser's mesh (with the singular locus and its
 * conformance, as the CLI runs it) and the mesh after the pass, measured by the analysis:
 * smallest angle, triangles under 10°, largest distance from f = 0 at centroids, edge
 * midpoints and vertices, χ, non-manifold edges and points, components, boundary loops; and
 * the pass's flips, moves and time. Asserts nothing.
 *
 *   bench_remesh PRESET [SHIFT...]     SHIFT: fractions of a finest cell (default 0 1e-3 0.37)
 */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "core/analysis/analysis.h"
#include "core/remesh/quality_pass.h"
#include "core/singular/surface.h"
#include "proto/request.h"

static void row(const char *tag, const ism_mesh *m, const ism_tape *t)
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
    ism_analysis_free(&a);
}

/* Meshes the preset in its box moved by shift finest cells (y the other way) and prints the
 * raw and good rows. False when the preset or the meshing fails. */
static bool run(const char *name, double shift)
{
    char json[256];
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
        row("raw", &m, t);
        ok = ism_quality_pass(t, &l, NULL, o.max_error, NULL, &m, &rs, &err);
    }
    if (ok) {
        row("good", &m, t);
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
    if (argc < 2) {
        fprintf(stderr, "usage: bench_remesh PRESET [SHIFT...]\n");
        return 2;
    }
    static const double shifts[] = {0, 1e-3, 0.37};
    printf("%-5s %8s %7s %6s %10s %10s %10s %4s %5s %4s %5s %3s\n", "", "tris", "min°",
           "<10°", "centroid", "midpoint", "vertex", "χ", "nm e", "nm p", "comp", "bl");
    bool ok = true;
    if (argc == 2)
        for (size_t i = 0; i < sizeof shifts / sizeof shifts[0]; i++)
            ok = run(argv[1], shifts[i]) && ok;
    for (int i = 2; i < argc; i++)
        ok = run(argv[1], atof(argv[i])) && ok;
    return ok ? 0 : 1;
}
