/* mesh_files.c — the service's PLY (attributes as extra vertex properties) and OBJ (features
 * as `l` lines) of mesh_files.h, streamed through core's sink. */
#include "proto/mesh_files.h"
#include "core/mesh/write_sink.h"

#include <stdlib.h>

static void ply_header(ism_sink *s, const ism_mesh *m, const ism_wire_mesh *w)
{
    ism_sink_printf(s, "ply\nformat binary_little_endian 1.0\ncomment isomesh\n"
                       "element vertex %zu\n"
                       "property float x\nproperty float y\nproperty float z\n", m->nverts);
    if (w->normal)
        ism_sink_printf(s, "property float nx\nproperty float ny\nproperty float nz\n");
    if (w->mean_curvature)
        ism_sink_printf(s, "property float mean_curvature\n");
    if (w->gauss_curvature)
        ism_sink_printf(s, "property float gauss_curvature\n");
    if (w->vertex_class)
        ism_sink_printf(s, "property uchar class\n");
    ism_sink_printf(s, "element face %zu\nproperty list uchar int vertex_indices\n", m->ntris);
    if (w->tri_cell)
        ism_sink_printf(s, "property uint cell\n");
    if (w->tri_sheet)
        ism_sink_printf(s, "property uchar double_sheet\n");
    ism_sink_printf(s, "end_header\n");
}

/* Faces with their labels (cell, double sheet) as face properties. */
static void ply_faces(ism_sink *s, const ism_mesh *m, const ism_wire_mesh *w)
{
    if (!w->tri_cell && !w->tri_sheet) {
        ism_ply_put_faces(s, m);
        return;
    }
    for (size_t t = 0; t < m->ntris; t++) {
        ism_sink_u8(s, 3);
        for (int k = 0; k < 3; k++)
            ism_sink_u32le(s, m->tri[3 * t + k]);
        if (w->tri_cell)
            ism_sink_u32le(s, w->tri_cell[t]);
        if (w->tri_sheet)
            ism_sink_u8(s, w->tri_sheet[t]);
    }
}

bool ism_write_ply_wire(const ism_mesh *m, const ism_wire_mesh *w, ism_write_fn write,
                        void *ctx)
{
    if (m->nverts > INT32_MAX || w->nverts != m->nverts)
        return false; /* PLY's int indices could not address every vertex */
    ism_sink *s = malloc(sizeof *s);
    if (!s)
        return false;
    ism_sink_init(s, write, ctx);
    ply_header(s, m, w);
    for (size_t i = 0; i < m->nverts; i++) {
        for (int k = 0; k < 3; k++)
            ism_sink_f32le(s, (float)m->pos[3 * i + k]);
        for (int k = 0; w->normal && k < 3; k++)
            ism_sink_f32le(s, w->normal[3 * i + k]);
        if (w->mean_curvature)
            ism_sink_f32le(s, w->mean_curvature[i]);
        if (w->gauss_curvature)
            ism_sink_f32le(s, w->gauss_curvature[i]);
        if (w->vertex_class)
            ism_sink_u8(s, w->vertex_class[i]);
    }
    ply_faces(s, m, w);
    bool ok = ism_sink_finish(s);
    free(s);
    return ok;
}

static void obj_lines(ism_sink *s, const char *group, const ism_polylines *p)
{
    if (!p->n)
        return;
    ism_sink_printf(s, "g %s\n", group);
    for (size_t c = 0; c < p->n; c++) {
        if (p->start[c + 1] - p->start[c] < 2)
            continue;
        ism_sink_printf(s, "l");
        for (uint32_t j = p->start[c]; j < p->start[c + 1]; j++)
            ism_sink_printf(s, " %u", p->verts[j] + 1);
        ism_sink_printf(s, "\n");
    }
}

/* The requested curves, one group per kind ("section_curves", ...), one `l` per arc. */
static void obj_cut_curves(ism_sink *s, const ism_features *f)
{
    const ism_polylines *a = &f->arcs;
    for (int k = 0; k < ISM_CUT_KIND_COUNT; k++) {
        bool named = false;
        for (size_t i = 0; i < a->n; i++) {
            if (f->arc_kind[i] != k || a->start[i + 1] - a->start[i] < 2)
                continue;
            if (!named)
                ism_sink_printf(s, "g %s_curves\n", ism_cut_kind_name(k));
            named = true;
            ism_sink_printf(s, "l");
            for (uint32_t j = a->start[i]; j < a->start[i + 1]; j++)
                ism_sink_printf(s, " %u", a->verts[j] + 1);
            ism_sink_printf(s, "\n");
        }
    }
}

bool ism_write_obj_features(const ism_mesh *m, const ism_wire_mesh *w, const ism_features *f,
                            ism_write_fn write, void *ctx)
{
    ism_obj_corner_normals cn = {0, NULL, NULL};
    if (w && w->ncorner_normals)
        cn = (ism_obj_corner_normals){w->ncorner_normals, w->corner_at, w->corner_normal};
    if (!ism_write_obj_corners(m, &cn, write, ctx))
        return false;
    if (!f)
        return true;
    ism_sink *s = malloc(sizeof *s);
    if (!s)
        return false;
    ism_sink_init(s, write, ctx);
    obj_lines(s, "nonmanifold_curves", &f->curves);
    obj_lines(s, "boundaries", &f->boundaries);
    obj_cut_curves(s, f);
    bool ok = ism_sink_finish(s);
    free(s);
    return ok;
}
