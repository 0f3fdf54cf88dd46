/* mesh_files.c — the service's PLY (attributes as extra vertex properties, one row per mesh
 * vertex, a crease vertex's sides' normals summed) and OBJ (features as `l` lines) of
 * mesh_files.h, streamed through core's sink. */
#include "proto/mesh_files.h"
#include "core/mesh/write_sink.h"
#include "core/util/vec3.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

typedef struct side_key {
    uint32_t vertex;     /* the mesh vertex */
    const float *normal; /* a crease side's normal there (into w->corner_normal) */
} side_key;

/* By vertex, then normal (bit for bit: one branch's normal at one vertex is one value). */
static int cmp_side(const void *x, const void *y)
{
    const side_key *a = x, *b = y;
    if (a->vertex != b->vertex)
        return a->vertex < b->vertex ? -1 : 1;
    return memcmp(a->normal, b->normal, 3 * sizeof *a->normal);
}

/* Whether entry j of w->corner_at is a crease side's (not the locus's sheet normal). */
static bool crease_side(const ism_wire_mesh *w, size_t j)
{
    return !w->corner_locus || !w->corner_locus[j];
}

/* Per mesh vertex: 1 when a corner without a crease side's normal uses it (calloc'd; NULL
 * when out of memory): the vertex's own normal is then one of its sides'. */
static uint8_t *plain_corners(const ism_mesh *m, const ism_wire_mesh *w, size_t nc)
{
    uint8_t *plain = calloc(m->nverts + 1, 1);
    for (size_t c = 0, j = 0; plain && c < 3 * m->ntris; c++) {
        bool side = j < nc && w->corner_at[j] == c && crease_side(w, j);
        j += j < nc && w->corner_at[j] == c;
        if (!side)
            plain[m->tri[c]] = 1;
    }
    return plain;
}

/* The row normal n of a vertex whose crease-side corners are k[0..nk) (sorted, so one side's
 * bit-equal normals are adjacent): the sum of its distinct sides' normals and own (the
 * vertex's, NULL when no plain corner uses it), normalised; n is left as it is when they
 * cancel. */
static void sum_sides(const side_key *k, size_t nk, const float *own, float *n)
{
    double s[3] = {0, 0, 0};
    for (int a = 0; own && a < 3; a++)
        s[a] = own[a];
    for (size_t i = 0; i < nk; i++)
        if (!i || cmp_side(&k[i], &k[i - 1]))
            for (int a = 0; a < 3; a++)
                s[a] += k[i].normal[a];
    double len = ism_norm3(s);
    if (len > 0 && isfinite(len))
        for (int a = 0; a < 3; a++)
            n[a] = (float)(s[a] / len);
}

/* A crease vertex in PLY: one row per mesh vertex (the file's vertices, edges and faces are the
 * mesh's, so a reader counting components or χ gets the stats' figures; the per-side normals
 * travel in drc/glb, split there, and in the OBJ's `vn`), with one normal for every side that
 * meets there: the normalised sum of the sides' unit normals — each side once (its branch's
 * normal, and the vertex's own, ∇f, when a corner that no crease side claims uses it), not
 * per corner or area, so the number of triangles a side happens to have there does not tilt
 * it. Why the sum and not ∇f: at a crease f is not differentiable, ∇f is the branch the
 * evaluator's tie took (right on one side, off by the whole crease angle on the other, and a
 * vertex whose corners are all crease sides has a ∇f that neither side's triangles use); the
 * sum bisects two sides (each off by half the crease angle, the usual normal of a
 * polyhedral edge) and points into a cube's corner between three. Where the sides cancel
 * (a fin folded back on itself) the row keeps ∇f. The corners at the singular locus with their
 * sheet's normal (w->corner_locus) are not sides: their vertex's row is ∇f's, as without them.
 * Returns per vertex the normal its row carries: w->normal itself when no crease side is cut
 * (or no normals are sent), else a copy with the crease vertices' rows summed, also in *owned
 * for the caller to free (NULL when out of memory). */
static const float *ply_row_normals(const ism_mesh *m, const ism_wire_mesh *w, float **owned)
{
    size_t nc = w->normal ? w->ncorner_normals : 0, nk = 0;
    *owned = NULL;
    for (size_t j = 0; j < nc; j++)
        nk += crease_side(w, j);
    if (!nk)
        return w->normal;
    side_key *key = malloc(nk * sizeof *key);
    float *row = malloc(3 * m->nverts * sizeof *row);
    uint8_t *plain = plain_corners(m, w, nc);
    if (!key || !row || !plain) {
        free(key);
        free(row);
        free(plain);
        return NULL;
    }
    memcpy(row, w->normal, 3 * m->nverts * sizeof *row);
    nk = 0;
    for (size_t j = 0; j < nc; j++)
        if (crease_side(w, j))
            key[nk++] = (side_key){m->tri[w->corner_at[j]], w->corner_normal + 3 * j};
    qsort(key, nk, sizeof *key, cmp_side);
    for (size_t i = 0, e; i < nk; i = e) {
        uint32_t v = key[i].vertex;
        for (e = i + 1; e < nk && key[e].vertex == v; e++)
            ;
        sum_sides(key + i, e - i, plain[v] ? w->normal + 3 * (size_t)v : NULL, row + 3 * v);
    }
    free(key);
    free(plain);
    return *owned = row;
}

static void ply_header(ism_sink *s, const ism_mesh *m, const ism_wire_mesh *w)
{
    ism_sink_printf(s, "ply\nformat binary_little_endian 1.0\ncomment isomesh\n"
                       "element vertex %zu\n"
                       "property float x\nproperty float y\nproperty float z\n",
                    m->nverts);
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

/* The mesh's faces with their labels (cell, double sheet) as face properties. */
static void ply_faces(ism_sink *s, const ism_mesh *m, const ism_wire_mesh *w)
{
    if (!w->tri_cell && !w->tri_sheet) {
        ism_ply_put_faces(s, m);
        return;
    }
    for (size_t t = 0; t < m->ntris; t++) {
        ism_sink_u8(s, 3);
        for (size_t c = 3 * t; c < 3 * t + 3; c++)
            ism_sink_u32le(s, m->tri[c]);
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
    if (w->nverts != m->nverts || m->nverts > INT32_MAX)
        return false; /* PLY's int indices could not address every vertex */
    float *owned;
    const float *row = ply_row_normals(m, w, &owned);
    ism_sink *s = !w->normal || row ? malloc(sizeof *s) : NULL;
    if (!s) {
        free(owned);
        return false;
    }
    ism_sink_init(s, write, ctx);
    ply_header(s, m, w);
    for (size_t i = 0; i < m->nverts; i++)
        ply_vertex(s, m, w, i, row ? row + 3 * i : NULL);
    ply_faces(s, m, w);
    bool ok = ism_sink_finish(s);
    free(s);
    free(owned);
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

/* As cmp_side, then by entry (the normal's place in w->corner_normal). */
static int cmp_side_entry(const void *x, const void *y)
{
    const side_key *a = x, *b = y;
    int c = cmp_side(a, b);
    return c ? c : (a->normal > b->normal) - (a->normal < b->normal);
}

/* The OBJ's corner normals, each distinct (vertex, normal) once: corners of one vertex with
 * bit-equal normals (one half-sheet at the singular locus, one crease side) share one `vn`,
 * as they share one point in drc/glb (corner_split.c). Listed in order of first use, so a
 * file without such repeats is the one-`vn`-per-corner file. cn's which and normal are
 * malloc'd (the caller frees them); false when out of memory. */
static bool obj_distinct_normals(const ism_mesh *m, const ism_wire_mesh *w,
                                 ism_obj_corner_normals *cn)
{
    size_t n = w->ncorner_normals, k = 0;
    side_key *key = malloc(n * sizeof *key);
    uint32_t *first = malloc(n * sizeof *first), *which = malloc(n * sizeof *which);
    float *normal = malloc(3 * n * sizeof *normal);
    bool ok = key && first && which && normal;
    for (size_t j = 0; ok && j < n; j++)
        key[j] = (side_key){m->tri[w->corner_at[j]], w->corner_normal + 3 * j};
    if (ok)
        qsort(key, n, sizeof *key, cmp_side_entry);
    for (size_t i = 0, e; ok && i < n; i = e) { /* a run's head is its first entry */
        uint32_t head = (uint32_t)((key[i].normal - w->corner_normal) / 3);
        for (e = i; e < n && !cmp_side(&key[e], &key[i]); e++)
            first[(key[e].normal - w->corner_normal) / 3] = head;
    }
    for (size_t j = 0; ok && j < n; j++) {
        if (first[j] == j) {
            memcpy(normal + 3 * k, w->corner_normal + 3 * j, 3 * sizeof *normal);
            which[j] = (uint32_t)k++;
        } else {
            which[j] = which[first[j]];
        }
    }
    free(key);
    free(first);
    if (!ok) {
        free(which);
        free(normal);
        return false;
    }
    *cn = (ism_obj_corner_normals){n, w->corner_at, normal, which, k};
    return true;
}

bool ism_write_obj_features(const ism_mesh *m, const ism_wire_mesh *w, const ism_features *f,
                            ism_write_fn write, void *ctx)
{
    ism_obj_corner_normals cn = {0, NULL, NULL, NULL, 0};
    if (w && w->ncorner_normals && !obj_distinct_normals(m, w, &cn))
        return false;
    bool written = ism_write_obj_corners(m, &cn, write, ctx);
    free((void *)cn.which);
    free((void *)cn.normal);
    if (!written)
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
