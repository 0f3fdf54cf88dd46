/* features.c — gathers the non-manifold curves and points from the analysis and the boundary
 * chains from the mesh into one structure, and writes the features JSON the viewer draws
 * beside a Draco mesh (format in features.h). */
#include "proto/features.h"
#include "proto/json_writer.h"

#include <stdlib.h>
#include <string.h>

static const char *const class_names[] = {"manifold", "boundary", "nonmanifold_edge",
                                          "nonmanifold_point", "isolated"};

const char *ism_point_kind_name(int kind)
{
    switch (kind) {
    case ISM_POINT_CONES: return "cones";
    case ISM_POINT_CURVE_END: return "curve_end";
    case ISM_POINT_JUNCTION: return "junction";
    default: return "unknown";
    }
}

static bool copy_curves(const ism_analysis *a, ism_polylines *c)
{
    size_t n = a->ncurves, nv = a->ncurves ? a->curve_start[a->ncurves] : 0;
    c->start = malloc((n + 1) * sizeof *c->start);
    c->verts = malloc((nv ? nv : 1) * sizeof *c->verts);
    if (!c->start || !c->verts)
        return false;
    c->n = n;
    if (n)
        memcpy(c->start, a->curve_start, (n + 1) * sizeof *c->start);
    else
        c->start[0] = 0;
    if (nv)
        memcpy(c->verts, a->curve_verts, nv * sizeof *c->verts);
    return true;
}

bool ism_features_build(const ism_mesh *m, const ism_analysis *a, ism_features *f)
{
    memset(f, 0, sizeof *f);
    if (a) {
        if (!copy_curves(a, &f->curves))
            goto fail;
        size_t np = a->npoints;
        f->points = malloc((np ? np : 1) * sizeof *f->points);
        f->point_kind = malloc(np ? np : 1);
        f->point_class = malloc(np ? np : 1);
        if (!f->points || !f->point_kind || !f->point_class)
            goto fail;
        f->npoints = np;
        for (size_t i = 0; i < np; i++) {
            f->points[i] = a->points[i];
            f->point_kind[i] = a->point_kind ? a->point_kind[i] : ISM_POINT_CONES;
            f->point_class[i] = a->vertex_class ? a->vertex_class[a->points[i]] : 0;
        }
    } else {
        f->curves.start = calloc(1, sizeof *f->curves.start);
        if (!f->curves.start)
            goto fail;
    }
    if (a && a->boundary_edges == 0) {
        f->boundaries.start = calloc(1, sizeof *f->boundaries.start);
        if (!f->boundaries.start)
            goto fail;
    } else if (!ism_boundary_chains(m, &f->boundaries)) {
        goto fail;
    }
    return true;
fail:
    ism_features_free(f);
    return false;
}

void ism_features_free(ism_features *f)
{
    ism_polylines_free(&f->curves);
    ism_polylines_free(&f->boundaries);
    free(f->points);
    free(f->point_kind);
    free(f->point_class);
    memset(f, 0, sizeof *f);
}

static void write_xyz(ism_jw *w, const ism_mesh *m, uint32_t v)
{
    for (int k = 0; k < 3; k++)
        ism_jw_float(w, (float)m->pos[3 * (size_t)v + k]);
}

static size_t write_lines(ism_jw *w, const ism_mesh *m, const ism_polylines *p)
{
    size_t edges = 0;
    ism_jw_array(w);
    for (size_t i = 0; i < p->n; i++) {
        uint32_t s = p->start[i], e = p->start[i + 1];
        ism_jw_object(w);
        ism_jw_key(w, "closed");
        ism_jw_bool(w, e - s > 1 && p->verts[s] == p->verts[e - 1]);
        ism_jw_key(w, "xyz");
        ism_jw_array(w);
        for (uint32_t j = s; j < e; j++)
            write_xyz(w, m, p->verts[j]);
        ism_jw_array_end(w);
        ism_jw_object_end(w);
        edges += e > s ? e - s - 1 : 0;
    }
    ism_jw_array_end(w);
    return edges;
}

char *ism_features_json(const ism_mesh *m, const ism_features *f, size_t *len)
{
    ism_jw w;
    ism_jw_init(&w);
    ism_jw_object(&w);
    ism_jw_key(&w, "version");
    ism_jw_int(&w, 1);
    ism_jw_key(&w, "classes");
    ism_jw_array(&w);
    for (size_t i = 0; i < sizeof class_names / sizeof class_names[0]; i++)
        ism_jw_string(&w, class_names[i]);
    ism_jw_array_end(&w);
    ism_jw_key(&w, "curves");
    size_t curve_edges = write_lines(&w, m, &f->curves);
    ism_jw_key(&w, "points");
    ism_jw_array(&w);
    for (size_t i = 0; i < f->npoints; i++) {
        ism_jw_object(&w);
        ism_jw_key(&w, "xyz");
        ism_jw_array(&w);
        write_xyz(&w, m, f->points[i]);
        ism_jw_array_end(&w);
        ism_jw_key(&w, "class");
        ism_jw_int(&w, f->point_class[i]);
        ism_jw_key(&w, "kind");
        ism_jw_string(&w, ism_point_kind_name(f->point_kind[i]));
        ism_jw_object_end(&w);
    }
    ism_jw_array_end(&w);
    ism_jw_key(&w, "boundaries");
    size_t boundary_edges = write_lines(&w, m, &f->boundaries);
    ism_jw_key(&w, "counts");
    ism_jw_object(&w);
    ism_jw_key(&w, "curves");
    ism_jw_uint(&w, f->curves.n);
    ism_jw_key(&w, "curve_edges");
    ism_jw_uint(&w, curve_edges);
    ism_jw_key(&w, "points");
    ism_jw_uint(&w, f->npoints);
    ism_jw_key(&w, "boundaries");
    ism_jw_uint(&w, f->boundaries.n);
    ism_jw_key(&w, "boundary_edges");
    ism_jw_uint(&w, boundary_edges);
    ism_jw_object_end(&w);
    ism_jw_object_end(&w);
    return ism_jw_take(&w, len);
}
