/* quality_pass.c — hands the locus's points, double-sheet ranges and the curve cut's edges to
 * the quality pass or the simplification as protection, and renumbers them as its collapses
 * renumbered the mesh (quality_pass.h). */
#include "core/remesh/quality_pass.h"

#include <stdlib.h>
#include <string.h>

static const char *const names[ISM_QUALITY_COUNT] = {"raw", "good"};

const char *ism_quality_name(enum ism_quality q)
{
    return q >= 0 && q < ISM_QUALITY_COUNT ? names[q] : "?";
}

int ism_quality_lookup(const char *name)
{
    for (int i = 0; i < ISM_QUALITY_COUNT; i++)
        if (!strcmp(name, names[i]))
            return i;
    return -1;
}

/* 0 for the polygoniser's triangles, 1 + i for double sheet i's (a triangle of a cut mesh
 * takes its parent's: cut.h). */
static uint32_t *sheet_labels(const ism_locus *locus, const ism_cut *cut, const ism_mesh *mesh)
{
    const uint32_t *parent = cut ? cut->tri_parent : NULL;
    uint32_t *label = calloc(mesh->ntris ? mesh->ntris : 1, sizeof *label);
    for (size_t t = 0; label && t < mesh->ntris; t++)
        label[t] = ism_locus_sheet_of(locus, parent ? parent[t] : t);
    return label;
}

/* The cut's edges and triangle parents in the renumbered mesh (a cut edge's vertices are
 * locked: never gone); false when out of memory. */
static bool renumber_cut(ism_cut *cut, const ism_remesh_renumber *ren)
{
    for (size_t i = 0; i < cut->nedges; i++) {
        cut->edges[i].a = ren->vert[cut->edges[i].a];
        cut->edges[i].b = ren->vert[cut->edges[i].b];
    }
    if (!cut->tri_parent)
        return true;
    uint32_t *parent = malloc((ren->ntris_after ? ren->ntris_after : 1) * sizeof *parent);
    if (!parent)
        return false;
    for (size_t t = 0; t < ren->ntris_after; t++)
        parent[t] = cut->tri_parent[ren->origin[t]];
    free(cut->tri_parent);
    cut->tri_parent = parent;
    return true;
}

/* How many triangles after the pass have their origin before triangle t (the origins are
 * non-decreasing: the first index whose origin is t or later). */
static size_t first_from(const ism_remesh_renumber *ren, size_t t)
{
    size_t n = 0;
    while (n < ren->ntris_after && ren->origin[n] < t)
        n++;
    return n;
}

/* Each double sheet's range of triangles in the renumbered mesh: those whose origin lies in
 * its range before. */
static void renumber_sheets(ism_locus *locus, const ism_remesh_renumber *ren)
{
    for (size_t i = 0; i < locus->nsheets; i++) {
        ism_double_sheet *s = &locus->sheets[i];
        size_t a = first_from(ren, s->first_triangle);
        s->triangles = first_from(ren, s->first_triangle + s->triangles) - a;
        s->first_triangle = a;
    }
}

/* A pass over the mesh with the options it is given, its statistics at st. */
typedef bool (*pass_fn)(ism_mesh *m, const ism_remesh_options *o, void *st,
                        ism_remesh_renumber *ren, ism_error *err);

static bool quality_fn(ism_mesh *m, const ism_remesh_options *o, void *st,
                       ism_remesh_renumber *ren, ism_error *err)
{
    return ism_remesh_quality(m, o, st, ren, err);
}

static bool simplify_fn(ism_mesh *m, const ism_remesh_options *o, void *st,
                        ism_remesh_renumber *ren, ism_error *err)
{
    return ism_remesh_simplify(m, o, st, ren, err);
}

/* Runs pass on mesh with the locus's points, the sheets' labels and the cut's edges
 * protected, and renumbers them after it. */
static bool run_protected(pass_fn pass, const ism_tape *f, ism_locus *locus, ism_cut *cut,
                          double max_error, const volatile int *cancel, ism_mesh *mesh,
                          void *st, ism_error *err)
{
    size_t ne = cut ? cut->nedges : 0, np = locus->npoints;
    uint32_t *edges = malloc((ne ? ne : 1) * 2 * sizeof *edges);
    double *points = malloc((np ? np : 1) * 3 * sizeof *points);
    uint32_t *label = sheet_labels(locus, cut, mesh);
    bool ok = edges && points && label;
    if (ok) {
        for (size_t i = 0; i < ne; i++) {
            edges[2 * i] = cut->edges[i].a;
            edges[2 * i + 1] = cut->edges[i].b;
        }
        for (size_t i = 0; i < np; i++)
            memcpy(points + 3 * i, locus->points[i].p, 3 * sizeof *points);
        ism_remesh_options o = {.f = f, .max_error = max_error, .tri_label = label,
                                .locked_edges = edges, .nlocked_edges = ne,
                                .locked_points = points, .nlocked_points = np,
                                .cancel = cancel};
        ism_remesh_renumber ren;
        ok = pass(mesh, &o, st, &ren, err);
        if (ren.vert && !(cut && cut->tri_parent))
            renumber_sheets(locus, &ren);
        if (ren.vert && cut && !renumber_cut(cut, &ren))
            ok = ism_error_set(err, "out of memory renumbering the curves after a mesh pass");
        ism_remesh_renumber_free(&ren);
    } else {
        ism_error_set(err, "out of memory before a mesh pass");
    }
    free(edges);
    free(points);
    free(label);
    return ok;
}

bool ism_quality_pass(const ism_tape *f, ism_locus *locus, ism_cut *cut,
                      double max_error, const volatile int *cancel, ism_mesh *mesh,
                      ism_remesh_stats *st, ism_error *err)
{
    memset(st, 0, sizeof *st);
    return run_protected(quality_fn, f, locus, cut, max_error, cancel, mesh, st, err);
}

bool ism_simplify_pass(const ism_tape *f, ism_locus *locus, ism_cut *cut,
                       double max_error, const volatile int *cancel, ism_mesh *mesh,
                       ism_simplify_stats *st, ism_error *err)
{
    memset(st, 0, sizeof *st);
    return run_protected(simplify_fn, f, locus, cut, max_error, cancel, mesh, st, err);
}
