/* mesh_files.c — the service's PLY (attributes as extra vertex properties, a crease's sides
 * on vertices of their own) and OBJ (features as `l` lines) of mesh_files.h, streamed through
 * core's sink. */
#include "proto/mesh_files.h"
#include "core/mesh/write_sink.h"

#include <stdlib.h>
#include <string.h>

/* A crease's other sides in PLY: the corners with a crease side's normal of their own
 * (w->corner_at, not marked in w->corner_locus) get vertices of their own, appended after the
 * mesh's (whose indices stay), one per vertex and distinct normal, so each side's triangles
 * stay joined and shade with their branch's normal. A vertex whose every corner has a normal
 * of its own (its own normal, ∇f, is not bit for bit either side's) lends its row to its
 * first side instead: no row of the file is left unused. The corners at the singular locus
 * with their sheet's normal (marked) stay on their vertex's row: the PLY's vertices are the
 * mesh's (the stats' count) wherever no crease is cut. */
typedef struct ply_sides {
    size_t n;             /* extra vertices */
    uint32_t *vertex;     /* per extra vertex: the mesh vertex it copies */
    const float **normal; /* per extra vertex: its normal (into w->corner_normal) */
    uint32_t *corner;     /* per corner with its own normal (as w->corner_at): its vertex */
    const float **row;    /* per mesh vertex: the normal its row carries when it lends it to
                             a side (NULL: its own) */
} ply_sides;

typedef struct side_key {
    uint32_t vertex, j; /* the mesh vertex, the corner's index in w->corner_at */
    const float *normal;
} side_key;

/* By vertex, then normal (bit for bit: one branch's normal at one vertex is one value). */
static int cmp_side(const void *x, const void *y)
{
    const side_key *a = x, *b = y;
    if (a->vertex != b->vertex)
        return a->vertex < b->vertex ? -1 : 1;
    return memcmp(a->normal, b->normal, 3 * sizeof *a->normal);
}

static void ply_sides_free(ply_sides *p)
{
    free(p->vertex);
    free((void *)p->normal);
    free(p->corner);
    free((void *)p->row);
}

/* Whether entry j of w->corner_at is a crease side's (the PLY gives it a vertex of its own). */
static bool crease_side(const ism_wire_mesh *w, size_t j)
{
    return !w->corner_locus || !w->corner_locus[j];
}

/* Per mesh vertex: 1 when a corner without a crease side's normal uses it (calloc'd; NULL
 * when out of memory). */
static uint8_t *plain_corners(const ism_mesh *m, const ism_wire_mesh *w, size_t nc)
{
    uint8_t *plain = calloc(m->nverts + 1, 1);
    for (size_t c = 0, j = 0; plain && c < 3 * m->ntris; c++) {
        if (j < nc && w->corner_at[j] == c && crease_side(w, j++))
            continue;
        plain[m->tri[c]] = 1;
    }
    return plain;
}

static bool ply_sides_build(const ism_mesh *m, const ism_wire_mesh *w, ply_sides *p)
{
    size_t nc = w->normal ? w->ncorner_normals : 0;
    memset(p, 0, sizeof *p);
    if (!nc)
        return true;
    side_key *key = malloc(nc * sizeof *key);
    p->vertex = malloc(nc * sizeof *p->vertex);
    p->normal = malloc(nc * sizeof *p->normal);
    p->corner = malloc(nc * sizeof *p->corner);
    p->row = calloc(m->nverts + 1, sizeof *p->row);
    uint8_t *plain = plain_corners(m, w, nc);
    if (!key || !p->vertex || !p->normal || !p->corner || !p->row || !plain) {
        free(key);
        free(plain);
        ply_sides_free(p);
        return false;
    }
    size_t nk = 0;
    for (size_t j = 0; j < nc; j++)
        if (crease_side(w, j))
            key[nk++] = (side_key){m->tri[w->corner_at[j]], (uint32_t)j, w->corner_normal + 3 * j};
    qsort(key, nk, sizeof *key, cmp_side);
    uint32_t at = 0;
    for (size_t i = 0; i < nk; i++) {
        uint32_t v = key[i].vertex;
        if (i && !cmp_side(&key[i], &key[i - 1])) {
            p->corner[key[i].j] = at;
        } else if (!plain[v] && !p->row[v]) { /* the vertex's own row, unused otherwise */
            p->row[v] = key[i].normal;
            p->corner[key[i].j] = at = v;
        } else {
            p->vertex[p->n] = v;
            p->normal[p->n++] = key[i].normal;
            p->corner[key[i].j] = at = (uint32_t)(m->nverts + p->n - 1);
        }
    }
    free(key);
    free(plain);
    return true;
}

static void ply_header(ism_sink *s, const ism_mesh *m, const ism_wire_mesh *w, size_t extra)
{
    ism_sink_printf(s, "ply\nformat binary_little_endian 1.0\ncomment isomesh\n"
                       "element vertex %zu\n"
                       "property float x\nproperty float y\nproperty float z\n",
                    m->nverts + extra);
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

/* Faces (a crease's other-side corners on their own vertices) with their labels (cell,
 * double sheet) as face properties. */
static void ply_faces(ism_sink *s, const ism_mesh *m, const ism_wire_mesh *w,
                      const ply_sides *sides)
{
    if (!w->tri_cell && !w->tri_sheet && !sides->n) {
        ism_ply_put_faces(s, m);
        return;
    }
    size_t j = 0; /* the next corner with a normal of its own */
    for (size_t t = 0; t < m->ntris; t++) {
        ism_sink_u8(s, 3);
        for (size_t c = 3 * t; c < 3 * t + 3; c++) {
            bool own = sides->n && j < w->ncorner_normals && w->corner_at[j] == c;
            ism_sink_u32le(s, own && crease_side(w, j) ? sides->corner[j] : m->tri[c]);
            j += own;
        }
        if (w->tri_cell)
            ism_sink_u32le(s, w->tri_cell[t]);
        if (w->tri_sheet)
            ism_sink_u8(s, w->tri_sheet[t]);
    }
}

/* One vertex row: mesh vertex i's position and attributes, with normal n (NULL: none). */
static void ply_vertex(ism_sink *s, const ism_mesh *m, const ism_wire_mesh *w, size_t i,
                       const float *n)
{
    for (int k = 0; k < 3; k++)
        ism_sink_f32le(s, (float)m->pos[3 * i + k]);
    for (int k = 0; n && k < 3; k++)
        ism_sink_f32le(s, n[k]);
    if (w->mean_curvature)
        ism_sink_f32le(s, w->mean_curvature[i]);
    if (w->gauss_curvature)
        ism_sink_f32le(s, w->gauss_curvature[i]);
    if (w->vertex_class)
        ism_sink_u8(s, w->vertex_class[i]);
}

bool ism_write_ply_wire(const ism_mesh *m, const ism_wire_mesh *w, ism_write_fn write,
                        void *ctx)
{
    ply_sides sides;
    if (w->nverts != m->nverts || !ply_sides_build(m, w, &sides))
        return false;
    ism_sink *s = m->nverts + sides.n <= INT32_MAX ? malloc(sizeof *s) : NULL;
    if (!s) { /* PLY's int indices could not address every vertex, or out of memory */
        ply_sides_free(&sides);
        return false;
    }
    ism_sink_init(s, write, ctx);
    ply_header(s, m, w, sides.n);
    for (size_t i = 0; i < m->nverts; i++)
        ply_vertex(s, m, w, i,
                   sides.row && sides.row[i] ? sides.row[i] : w->normal ? w->normal + 3 * i : NULL);
    for (size_t i = 0; i < sides.n; i++)
        ply_vertex(s, m, w, sides.vertex[i], sides.normal[i]);
    ply_faces(s, m, w, &sides);
    bool ok = ism_sink_finish(s);
    free(s);
    ply_sides_free(&sides);
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
