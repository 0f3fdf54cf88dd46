/* glb.c — writes the .glb container by hand: a JSON chunk (built with the JSON writer) and a
 * BIN chunk holding the Draco bitstream followed by the uncompressed feature arrays, every
 * bufferView 4-byte aligned, chunks padded as the spec asks (JSON with spaces, BIN with
 * zeros). */
#include "proto/glb.h"
#include "proto/corner_split.h"
#include "core/util/le_bytes.h"
#include "proto/json_writer.h"
#include "core/version.h"

#include <math.h>
#include <stdio.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

enum { GL_POINTS = 0, GL_LINES = 1, GL_TRIANGLES = 4 };
enum { CT_UBYTE = 5121, CT_USHORT = 5123, CT_UINT = 5125, CT_FLOAT = 5126 };
enum { TARGET_ARRAY = 34962, TARGET_ELEMENTS = 34963 };

/* The BIN chunk under construction. */
typedef struct bin {
    unsigned char *data;
    size_t len, cap;
    bool failed;
} bin;

static size_t bin_append(bin *b, const void *p, size_t n)
{
    size_t at = (b->len + 3) & ~(size_t)3;
    if (b->failed)
        return 0;
    if (at + n > b->cap) {
        size_t c = b->cap ? b->cap : 4096;
        while (c < at + n)
            c *= 2;
        unsigned char *d = realloc(b->data, c);
        if (!d) {
            b->failed = true;
            return 0;
        }
        b->data = d;
        b->cap = c;
    }
    memset(b->data + b->len, 0, at - b->len);
    if (n)
        memcpy(b->data + at, p, n);
    b->len = at + n;
    return at;
}

/* The JSON arrays are written in separate writers and joined at the end, because accessors
 * and bufferViews are discovered while walking the primitives. */
typedef struct gltf {
    ism_jw accessors, views, meshes, nodes;
    int naccessors, nviews, nmeshes, nnodes;
    bin bin;
} gltf;

static int add_view(gltf *g, size_t offset, size_t length, int target, int stride)
{
    ism_jw *w = &g->views;
    ism_jw_object(w);
    ism_jw_key(w, "buffer");
    ism_jw_int(w, 0);
    ism_jw_key(w, "byteOffset");
    ism_jw_uint(w, offset);
    ism_jw_key(w, "byteLength");
    ism_jw_uint(w, length);
    if (stride) {
        ism_jw_key(w, "byteStride");
        ism_jw_int(w, stride);
    }
    if (target) {
        ism_jw_key(w, "target");
        ism_jw_int(w, target);
    }
    ism_jw_object_end(w);
    return g->nviews++;
}

/* An accessor; view < 0 for one whose data lives in the Draco stream. bounds (6) for
 * POSITION accessors, else NULL. */
static int add_accessor(gltf *g, int view, int ctype, size_t count, const char *type,
                        const double *bounds)
{
    ism_jw *w = &g->accessors;
    ism_jw_object(w);
    if (view >= 0) {
        ism_jw_key(w, "bufferView");
        ism_jw_int(w, view);
    }
    ism_jw_key(w, "componentType");
    ism_jw_int(w, ctype);
    ism_jw_key(w, "count");
    ism_jw_uint(w, count);
    ism_jw_key(w, "type");
    ism_jw_string(w, type);
    if (bounds) {
        ism_jw_key(w, "min");
        ism_jw_array(w);
        for (int k = 0; k < 3; k++)
            ism_jw_float(w, (float)bounds[k]);
        ism_jw_array_end(w);
        ism_jw_key(w, "max");
        ism_jw_array(w);
        for (int k = 0; k < 3; k++)
            ism_jw_float(w, (float)bounds[k + 3]);
        ism_jw_array_end(w);
    }
    ism_jw_object_end(w);
    return g->naccessors++;
}

static void add_node(gltf *g, const char *name, int mesh, const ism_jw *extras_src)
{
    ism_jw *w = &g->nodes;
    ism_jw_object(w);
    ism_jw_key(w, "name");
    ism_jw_string(w, name);
    ism_jw_key(w, "mesh");
    ism_jw_int(w, mesh);
    if (extras_src && extras_src->data) {
        ism_jw_key(w, "extras");
        ism_jw_raw(w, extras_src->data, extras_src->len);
    }
    ism_jw_object_end(w);
    g->nnodes++;
}

/* The surface's mesh up to its primitive's attributes (acc[i] < 0: not sent); the caller may
 * add members to the open primitive, then calls close_surface. */
enum { NSURF = 7 };
static const char *const SURFACE_ATTRIBUTES[NSURF] = {
    "POSITION", "NORMAL", "_MEAN_CURVATURE", "_GAUSS_CURVATURE", "_CLASS", "_CELL",
    "_DOUBLE_SHEET"};

static ism_jw *open_surface(gltf *g, int indices, const int acc[NSURF])
{
    ism_jw *w = &g->meshes;
    ism_jw_object(w);
    ism_jw_key(w, "name");
    ism_jw_string(w, "surface");
    ism_jw_key(w, "primitives");
    ism_jw_array(w);
    ism_jw_object(w);
    ism_jw_key(w, "mode");
    ism_jw_int(w, GL_TRIANGLES);
    ism_jw_key(w, "material");
    ism_jw_int(w, 0);
    ism_jw_key(w, "indices");
    ism_jw_int(w, indices);
    ism_jw_key(w, "attributes");
    ism_jw_object(w);
    for (int i = 0; i < NSURF; i++)
        if (acc[i] >= 0) {
            ism_jw_key(w, SURFACE_ATTRIBUTES[i]);
            ism_jw_int(w, acc[i]);
        }
    ism_jw_object_end(w);
    return w;
}

static void close_surface(gltf *g)
{
    ism_jw *w = &g->meshes;
    ism_jw_object_end(w);
    ism_jw_array_end(w);
    ism_jw_object_end(w);
    add_node(g, "surface", g->nmeshes++, NULL);
}

/* The Draco primitive of the surface. */
static void add_surface(gltf *g, const ism_wire_mesh *wm, const ism_draco_output *d)
{
    size_t off = bin_append(&g->bin, d->data, d->len);
    int view = add_view(g, off, d->len, 0, 0);
    struct {
        const char *name;
        bool present;
        int id, ctype;
        const char *type;
    } atts[] = {
        {"POSITION", true, ISM_DRACO_ID_POSITION, CT_FLOAT, "VEC3"},
        {"NORMAL", wm->normal != NULL, ISM_DRACO_ID_NORMAL, CT_FLOAT, "VEC3"},
        {"_MEAN_CURVATURE", wm->mean_curvature != NULL, ISM_DRACO_ID_MEAN_CURVATURE, CT_FLOAT,
         "SCALAR"},
        {"_GAUSS_CURVATURE", wm->gauss_curvature != NULL, ISM_DRACO_ID_GAUSS_CURVATURE,
         CT_FLOAT, "SCALAR"},
        {"_CLASS", wm->vertex_class != NULL, ISM_DRACO_ID_CLASS, CT_UBYTE, "SCALAR"},
        /* uint32 in the Draco stream; read as float (exact below 2^24 cells), since glTF
         * allows unsigned int only for indices */
        {"_CELL", wm->tri_cell != NULL, ISM_DRACO_ID_CELL, CT_FLOAT, "SCALAR"},
        {"_DOUBLE_SHEET", wm->tri_sheet != NULL, ISM_DRACO_ID_DOUBLE_SHEET, CT_UBYTE, "SCALAR"},
    };
    int acc[NSURF];
    for (int i = 0; i < NSURF; i++)
        acc[i] = atts[i].present ? add_accessor(g, -1, atts[i].ctype, d->points, atts[i].type,
                                                i == 0 ? wm->bounds : NULL)
                                 : -1;
    int indices = add_accessor(g, -1, d->points > 65535 ? CT_UINT : CT_USHORT, 3 * d->faces,
                               "SCALAR", NULL);
    ism_jw *w = open_surface(g, indices, acc);
    ism_jw_key(w, "extensions");
    ism_jw_object(w);
    ism_jw_key(w, "KHR_draco_mesh_compression");
    ism_jw_object(w);
    ism_jw_key(w, "bufferView");
    ism_jw_int(w, view);
    ism_jw_key(w, "attributes");
    ism_jw_object(w);
    for (int i = 0; i < NSURF; i++)
        if (atts[i].present) {
            ism_jw_key(w, atts[i].name);
            ism_jw_int(w, atts[i].id);
        }
    ism_jw_object_end(w);
    ism_jw_object_end(w);
    ism_jw_object_end(w);
    close_surface(g);
}

/* A vertex attribute of the plain surface as its own bufferView and accessor. */
static int plain_attribute(gltf *g, const void *data, size_t bytes, size_t count, int ctype,
                           const char *type, const double *bounds)
{
    size_t off = bin_append(&g->bin, data, bytes);
    return add_accessor(g, add_view(g, off, bytes, TARGET_ARRAY, 0), ctype, count, type, bounds);
}

/* One byte per vertex: glTF wants vertex attributes 4-byte aligned, so each byte gets its own
 * 4-byte slot (byteStride 4). -1 when out of memory. */
static int plain_bytes(gltf *g, const uint8_t *data, size_t count)
{
    uint8_t *wide = calloc(count ? count : 1, 4);
    if (!wide)
        return -1;
    for (size_t i = 0; i < count; i++)
        wide[4 * i] = data[i];
    size_t off = bin_append(&g->bin, wide, 4 * count);
    free(wide);
    return add_accessor(g, add_view(g, off, 4 * count, TARGET_ARRAY, 4), CT_UBYTE, count,
                        "SCALAR", NULL);
}

/* The plain surface's vertices: the wire's, or points split along the triangle labels
 * (corner_split.h) with every per-vertex array copied out per point. */
typedef struct plain_points {
    size_t n;
    const uint32_t *tri;
    const float *f32[4];        /* pos, normal, mean, gauss (3, 3, 1, 1 per point) */
    const uint8_t *cls, *sheet;
    float *cell;                /* the cell id as float (glTF: no unsigned int attributes) */
    ism_corner_split split;
    void *owned[6];
} plain_points;

static const int F32_COMPONENTS[4] = {3, 3, 1, 1};

static void plain_points_free(plain_points *pp)
{
    for (int i = 0; i < 6; i++)
        free(pp->owned[i]);
    free(pp->cell);
    ism_corner_split_free(&pp->split);
}

static bool plain_points_build(const ism_wire_mesh *wm, plain_points *pp)
{
    memset(pp, 0, sizeof *pp);
    const float *src[4] = {wm->pos, wm->normal, wm->mean_curvature, wm->gauss_curvature};
    if (!ism_corner_split_needed(wm)) {
        pp->n = wm->nverts;
        pp->tri = wm->tri;
        memcpy(pp->f32, src, sizeof src);
        pp->cls = wm->vertex_class;
        return true;
    }
    ism_corner_split *sp = &pp->split;
    if (!ism_corner_split_build(wm, sp))
        return false;
    pp->n = sp->npoints;
    pp->tri = sp->tri;
    pp->sheet = sp->point_sheet;
    if (sp->point_normal)
        src[1] = NULL; /* a crease's sides: the split's per-point normals, below */
    for (int i = 0; i < 4; i++) {
        if (!src[i])
            continue;
        int c = F32_COMPONENTS[i];
        float *d = pp->owned[i] = malloc((pp->n ? pp->n : 1) * (size_t)c * sizeof *d);
        if (!d)
            return false;
        for (size_t p = 0; p < pp->n; p++)
            memcpy(d + (size_t)c * p, src[i] + (size_t)c * sp->point_vertex[p], c * sizeof *d);
        pp->f32[i] = d;
    }
    if (sp->point_normal)
        pp->f32[1] = sp->point_normal;
    if (wm->vertex_class) {
        uint8_t *d = pp->owned[4] = malloc(pp->n ? pp->n : 1);
        if (!d)
            return false;
        for (size_t p = 0; p < pp->n; p++)
            d[p] = wm->vertex_class[sp->point_vertex[p]];
        pp->cls = d;
    }
    if (sp->point_cell) {
        pp->cell = malloc((pp->n ? pp->n : 1) * sizeof *pp->cell);
        if (!pp->cell)
            return false;
        for (size_t p = 0; p < pp->n; p++)
            pp->cell[p] = (float)sp->point_cell[p];
    }
    return true;
}

/* The surface without Draco: plain accessors for every attribute sent and uint32 indices of
 * the triangles with three distinct vertices (as Draco keeps them). */
static bool add_plain_surface(gltf *g, const ism_wire_mesh *wm)
{
    plain_points pp;
    uint32_t *idx = malloc((wm->live_triangles ? wm->live_triangles : 1) * 3 * sizeof *idx);
    if (!plain_points_build(wm, &pp) || !idx) {
        plain_points_free(&pp);
        free(idx);
        return false;
    }
    size_t ni = 0;
    for (size_t t = 0; t < wm->ntris; t++) {
        const uint32_t *v = wm->tri + 3 * t; /* liveness is the vertices' */
        if (v[0] != v[1] && v[1] != v[2] && v[0] != v[2])
            for (int k = 0; k < 3; k++)
                idx[ni++] = pp.tri[3 * t + k];
    }
    size_t n = pp.n;
    int acc[NSURF];
    acc[4] = pp.cls ? plain_bytes(g, pp.cls, n) : -1;
    acc[6] = pp.sheet ? plain_bytes(g, pp.sheet, n) : -1;
    for (int i = 0; i < 4; i++)
        acc[i] = pp.f32[i] ? plain_attribute(g, pp.f32[i], n * F32_COMPONENTS[i] * sizeof(float),
                                             n, CT_FLOAT, F32_COMPONENTS[i] == 3 ? "VEC3" : "SCALAR",
                                             i == 0 ? wm->bounds : NULL)
                           : -1;
    acc[5] = pp.cell ? plain_attribute(g, pp.cell, n * sizeof(float), n, CT_FLOAT, "SCALAR", NULL)
                     : -1;
    size_t ioff = bin_append(&g->bin, idx, ni * sizeof *idx);
    int indices = add_accessor(g, add_view(g, ioff, ni * sizeof *idx, TARGET_ELEMENTS, 0), CT_UINT,
                               ni, "SCALAR", NULL);
    free(idx);
    plain_points_free(&pp);
    open_surface(g, indices, acc);
    close_surface(g);
    return !g->bin.failed;
}

/* One uncompressed primitive: nv float positions (3 each) and, for LINES, nidx indices (two
 * per segment). Takes neither array. */
static bool emit_primitive(gltf *g, const char *name, int mode, int material, const float *pos,
                           size_t nv, const uint32_t *idx, size_t nidx, const ism_jw *extras)
{
    if (nv == 0 || (mode == GL_LINES && nidx == 0))
        return true; /* nothing to draw */
    double bounds[6] = {INFINITY, INFINITY, INFINITY, -INFINITY, -INFINITY, -INFINITY};
    for (size_t i = 0; i < nv; i++)
        for (int k = 0; k < 3; k++) {
            bounds[k] = fmin(bounds[k], pos[3 * i + k]);
            bounds[k + 3] = fmax(bounds[k + 3], pos[3 * i + k]);
        }
    size_t poff = bin_append(&g->bin, pos, nv * 3 * sizeof *pos);
    int pacc = add_accessor(g, add_view(g, poff, nv * 3 * sizeof *pos, TARGET_ARRAY, 0), CT_FLOAT,
                            nv, "VEC3", bounds);
    int iacc = -1;
    if (nidx) {
        size_t ioff = bin_append(&g->bin, idx, nidx * sizeof *idx);
        iacc = add_accessor(g, add_view(g, ioff, nidx * sizeof *idx, TARGET_ELEMENTS, 0), CT_UINT,
                            nidx, "SCALAR", NULL);
    }
    ism_jw *w = &g->meshes;
    ism_jw_object(w);
    ism_jw_key(w, "name");
    ism_jw_string(w, name);
    ism_jw_key(w, "primitives");
    ism_jw_array(w);
    ism_jw_object(w);
    ism_jw_key(w, "mode");
    ism_jw_int(w, mode);
    ism_jw_key(w, "material");
    ism_jw_int(w, material);
    ism_jw_key(w, "attributes");
    ism_jw_object(w);
    ism_jw_key(w, "POSITION");
    ism_jw_int(w, pacc);
    ism_jw_object_end(w);
    if (iacc >= 0) {
        ism_jw_key(w, "indices");
        ism_jw_int(w, iacc);
    }
    ism_jw_object_end(w);
    ism_jw_array_end(w);
    ism_jw_object_end(w);
    add_node(g, name, g->nmeshes++, extras);
    return !g->bin.failed;
}

/* One uncompressed primitive from polylines (LINES) or single vertices (POINTS) of the mesh. */
static bool add_feature_primitive(gltf *g, const ism_mesh *m, const char *name, int mode,
                                  int material, const ism_polylines *lines,
                                  const uint32_t *points, size_t npoints, const ism_jw *extras)
{
    size_t nv = lines ? (lines->n ? lines->start[lines->n] : 0) : npoints;
    if (nv == 0)
        return true;
    float *pos = malloc(nv * 3 * sizeof *pos);
    uint32_t *idx = lines ? malloc(2 * nv * sizeof *idx) : NULL;
    bool ok = pos && (!lines || idx);
    const uint32_t *verts = lines ? lines->verts : points;
    for (size_t i = 0; ok && i < nv; i++)
        for (int k = 0; k < 3; k++)
            pos[3 * i + k] = (float)m->pos[3 * (size_t)verts[i] + k];
    size_t nidx = 0;
    if (ok && lines)
        for (size_t c = 0; c < lines->n; c++)
            for (uint32_t j = lines->start[c]; j + 1 < lines->start[c + 1]; j++) {
                idx[nidx++] = j;
                idx[nidx++] = j + 1;
            }
    ok = ok && emit_primitive(g, name, mode, material, pos, nv, idx, nidx, extras);
    free(pos);
    free(idx);
    return ok;
}

/* The singular points of the locus as POINTS, their types etc. in extras. */
static bool add_singular_points(gltf *g, const ism_features *f, int material)
{
    const ism_locus *l = f->locus;
    if (!l || !l->npoints)
        return true;
    float *pos = malloc(l->npoints * 3 * sizeof *pos);
    if (!pos)
        return false;
    ism_jw ex;
    ism_jw_init(&ex);
    ism_jw_object(&ex);
    ism_jw_key(&ex, "type");
    ism_jw_array(&ex);
    for (size_t i = 0; i < l->npoints; i++) {
        for (int k = 0; k < 3; k++)
            pos[3 * i + k] = (float)l->points[i].p[k];
        ism_jw_string(&ex, ism_sing_type_name(l->points[i].type));
    }
    ism_jw_array_end(&ex);
    ism_jw_key(&ex, "certified");
    ism_jw_array(&ex);
    for (size_t i = 0; i < l->npoints; i++)
        ism_jw_bool(&ex, l->points[i].certified);
    ism_jw_array_end(&ex);
    ism_jw_key(&ex, "xyz");
    ism_jw_array(&ex);
    for (size_t i = 0; i < 3 * l->npoints; i++)
        ism_jw_number(&ex, l->points[i / 3].p[i % 3]);
    ism_jw_array_end(&ex);
    ism_jw_object_end(&ex);
    bool ok = emit_primitive(g, "singular_points", GL_POINTS, material, pos, l->npoints, NULL,
                             0, &ex);
    ism_jw_free(&ex);
    free(pos);
    return ok;
}

/* The singular curves of one kind as LINES (a closed curve also joins its ends). */
static bool add_singular_curves(gltf *g, const ism_features *f, int kind, const char *name,
                                int material)
{
    const ism_locus *l = f->locus;
    size_t nv = 0, nseg = 0, ncurves = 0;
    for (size_t c = 0; l && c < l->ncurves; c++)
        if (l->curves[c].kind == kind && l->curves[c].n > 1) {
            nv += l->curves[c].n;
            nseg += l->curves[c].n - 1 + l->curves[c].closed;
            ncurves++;
        }
    if (!nseg)
        return true;
    float *pos = malloc(nv * 3 * sizeof *pos);
    uint32_t *idx = malloc(2 * nseg * sizeof *idx);
    bool ok = pos && idx;
    size_t v = 0, ni = 0;
    for (size_t c = 0; ok && c < l->ncurves; c++) {
        const ism_sing_curve *cv = &l->curves[c];
        if (cv->kind != kind || cv->n < 2)
            continue;
        for (size_t i = 0; i < 3 * cv->n; i++)
            pos[3 * v + i] = (float)cv->xyz[i];
        for (size_t i = 0; i + 1 < cv->n + cv->closed; i++) {
            idx[ni++] = (uint32_t)(v + i);
            idx[ni++] = (uint32_t)(v + (i + 1) % cv->n);
        }
        v += cv->n;
    }
    ism_jw ex;
    ism_jw_init(&ex);
    ism_jw_object(&ex);
    ism_jw_key(&ex, "kind");
    ism_jw_string(&ex, ism_curve_kind_name(kind));
    ism_jw_key(&ex, "curves");
    ism_jw_uint(&ex, ncurves);
    ism_jw_object_end(&ex);
    ok = ok && emit_primitive(g, name, GL_LINES, material, pos, nv, idx, ni, &ex);
    ism_jw_free(&ex);
    free(pos);
    free(idx);
    return ok;
}

/* The requested curves of one kind (enum ism_cut_kind) as LINES, one polyline per arc;
 * extras {"kind", "curves": how many, "curve": each arc's curve (the features JSON's order of
 * the requested curves)}. */
static bool add_cut_curves(gltf *g, const ism_mesh *m, const ism_features *f, int kind,
                           int material)
{
    const ism_polylines *a = &f->arcs;
    ism_polylines some = {0, NULL, NULL};
    some.start = malloc((a->n + 1) * sizeof *some.start);
    some.verts = malloc(((a->n ? a->start[a->n] : 0) + 1) * sizeof *some.verts);
    uint32_t top = 0; /* curve ids < top */
    for (size_t i = 0; i < a->n; i++)
        top = f->arc_curve[i] >= top ? f->arc_curve[i] + 1 : top;
    uint8_t *seen = calloc(top ? top : 1, 1);
    ism_jw ex;
    ism_jw_init(&ex);
    bool ok = some.start && some.verts && seen;
    if (ok) {
        some.start[0] = 0;
        ism_jw_object(&ex);
        ism_jw_key(&ex, "kind");
        ism_jw_string(&ex, ism_cut_kind_name(kind));
        ism_jw_key(&ex, "curve");
        ism_jw_array(&ex);
        size_t ncurves = 0;
        for (size_t i = 0; i < a->n; i++) {
            if (f->arc_kind[i] != kind)
                continue;
            uint32_t len = a->start[i + 1] - a->start[i];
            memcpy(some.verts + some.start[some.n], a->verts + a->start[i], len * sizeof(uint32_t));
            some.start[some.n + 1] = some.start[some.n] + len;
            some.n++;
            ism_jw_uint(&ex, f->arc_curve[i]);
            ncurves += !seen[f->arc_curve[i]];
            seen[f->arc_curve[i]] = 1;
        }
        ism_jw_array_end(&ex);
        ism_jw_key(&ex, "curves");
        ism_jw_uint(&ex, ncurves);
        ism_jw_object_end(&ex);
        char name[48];
        snprintf(name, sizeof name, "%s_curves", ism_cut_kind_name(kind));
        ok = add_feature_primitive(g, m, name, GL_LINES, material, &some, NULL, 0, &ex);
    }
    ism_jw_free(&ex);
    ism_polylines_free(&some);
    free(seen);
    return ok;
}

/* Colours of the requested curves by kind (the viewer's, web/js/curves.js). */
static const float CUT_COLORS[ISM_CUT_KIND_COUNT][3] = {
    {1.00f, 0.31f, 0.64f}, {0.23f, 0.53f, 1.00f}, {1.00f, 0.75f, 0.04f}, {0.90f, 0.90f, 0.90f},
    {0.98f, 0.34f, 0.03f}};
#define CUT_MATERIAL0 7 /* the first requested-curve material */

static void write_material(ism_jw *w, const char *name, float r, float gr, float b,
                           bool double_sided)
{
    ism_jw_object(w);
    ism_jw_key(w, "name");
    ism_jw_string(w, name);
    ism_jw_key(w, "pbrMetallicRoughness");
    ism_jw_object(w);
    ism_jw_key(w, "baseColorFactor");
    ism_jw_array(w);
    ism_jw_float(w, r);
    ism_jw_float(w, gr);
    ism_jw_float(w, b);
    ism_jw_float(w, 1);
    ism_jw_array_end(w);
    ism_jw_key(w, "metallicFactor");
    ism_jw_float(w, 0);
    ism_jw_key(w, "roughnessFactor");
    ism_jw_float(w, 0.6f);
    ism_jw_object_end(w);
    if (double_sided) {
        ism_jw_key(w, "doubleSided");
        ism_jw_bool(w, true);
    }
    ism_jw_object_end(w);
}

static char *join_json(gltf *g, const ism_glb_input *in, size_t *len)
{
    ism_jw w;
    ism_jw_init(&w);
    ism_jw_object(&w);
    ism_jw_key(&w, "asset");
    ism_jw_object(&w);
    ism_jw_key(&w, "version");
    ism_jw_string(&w, "2.0");
    ism_jw_key(&w, "generator");
    ism_jw_string(&w, "isomesh " ISM_VERSION " (" ISM_MESHER_VERSION ")");
    if (in->key) {
        ism_jw_key(&w, "extras");
        ism_jw_object(&w);
        ism_jw_key(&w, "key");
        ism_jw_string(&w, in->key);
        ism_jw_object_end(&w);
    }
    ism_jw_object_end(&w);
    if (in->draco) {
        ism_jw_key(&w, "extensionsUsed");
        ism_jw_array(&w);
        ism_jw_string(&w, "KHR_draco_mesh_compression");
        ism_jw_array_end(&w);
        ism_jw_key(&w, "extensionsRequired");
        ism_jw_array(&w);
        ism_jw_string(&w, "KHR_draco_mesh_compression");
        ism_jw_array_end(&w);
    }
    ism_jw_key(&w, "scene");
    ism_jw_int(&w, 0);
    ism_jw_key(&w, "scenes");
    ism_jw_array(&w);
    ism_jw_object(&w);
    ism_jw_key(&w, "name");
    ism_jw_string(&w, g->nnodes ? "isomesh surface" : "isomesh surface (empty)");
    if (g->nnodes) {
        ism_jw_key(&w, "nodes");
        ism_jw_array(&w);
        for (int i = 0; i < g->nnodes; i++)
            ism_jw_int(&w, i);
        ism_jw_array_end(&w);
    }
    ism_jw_object_end(&w);
    ism_jw_array_end(&w);
    if (g->nnodes) {
        struct {
            const char *key;
            ism_jw *items;
        } arrays[] = {{"nodes", &g->nodes}, {"meshes", &g->meshes},
                      {"accessors", &g->accessors}, {"bufferViews", &g->views}};
        for (size_t i = 0; i < 4; i++) {
            size_t n;
            char *items = ism_jw_take(arrays[i].items, &n);
            if (!items) {
                ism_jw_free(&w);
                return NULL;
            }
            ism_jw_key(&w, arrays[i].key);
            ism_jw_raw(&w, items, n);
            free(items);
        }
        ism_jw_key(&w, "materials");
        ism_jw_array(&w);
        write_material(&w, "surface", 0.80f, 0.80f, 0.85f, true);
        write_material(&w, "nonmanifold_curves", 0.90f, 0.10f, 0.10f, false);
        write_material(&w, "nonmanifold_points", 1.00f, 0.85f, 0.10f, false);
        write_material(&w, "boundaries", 0.10f, 0.35f, 0.95f, false);
        write_material(&w, "singular_points", 1.00f, 0.82f, 0.12f, false);
        write_material(&w, "double_curves", 0.22f, 0.89f, 0.42f, false);
        write_material(&w, "whiskers", 0.13f, 0.83f, 0.93f, false);
        for (int k = 0; k < ISM_CUT_KIND_COUNT; k++) {
            char name[48];
            snprintf(name, sizeof name, "%s_curves", ism_cut_kind_name(k));
            write_material(&w, name, CUT_COLORS[k][0], CUT_COLORS[k][1], CUT_COLORS[k][2], false);
        }
        ism_jw_array_end(&w);
        ism_jw_key(&w, "buffers");
        ism_jw_array(&w);
        ism_jw_object(&w);
        ism_jw_key(&w, "byteLength");
        ism_jw_uint(&w, g->bin.len);
        ism_jw_object_end(&w);
        ism_jw_array_end(&w);
    }
    ism_jw_object_end(&w);
    return ism_jw_take(&w, len);
}

static bool container(const char *json, size_t jlen, const bin *b, unsigned char **out,
                      size_t *len)
{
    size_t jpad = (jlen + 3) & ~(size_t)3, bpad = (b->len + 3) & ~(size_t)3;
    size_t total = 12 + 8 + jpad + (b->len ? 8 + bpad : 0);
    if (total > UINT32_MAX)
        return false;
    unsigned char *p = malloc(total);
    if (!p)
        return false;
    ism_put_le32(p, 0x46546C67u); /* "glTF" */
    ism_put_le32(p + 4, 2);
    ism_put_le32(p + 8, (uint32_t)total);
    ism_put_le32(p + 12, (uint32_t)jpad);
    ism_put_le32(p + 16, 0x4E4F534Au); /* "JSON" */
    memcpy(p + 20, json, jlen);
    memset(p + 20 + jlen, ' ', jpad - jlen);
    if (b->len) {
        unsigned char *q = p + 20 + jpad;
        ism_put_le32(q, (uint32_t)bpad);
        ism_put_le32(q + 4, 0x004E4942u); /* "BIN\0" */
        memcpy(q + 8, b->data, b->len);
        memset(q + 8 + b->len, 0, bpad - b->len);
    }
    *out = p;
    *len = total;
    return true;
}

static void extras_for_points(const ism_features *f, ism_jw *w)
{
    ism_jw_object(w);
    ism_jw_key(w, "class");
    ism_jw_array(w);
    for (size_t i = 0; i < f->npoints; i++)
        ism_jw_int(w, f->point_class[i]);
    ism_jw_array_end(w);
    ism_jw_key(w, "kind");
    ism_jw_array(w);
    for (size_t i = 0; i < f->npoints; i++)
        ism_jw_string(w, ism_point_kind_name(f->point_kind[i]));
    ism_jw_array_end(w);
    ism_jw_object_end(w);
}

bool ism_glb_build(const ism_glb_input *in, unsigned char **out, size_t *len)
{
    gltf g;
    memset(&g, 0, sizeof g);
    ism_jw *arrays[] = {&g.accessors, &g.views, &g.meshes, &g.nodes};
    for (int i = 0; i < 4; i++) {
        ism_jw_init(arrays[i]);
        ism_jw_array(arrays[i]);
    }
    ism_jw extras;
    ism_jw_init(&extras);
    bool ok = true;
    bool plain = !in->draco && in->wire && in->wire->live_triangles;
    if ((in->draco && in->draco->len) || plain) {
        if (plain)
            ok = add_plain_surface(&g, in->wire);
        else
            add_surface(&g, in->wire, in->draco);
        const ism_features *f = in->features;
        if (f && ok) {
            extras_for_points(f, &extras);
            ok = add_feature_primitive(&g, in->mesh, "nonmanifold_curves", GL_LINES, 1,
                                       &f->curves, NULL, 0, NULL) &&
                 add_feature_primitive(&g, in->mesh, "nonmanifold_points", GL_POINTS, 2, NULL,
                                       f->points, f->npoints, &extras) &&
                 add_feature_primitive(&g, in->mesh, "boundaries", GL_LINES, 3, &f->boundaries,
                                       NULL, 0, NULL) &&
                 add_singular_points(&g, f, 4) &&
                 add_singular_curves(&g, f, ISM_CURVE_DOUBLE, "double_curves", 5) &&
                 add_singular_curves(&g, f, ISM_CURVE_WHISKER, "whiskers", 6);
            for (int k = 0; ok && k < ISM_CUT_KIND_COUNT; k++)
                ok = add_cut_curves(&g, in->mesh, f, k, CUT_MATERIAL0 + k);
        }
    }
    for (int i = 0; i < 4; i++)
        ism_jw_array_end(arrays[i]);
    size_t jlen = 0;
    char *json = ok && !g.bin.failed ? join_json(&g, in, &jlen) : NULL;
    ok = json && container(json, jlen, &g.bin, out, len);
    free(json);
    free(g.bin.data);
    ism_jw_free(&extras);
    for (int i = 0; i < 4; i++)
        ism_jw_free(arrays[i]);
    return ok;
}
