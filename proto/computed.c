/* computed.c — the computed surface of computed.h: freeing it, its versioned binary entry
 * (written and read field by field, every length and index checked on the way in) and the
 * per-request view of its wire attributes. */
#include "proto/computed.h"
#include "proto/request.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#if defined(__BYTE_ORDER__) && __BYTE_ORDER__ != __ORDER_LITTLE_ENDIAN__
#error "computed.c writes arrays in host order, which the entry format fixes as little endian"
#endif

static const char MAGIC[4] = {'I', 'S', 'M', 'S'};

void ism_computed_init(ism_computed *c)
{
    memset(c, 0, sizeof *c);
    ism_mesh_init(&c->mesh);
    ism_locus_init(&c->locus);
}

void ism_computed_free(ism_computed *c)
{
    ism_mesh_free(&c->mesh);
    free(c->wire.pos);
    free(c->wire.normal);
    free(c->wire.mean_curvature);
    free(c->wire.gauss_curvature);
    free(c->vertex_class);
    free(c->tri_cell);
    free(c->tri_sheet);
    free(c->corner_at);
    free(c->corner_normal);
    free(c->corner_locus);
    ism_features_free(&c->features);
    ism_locus_free(&c->locus);
    free(c->features_json);
    free(c->stats_json);
    ism_computed_init(c);
}

void ism_computed_wire(const ism_computed *c, unsigned attrs, ism_wire_mesh *view)
{
    *view = c->wire;
    if (!(attrs & ISM_ATTR_NORMAL)) {
        view->normal = NULL;
        view->ncorner_normals = 0;
    }
    if (!(attrs & ISM_ATTR_MEAN_CURVATURE))
        view->mean_curvature = NULL;
    if (!(attrs & ISM_ATTR_GAUSS_CURVATURE))
        view->gauss_curvature = NULL;
    if (!(attrs & ISM_ATTR_CLASS))
        view->vertex_class = NULL;
    view->tri_cell = c->tri_cell; /* labels of triangles: sent whenever the surface has them */
    view->tri_sheet = c->tri_sheet;
}

/* ---- writing ------------------------------------------------------------------------- */

static void put_array(ism_frame_builder *b, const void *p, size_t count, size_t size)
{
    ism_frame_put_bytes(b, p, p ? count * size : 0);
}

static void put_polylines(ism_frame_builder *b, const ism_polylines *p)
{
    put_array(b, p->n ? p->start : NULL, p->n + 1, sizeof *p->start);
    put_array(b, p->n ? p->verts : NULL, p->n ? p->start[p->n] : 0, sizeof *p->verts);
}

/* A double as the u64 of its bits (the entry is little endian, as the host). */
static void put_f64(ism_frame_builder *b, double v)
{
    uint64_t u;
    memcpy(&u, &v, sizeof u);
    ism_frame_put_u64(b, u);
}

static double get_f64(ism_frame_cursor *c)
{
    uint64_t u = ism_frame_get_u64(c);
    double v;
    memcpy(&v, &u, sizeof v);
    return v;
}

static void put_locus(ism_frame_builder *b, const ism_locus *l)
{
    ism_frame_put_u64(b, l->npoints);
    for (size_t i = 0; i < l->npoints; i++) {
        put_array(b, l->points[i].p, 3, sizeof(double));
        ism_frame_put_u32(b, (uint32_t)l->points[i].type);
        ism_frame_put_u32(b, l->points[i].certified);
    }
    ism_frame_put_u64(b, l->ncurves);
    for (size_t i = 0; i < l->ncurves; i++) {
        const ism_sing_curve *cv = &l->curves[i];
        ism_frame_put_u32(b, (uint32_t)cv->kind);
        ism_frame_put_u32(b, cv->closed);
        for (int e = 0; e < 2; e++) {
            ism_frame_put_u32(b, (uint32_t)cv->end_type[e]);
            ism_frame_put_u32(b, (uint32_t)cv->end_point[e]); /* -1: UINT32_MAX */
        }
        put_f64(b, cv->split_cell);
        ism_frame_put_u32(b, cv->certified);
        ism_frame_put_u64(b, cv->uncertified_points);
        ism_frame_put_u64(b, (uint64_t)cv->first_uncertified); /* -1: UINT64_MAX */
        put_f64(b, cv->first_residual_f);
        put_f64(b, cv->first_residual_grad);
        put_f64(b, cv->cert_radius);
        put_array(b, cv->xyz, 3 * cv->n, sizeof(double));
    }
}

bool ism_computed_write(const ism_computed *c, ism_frame_builder *b)
{
    const ism_mesh *m = &c->mesh;
    const ism_wire_mesh *w = &c->wire;
    size_t nv = m->nverts;
    ism_frame_put_bytes(b, MAGIC, sizeof MAGIC);
    ism_frame_put_u32(b, ISM_COMPUTED_VERSION);
    ism_frame_put_str(b, c->surface_key);
    ism_frame_put_u32(b, c->empty);
    ism_frame_put_u64(b, nv);
    ism_frame_put_u64(b, m->ntris);
    put_array(b, m->pos, 3 * nv, sizeof *m->pos);
    put_array(b, m->normal, 3 * nv, sizeof *m->normal);
    put_array(b, m->tri, 3 * m->ntris, sizeof *m->tri);
    put_array(b, w->pos, 3 * nv, sizeof *w->pos);
    put_array(b, w->normal, 3 * nv, sizeof *w->normal);
    put_array(b, w->mean_curvature, nv, sizeof(float));
    put_array(b, w->gauss_curvature, nv, sizeof(float));
    put_array(b, c->vertex_class, nv, 1);
    put_array(b, c->tri_cell, m->ntris, sizeof *c->tri_cell);
    put_array(b, c->tri_sheet, m->ntris, 1);
    ism_frame_put_u64(b, w->live_triangles);
    put_array(b, w->bounds, 6, sizeof(double));
    put_polylines(b, &c->features.curves);
    put_polylines(b, &c->features.boundaries);
    put_array(b, c->features.points, c->features.npoints, sizeof(uint32_t));
    put_array(b, c->features.point_kind, c->features.npoints, 1);
    put_array(b, c->features.point_class, c->features.npoints, 1);
    put_polylines(b, &c->features.arcs);
    put_array(b, c->features.arc_kind, c->features.arcs.n, 1);
    put_array(b, c->features.arc_curve, c->features.arcs.n, sizeof(uint32_t));
    put_locus(b, &c->locus);
    put_array(b, c->corner_at, w->ncorner_normals, sizeof *c->corner_at);
    put_array(b, c->corner_normal, 3 * w->ncorner_normals, sizeof *c->corner_normal);
    put_array(b, c->corner_locus, c->corner_locus ? w->ncorner_normals : 0, 1);
    put_array(b, c->timings_ms, ISM_TIME_COUNT, sizeof(double));
    ism_frame_put_bytes(b, c->features_json, c->features_len);
    ism_frame_put_bytes(b, c->stats_json, c->stats_len);
    return !b->failed;
}

/* ---- reading ------------------------------------------------------------------------- */

typedef struct reader {
    ism_frame_cursor cur;
    const char *why;           /* first problem seen */
} reader;

static bool bad(reader *r, const char *why)
{
    if (!r->why)
        r->why = why;
    return false;
}

/* A byte string of exactly count items of size bytes (or, when optional, none), copied
 * into *out (NULL when absent). */
static bool get_array(reader *r, size_t count, size_t size, bool optional, void **out,
                      const char *what)
{
    size_t len;
    const unsigned char *p = ism_frame_get_bytes(&r->cur, &len);
    *out = NULL;
    if (r->cur.failed)
        return bad(r, "truncated");
    if (len == 0 && (optional || count == 0))
        return true;
    if (size && count > SIZE_MAX / size)
        return bad(r, what);
    if (len != count * size)
        return bad(r, what);
    *out = malloc(len);
    if (!*out)
        return bad(r, "out of memory");
    memcpy(*out, p, len);
    return true;
}

static bool indices_below(const uint32_t *idx, size_t n, size_t limit)
{
    for (size_t i = 0; i < n; i++)
        if (idx[i] >= limit)
            return false;
    return true;
}

static bool get_polylines(reader *r, size_t nverts, ism_polylines *p)
{
    size_t len;
    ism_frame_cursor peek = r->cur;
    ism_frame_get_bytes(&peek, &len);
    if (peek.failed || len % sizeof(uint32_t))
        return bad(r, "polyline starts");
    size_t n = len ? len / sizeof(uint32_t) - 1 : 0;
    void *start, *verts;
    if (!get_array(r, n + 1, sizeof(uint32_t), true, &start, "polyline starts"))
        return false;
    p->start = start;
    p->n = n;
    size_t total = n ? p->start[n] : 0;
    for (size_t i = 0; i < n; i++)
        if (p->start[i] > p->start[i + 1])
            return bad(r, "polyline starts");
    if (n && p->start[0] != 0)
        return bad(r, "polyline starts");
    if (!get_array(r, total, sizeof(uint32_t), false, &verts, "polyline vertices"))
        return false;
    p->verts = verts;
    if (!indices_below(p->verts, total, nverts))
        return bad(r, "polyline vertex out of range");
    return true;
}

static bool get_count(reader *r, size_t *n, const char *what)
{
    uint64_t v = ism_frame_get_u64(&r->cur);
    if (r->cur.failed)
        return bad(r, "truncated");
    if (v > r->cur.left) /* every item takes at least one byte */
        return bad(r, what);
    *n = (size_t)v;
    return true;
}

static bool get_locus(reader *r, ism_locus *l)
{
    size_t n;
    if (!get_count(r, &n, "singular points"))
        return false;
    for (size_t i = 0; i < n; i++) {
        ism_sing_point sp;
        memset(&sp, 0, sizeof sp);
        void *xyz;
        if (!get_array(r, 3, sizeof(double), false, &xyz, "singular point"))
            return false;
        memcpy(sp.p, xyz, sizeof sp.p);
        free(xyz);
        sp.type = (int)ism_frame_get_u32(&r->cur);
        sp.certified = ism_frame_get_u32(&r->cur) != 0;
        sp.cones = -1;
        if (r->cur.failed || sp.type < 0 || sp.type >= ISM_SING_TYPES)
            return bad(r, "singular point");
        if (!ism_locus_add_point(l, &sp))
            return bad(r, "out of memory");
    }
    if (!get_count(r, &n, "singular curves"))
        return false;
    for (size_t i = 0; i < n; i++) {
        ism_sing_curve cv;
        memset(&cv, 0, sizeof cv);
        cv.kind = (int)ism_frame_get_u32(&r->cur);
        cv.closed = ism_frame_get_u32(&r->cur) != 0;
        bool ends_ok = true;
        for (int e = 0; e < 2; e++) {
            uint32_t type = ism_frame_get_u32(&r->cur), point = ism_frame_get_u32(&r->cur);
            ends_ok = ends_ok && type < ISM_END_TYPES &&
                      (point == UINT32_MAX || point < l->npoints);
            cv.end_type[e] = (int)type;
            cv.end_point[e] = point == UINT32_MAX ? -1 : (int)point;
        }
        cv.split_cell = get_f64(&r->cur);
        cv.certified = ism_frame_get_u32(&r->cur) != 0;
        cv.uncertified_points = (size_t)ism_frame_get_u64(&r->cur);
        cv.first_uncertified = (long)(int64_t)ism_frame_get_u64(&r->cur);
        cv.first_residual_f = get_f64(&r->cur);
        cv.first_residual_grad = get_f64(&r->cur);
        cv.cert_radius = get_f64(&r->cur);
        size_t len;
        ism_frame_cursor peek = r->cur;
        ism_frame_get_bytes(&peek, &len);
        if (r->cur.failed || peek.failed || cv.kind < 0 || cv.kind >= ISM_CURVE_KINDS ||
            !ends_ok || !(cv.split_cell >= 0 && cv.split_cell < INFINITY) ||
            len % (3 * sizeof(double)))
            return bad(r, "singular curve");
        cv.n = len / (3 * sizeof(double));
        if (cv.uncertified_points > cv.n || cv.first_uncertified < -1 ||
            cv.first_uncertified >= (long)cv.n)
            return bad(r, "singular curve certificate");
        void *xyz;
        if (!get_array(r, 3 * cv.n, sizeof(double), false, &xyz, "singular curve"))
            return false;
        cv.xyz = xyz;
        if (!ism_locus_add_curve(l, &cv)) {
            free(xyz);
            return bad(r, "out of memory");
        }
    }
    return true;
}

static bool get_text(reader *r, char **out, size_t *len)
{
    void *p;
    size_t n;
    ism_frame_cursor peek = r->cur;
    ism_frame_get_bytes(&peek, &n);
    if (peek.failed)
        return bad(r, "truncated");
    if (!get_array(r, n, 1, false, &p, "text"))
        return false;
    char *s = malloc(n + 1);
    if (!s) {
        free(p);
        return bad(r, "out of memory");
    }
    if (n)
        memcpy(s, p, n);
    s[n] = 0;
    free(p);
    *out = s;
    *len = n;
    return true;
}

static bool get_mesh(reader *r, ism_computed *c)
{
    ism_mesh *m = &c->mesh;
    size_t nv, nt;
    if (!get_count(r, &nv, "vertex count") || !get_count(r, &nt, "triangle count"))
        return false;
    if (nv > UINT32_MAX || nt > SIZE_MAX / 12)
        return bad(r, "mesh size");
    void *pos, *normal, *tri;
    if (!get_array(r, 3 * nv, sizeof(double), false, &pos, "positions"))
        return false;
    m->pos = pos;
    if (!get_array(r, 3 * nv, sizeof(float), true, &normal, "normals"))
        return false;
    m->normal = normal;
    if (!get_array(r, 3 * nt, sizeof(uint32_t), false, &tri, "triangles"))
        return false;
    m->tri = tri;
    m->nverts = m->cap_verts = nv;
    m->ntris = m->cap_tris = nt;
    if (!indices_below(m->tri, 3 * nt, nv))
        return bad(r, "triangle vertex out of range");
    return true;
}

static bool get_wire(reader *r, ism_computed *c)
{
    ism_wire_mesh *w = &c->wire;
    size_t nv = c->mesh.nverts;
    void *p[5], *bounds;
    if (!get_array(r, 3 * nv, sizeof(float), false, &p[0], "wire positions"))
        return false;
    w->pos = p[0];
    if (!get_array(r, 3 * nv, sizeof(float), true, &p[1], "wire normals"))
        return false;
    w->normal = p[1];
    if (!get_array(r, nv, sizeof(float), true, &p[2], "mean curvature"))
        return false;
    w->mean_curvature = p[2];
    if (!get_array(r, nv, sizeof(float), true, &p[3], "Gauss curvature"))
        return false;
    w->gauss_curvature = p[3];
    if (!get_array(r, nv, 1, true, &p[4], "vertex class"))
        return false;
    c->vertex_class = p[4];
    w->vertex_class = c->vertex_class;
    void *cell, *sheet;
    if (!get_array(r, c->mesh.ntris, sizeof(uint32_t), true, &cell, "cells"))
        return false;
    c->tri_cell = cell;
    w->tri_cell = c->tri_cell;
    if (!get_array(r, c->mesh.ntris, 1, true, &sheet, "double sheets"))
        return false;
    c->tri_sheet = sheet;
    w->tri_sheet = c->tri_sheet;
    w->nverts = nv;
    w->ntris = c->mesh.ntris;
    w->tri = c->mesh.tri;
    w->live_triangles = (size_t)ism_frame_get_u64(&r->cur);
    if (!get_array(r, 6, sizeof(double), false, &bounds, "bounds"))
        return false;
    memcpy(w->bounds, bounds, sizeof w->bounds);
    free(bounds);
    return true;
}

static bool get_features(reader *r, ism_computed *c)
{
    ism_features *f = &c->features;
    size_t nv = c->mesh.nverts;
    if (!get_polylines(r, nv, &f->curves) || !get_polylines(r, nv, &f->boundaries))
        return false;
    size_t len;
    ism_frame_cursor peek = r->cur;
    ism_frame_get_bytes(&peek, &len);
    if (peek.failed || len % sizeof(uint32_t))
        return bad(r, "feature points");
    f->npoints = len / sizeof(uint32_t);
    void *pts, *kind, *cls;
    if (!get_array(r, f->npoints, sizeof(uint32_t), false, &pts, "feature points"))
        return false;
    f->points = pts;
    if (!get_array(r, f->npoints, 1, false, &kind, "feature point kinds"))
        return false;
    f->point_kind = kind;
    if (!get_array(r, f->npoints, 1, false, &cls, "feature point classes"))
        return false;
    f->point_class = cls;
    if (!indices_below(f->points, f->npoints, nv))
        return bad(r, "feature point out of range");
    if (!get_polylines(r, nv, &f->arcs))
        return false;
    void *akind, *acurve;
    if (!get_array(r, f->arcs.n, 1, false, &akind, "arc kinds"))
        return false;
    f->arc_kind = akind;
    if (!get_array(r, f->arcs.n, sizeof(uint32_t), false, &acurve, "arc curves"))
        return false;
    f->arc_curve = acurve;
    for (size_t i = 0; i < f->arcs.n; i++)
        if (f->arc_kind[i] >= ISM_CUT_KIND_COUNT)
            return bad(r, "arc kind out of range");
    f->locus = &c->locus;
    return true;
}

/* The corners' own normals (crease sides, the singular locus's sheets; after the mesh and
 * the wire). */
static bool get_corner_normals(reader *r, ism_computed *c)
{
    size_t len;
    ism_frame_cursor peek = r->cur;
    ism_frame_get_bytes(&peek, &len);
    if (peek.failed || len % sizeof(uint32_t))
        return bad(r, "corner normals");
    size_t n = len / sizeof(uint32_t);
    void *at, *nrm;
    if (!get_array(r, n, sizeof(uint32_t), true, &at, "corner indices"))
        return false;
    c->corner_at = at;
    if (!get_array(r, 3 * n, sizeof(float), true, &nrm, "corner normals"))
        return false;
    c->corner_normal = nrm;
    void *on;
    if (!get_array(r, n, 1, true, &on, "corner locus marks"))
        return false;
    c->corner_locus = on;
    for (size_t i = 0; i < n; i++)
        if (c->corner_at[i] >= 3 * c->mesh.ntris || (i && c->corner_at[i] <= c->corner_at[i - 1]))
            return bad(r, "corner index out of order or range");
    for (size_t i = 0; c->corner_locus && i < n; i++)
        if (c->corner_locus[i] > 1)
            return bad(r, "corner locus mark not 0 or 1");
    ism_wire_mesh *w = &c->wire;
    w->ncorner_normals = n;
    w->corner_at = c->corner_at;
    w->corner_normal = c->corner_normal;
    w->corner_locus = c->corner_locus;
    return true;
}

static bool read_all(reader *r, ism_computed *c)
{
    size_t len;
    const unsigned char *magic = ism_frame_get_bytes(&r->cur, &len);
    if (r->cur.failed || len != sizeof MAGIC || memcmp(magic, MAGIC, sizeof MAGIC) != 0)
        return bad(r, "not a computed-mesh entry");
    if (ism_frame_get_u32(&r->cur) != ISM_COMPUTED_VERSION)
        return bad(r, "another entry version");
    ism_frame_get_str(&r->cur, c->surface_key, sizeof c->surface_key);
    c->empty = ism_frame_get_u32(&r->cur) != 0;
    if (r->cur.failed)
        return bad(r, "truncated");
    void *timings;
    if (!get_mesh(r, c) || !get_wire(r, c) || !get_features(r, c) || !get_locus(r, &c->locus) ||
        !get_corner_normals(r, c) || !get_array(r, ISM_TIME_COUNT, sizeof(double), false, &timings, "timings"))
        return false;
    memcpy(c->timings_ms, timings, sizeof c->timings_ms);
    free(timings);
    if (!get_text(r, &c->features_json, &c->features_len) ||
        !get_text(r, &c->stats_json, &c->stats_len))
        return false;
    if (r->cur.left != 0)
        return bad(r, "trailing bytes");
    return true;
}

bool ism_computed_read(const void *data, size_t len, ism_computed *c, char *why, size_t n)
{
    ism_computed_init(c);
    reader r = {.why = NULL};
    ism_frame_cursor_init(&r.cur, data, len);
    if (read_all(&r, c))
        return true;
    if (why && n) {
        strncpy(why, r.why ? r.why : "malformed", n - 1);
        why[n - 1] = 0;
    }
    ism_computed_free(c);
    return false;
}
