/* features_curves.c — the requested curves and their arrangement in the features JSON:
 * curves of kinds section / level / intersection / silhouette (each its arcs as polylines in
 * full double precision, with its ends), the crease (its arcs thinned and rounded within the
 * drawing tolerance: features.h's digits table), and the "arrangement" object (vertices,
 * edges, faces with their triangle ranges, areas and Euler characteristics, and the Euler
 * check). */
#include "proto/features.h"
#include "proto/json_writer.h"

#include <stdlib.h>
#include <string.h>

static const char *const kind_names[ISM_CUT_KIND_COUNT] = {
    "section", "level", "intersection", "silhouette", "crease"};
static const char *const vertex_types[ISM_ARR_VERTEX_TYPE_COUNT] = {
    "crossing", "branch", "end", "loop", "double_curve", "singular_point"};

const char *ism_cut_kind_name(int kind)
{
    return kind >= 0 && kind < ISM_CUT_KIND_COUNT ? kind_names[kind] : "unknown";
}

bool ism_features_add_arcs(ism_features *f, const ism_arrangement *a, const ism_cut_fn *fns)
{
    size_t n = a->nedges, total = 0;
    for (size_t i = 0; i < n; i++)
        total += a->edges[i].count;
    if (total >= UINT32_MAX)
        return false;
    ism_polylines *p = &f->arcs;
    p->start = malloc((n + 1) * sizeof *p->start);
    p->verts = malloc((total ? total : 1) * sizeof *p->verts);
    f->arc_kind = malloc(n ? n : 1);
    f->arc_curve = malloc((n ? n : 1) * sizeof *f->arc_curve);
    if (!p->start || !p->verts || !f->arc_kind || !f->arc_curve)
        return false; /* the caller frees f */
    p->n = n;
    p->start[0] = 0;
    for (size_t i = 0; i < n; i++) {
        const ism_arr_edge *e = &a->edges[i];
        memcpy(p->verts + p->start[i], a->chain + e->first, e->count * sizeof *p->verts);
        p->start[i + 1] = p->start[i] + (uint32_t)e->count;
        f->arc_kind[i] = (uint8_t)fns[e->fn].kind;
        f->arc_curve[i] = e->curve;
    }
    return true;
}

static void write_vertex_xyz(ism_jw *w, const ism_mesh *m, uint32_t v)
{
    ism_jw_key(w, "xyz");
    ism_jw_numbers(w, m->pos + 3 * (size_t)v, 3);
}

/* What a curve ending at a vertex of type t ends on: "box", "double_curve",
 * "singular_point", or NULL where it does not end (its arcs join there). */
static const char *end_type(int t)
{
    return t == ISM_ARR_END            ? "box"
           : t == ISM_ARR_DOUBLE_CURVE   ? "double_curve"
           : t == ISM_ARR_SINGULAR_POINT ? "singular_point"
                                         : NULL;
}

/* The singular point's index into "singular_points" when v is at one. */
static void write_point(ism_jw *w, const ism_arr_vertex *v)
{
    if (v->type != ISM_ARR_SINGULAR_POINT)
        return;
    ism_jw_key(w, "point");
    ism_jw_int(w, v->point);
}

/* Each arc end of curve c where the curve ends, as {"type": "box" | "double_curve" |
 * "singular_point", "xyz", "vertex", "point" (singular points)}. */
static void write_ends(ism_jw *w, const ism_mesh *m, const ism_arrangement *a, size_t c)
{
    ism_jw_key(w, "ends");
    ism_jw_array(w);
    for (size_t i = 0; i < a->nedges; i++) {
        const ism_arr_edge *e = &a->edges[i];
        for (int k = 0; e->curve == c && k < 2; k++) {
            uint32_t v = k ? e->to : e->from;
            const char *type = end_type(a->vertices[v].type);
            if (!type)
                continue;
            ism_jw_object(w);
            ism_jw_key(w, "type");
            ism_jw_string(w, type);
            write_vertex_xyz(w, m, a->vertices[v].v);
            ism_jw_key(w, "vertex");
            ism_jw_uint(w, v);
            write_point(w, &a->vertices[v]);
            ism_jw_object_end(w);
        }
    }
    ism_jw_array_end(w);
}

void ism_features_cut_curves_json(ism_jw *w, const ism_mesh *m, const ism_arrangement *a,
                                  const ism_cut_fn *fns, double tol, int d)
{
    for (size_t c = 0; a && c < a->ncurves; c++) {
        const ism_arr_curve *cv = &a->curves[c];
        const ism_cut_fn *fn = &fns[cv->fn];
        /* the table in features.h: only the crease is thinned and rounded */
        int dc = fn->kind == ISM_CUT_CREASE ? d : -1;
        double tc = fn->kind == ISM_CUT_CREASE ? tol : 0;
        ism_jw_object(w);
        ism_jw_key(w, "kind");
        ism_jw_string(w, kind_names[fn->kind]);
        ism_jw_key(w, "source");
        ism_jw_int(w, fn->source);
        ism_jw_key(w, "index");
        ism_jw_int(w, fn->index);
        ism_jw_key(w, "closed");
        ism_jw_bool(w, cv->closed);
        ism_jw_key(w, "length");
        ism_jw_number(w, cv->length);
        ism_jw_key(w, "edges");
        ism_jw_array(w);
        for (size_t i = 0; i < a->nedges; i++)
            if (a->edges[i].curve == c)
                ism_jw_uint(w, i);
        ism_jw_array_end(w);
        if (tc > 0) {
            ism_jw_key(w, "tolerance");
            ism_jw_number(w, tc);
        }
        ism_jw_key(w, "arcs");
        ism_jw_array(w);
        for (size_t i = 0; i < a->nedges; i++)
            if (a->edges[i].curve == c)
                ism_features_chain_xyz(w, m, a->chain + a->edges[i].first, a->edges[i].count,
                                       tc, dc, true);
        ism_jw_array_end(w);
        write_ends(w, m, a, c);
        ism_jw_object_end(w);
    }
}

static void write_faces(ism_jw *w, const ism_arrangement *a)
{
    ism_jw_key(w, "faces");
    ism_jw_array(w);
    for (size_t f = 0; f < a->nfaces; f++) {
        const ism_arr_face *fc = &a->faces[f];
        ism_jw_object(w);
        ism_jw_key(w, "id");
        ism_jw_uint(w, f);
        ism_jw_key(w, "first_triangle");
        ism_jw_uint(w, fc->first);
        ism_jw_key(w, "triangles");
        ism_jw_uint(w, fc->ntris);
        ism_jw_key(w, "area");
        ism_jw_number(w, fc->area);
        ism_jw_key(w, "euler");
        ism_jw_int(w, fc->euler);
        ism_jw_key(w, "boundary");
        ism_jw_uint(w, fc->boundary);
        ism_jw_key(w, "component");
        ism_jw_uint(w, fc->component);
        ism_jw_object_end(w);
    }
    ism_jw_array_end(w);
}

void ism_features_arrangement_json(ism_jw *w, const ism_mesh *m, const ism_arrangement *a)
{
    ism_jw_object(w);
    ism_jw_key(w, "vertices");
    ism_jw_array(w);
    for (size_t i = 0; i < a->nvertices; i++) {
        ism_jw_object(w);
        write_vertex_xyz(w, m, a->vertices[i].v);
        ism_jw_key(w, "degree");
        ism_jw_int(w, a->vertices[i].degree);
        ism_jw_key(w, "type");
        ism_jw_string(w, vertex_types[a->vertices[i].type]);
        write_point(w, &a->vertices[i]);
        ism_jw_object_end(w);
    }
    ism_jw_array_end(w);
    ism_jw_key(w, "edges");
    ism_jw_array(w);
    for (size_t i = 0; i < a->nedges; i++) {
        ism_jw_object(w);
        ism_jw_key(w, "from");
        ism_jw_uint(w, a->edges[i].from);
        ism_jw_key(w, "to");
        ism_jw_uint(w, a->edges[i].to);
        ism_jw_key(w, "curve");
        ism_jw_uint(w, a->edges[i].curve);
        ism_jw_key(w, "length");
        ism_jw_number(w, a->edges[i].length);
        ism_jw_object_end(w);
    }
    ism_jw_array_end(w);
    write_faces(w, a);
    ism_jw_key(w, "components");
    ism_jw_uint(w, a->ncomponents);
    ism_jw_key(w, "euler");
    ism_jw_object(w);
    ism_jw_key(w, "mesh");
    ism_jw_int(w, a->euler_mesh);
    ism_jw_key(w, "arrangement");
    ism_jw_int(w, a->euler_arr);
    ism_jw_key(w, "ok");
    ism_jw_bool(w, a->euler_ok);
    ism_jw_object_end(w);
    ism_jw_object_end(w);
}
