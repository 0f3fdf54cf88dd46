/* pipeline.c — one surface request from JSON to bytes (contract in pipeline.h): decode and
 * validate, compile, key; polygonise within the operator's limits, with progress and
 * cancellation; analyse; gather the non-manifold features; encode in the requested format;
 * write the stats. Every outcome fills the result: a status, and either the file or the
 * error JSON in body. No geometry is computed here: core does it, proto encodes it. */
#include "server/common/pipeline.h"
#include "server/common/fit_error.h"
#include "core/util/clock.h"

#include "core/analysis/analysis.h"
#include "core/curves/curves.h"
#include "core/mesh/write_mesh.h"
#include "core/octree/polygonise.h"
#include "core/octree/resolvable.h"
#include "core/singular/check.h"
#include "core/singular/surface.h"
#include "core/util/vec3.h"
#include "proto/computed.h"
#include "proto/corner_split.h"
#include "proto/curve_fns.h"
#include "proto/draco_encode.h"
#include "proto/features.h"
#include "proto/glb.h"
#include "proto/mesh_files.h"
#include "proto/request.h"
#include "proto/stats.h"
#include "proto/thumbnail.h"
#include "proto/wire_mesh.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

void ism_buf_free(ism_buf *b)
{
    free(b->data);
    memset(b, 0, sizeof *b);
}

void ism_pipeline_limits_default(ism_pipeline_limits *l)
{
    l->max_depth = ISM_REQ_DEFAULT_MAX_DEPTH_LIMIT;
    l->max_triangles = 4000000;
    l->max_memory = (size_t)2 << 30;
    l->threads = 0;
}

/* Defaults for a NULL limits pointer. */
static const ism_pipeline_limits *limits_or_default(const ism_pipeline_limits *lim,
                                                    ism_pipeline_limits *dl)
{
    if (lim)
        return lim;
    ism_pipeline_limits_default(dl);
    return dl;
}

void ism_pipeline_result_free(ism_pipeline_result *r)
{
    ism_buf_free(&r->body);
    ism_buf_free(&r->stats);
    ism_buf_free(&r->features);
    ism_buf_free(&r->canonical);
    ism_buf_free(&r->computed);
    memset(r, 0, sizeof *r);
}

/* Moves malloc'd text into a buffer. */
static void take(ism_buf *b, void *data, size_t len)
{
    ism_buf_free(b);
    b->data = data;
    b->len = len;
    b->cap = len;
}

size_t ism_buf_write(void *ctx, const void *p, size_t n)
{
    ism_buf *b = ctx;
    if (b->len + n > b->cap) {
        size_t c = b->cap ? b->cap : 65536;
        while (c < b->len + n)
            c *= 2;
        unsigned char *d = realloc(b->data, c);
        if (!d)
            return 0;
        b->data = d;
        b->cap = c;
    }
    memcpy(b->data + b->len, p, n);
    b->len += n;
    return n;
}

/* Ends the run with an error: status, error JSON body. Returns false. */
static bool fail(ism_pipeline_result *r, const ism_req_error *e)
{
    r->status = e->status ? e->status : 500;
    r->content_type = "application/json";
    size_t n;
    char *json = ism_req_error_json(e, &n);
    if (json)
        take(&r->body, json, n);
    else
        ism_buf_free(&r->body);
    return false;
}

static bool fail_with(ism_pipeline_result *r, int status, const char *code, const char *fmt,
                      const char *detail)
{
    ism_req_error e;
    ism_req_error_set(&e, status, code, "", fmt, detail);
    return fail(r, &e);
}

static ism_request_limits request_limits(const ism_pipeline_limits *lim)
{
    ism_request_limits rl = {lim->max_depth};
    return rl;
}

/* Decode, override the format, compile, key, canonical form: the part that needs no
 * geometry. Clears r first; lim NULL means the defaults. On success the caller owns *req and
 * *tape. */
static bool prepare(const char *json, size_t len, const char *format_override,
                    const ism_pipeline_limits *lim, ism_pipeline_result *r, ism_request *req,
                    ism_tape **tape, double *decode_ms, double *compile_ms)
{
    memset(r, 0, sizeof *r);
    ism_pipeline_limits dl;
    lim = limits_or_default(lim, &dl);
    ism_req_error e;
    double t0 = ism_now_ms();
    ism_request_limits rl = request_limits(lim);
    if (!ism_request_decode(json ? json : "", json ? len : 0, &rl, req, &e))
        return fail(r, &e);
    if (format_override && !ism_request_set_format(req, format_override, &e)) {
        ism_request_free(req);
        return fail(r, &e);
    }
    snprintf(r->format, sizeof r->format, "%s", ism_format_name(req->format));
    double t1 = ism_now_ms();
    *tape = ism_request_compile(req, &e);
    ism_curve_fns cf; /* the curves' expressions compile (400 naming $.curves[i].expr) */
    if (!*tape || !ism_curve_fns_build(req, &cf, &e)) {
        ism_tape_free(*tape);
        *tape = NULL;
        ism_request_free(req);
        return fail(r, &e);
    }
    ism_curve_fns_free(&cf);
    size_t n;
    char *canonical = ism_request_canonical(req, &n);
    if (!canonical || !ism_request_key(req, *tape, r->key) ||
        !ism_request_surface_key(req, *tape, r->surface_key)) {
        free(canonical);
        ism_tape_free(*tape);
        *tape = NULL;
        ism_request_free(req);
        return fail_with(r, 500, "no_memory", "%s", "out of memory computing the cache key");
    }
    take(&r->canonical, canonical, n);
    *decode_ms = t1 - t0;
    *compile_ms = ism_now_ms() - t1;
    return true;
}

bool ism_pipeline_key(const char *json, size_t len, const char *format_override,
                      const ism_pipeline_limits *lim, ism_pipeline_result *r)
{
    ism_request req;
    ism_tape *tape;
    double d, c;
    if (!prepare(json, len, format_override, lim, r, &req, &tape, &d, &c))
        return false;
    r->status = 200;
    r->content_type = ism_format_mime(req.format);
    ism_tape_free(tape);
    ism_request_free(&req);
    return true;
}

/* ---------------------------------------------------------------------------------------
 * The run */

typedef struct progress_map {
    const ism_pipeline_hooks *hooks;
    double lo, hi;
} progress_map;

static void report(const ism_pipeline_hooks *h, double f)
{
    if (h && h->progress)
        h->progress(h->ctx, f);
}

static void polygoniser_progress(void *ctx, double f)
{
    const progress_map *m = ctx;
    report(m->hooks, m->lo + (m->hi - m->lo) * (f < 0 ? 0 : f > 1 ? 1 : f));
}

static bool cancelled(const ism_pipeline_hooks *h) { return h && h->cancel && *h->cancel; }

/* The 422 for a mesh over the triangle budget. Under a bound depth.max is not what makes
 * the mesh big (the bound is), so the answer names a larger max_error that fits, found by
 * coarse passes (server/common/fit_error.h); on the depth path, a lower depth.max. */
static bool too_big(ism_pipeline_result *r, const ism_error *err, const ism_tape *tape,
                    const ism_poly_options *o, bool preview)
{
    if (!(o->max_error > 0))
        return fail_with(r, 422, "too_big", "%s (lower depth.max or shrink the box)",
                         err->message);
    double fit = ism_fit_error(tape, o, preview);
    ism_req_error e;
    char buf[32];
    if (fit > 0)
        ism_req_error_set(&e, 422, "too_big", "",
                          "%s under max_error %s; max_error %s fits (max_error_that_fits)",
                          err->message, ism_three_digits(o->max_error, 0, buf),
                          ism_three_digits(fit, 1, (char[32]){0}));
    else
        ism_req_error_set(&e, 422, "too_big", "",
                          "%s under max_error %s; no max_error up to the box diagonal fits "
                          "(shrink the box)",
                          err->message, ism_three_digits(o->max_error, 0, buf));
    e.max_error_that_fits = fit;
    return fail(r, &e);
}

static bool polygonise_status(ism_pipeline_result *r, enum ism_poly_status st,
                              const ism_error *err, const ism_tape *tape,
                              const ism_poly_options *o, bool preview)
{
    switch (st) {
    case ISM_POLY_OK:
        return true;
    case ISM_POLY_BAD_OPTIONS:
        return fail_with(r, 400, "bad_request", "%s", err->message);
    case ISM_POLY_TOO_BIG:
        return too_big(r, err, tape, o, preview);
    case ISM_POLY_CANCELLED:
        return fail_with(r, 499, "cancelled", "%s", "the request was cancelled");
    case ISM_POLY_INTERNAL:
        return fail_with(r, 500, "internal", "the polygoniser failed: %s", err->message);
    case ISM_POLY_NO_MEMORY:
    default:
        return fail_with(r, 500, "no_memory", "the polygoniser ran out of memory: %s",
                         err->message);
    }
}

/* What the encoders share. */
typedef struct encode_job {
    const ism_request *req;
    const ism_computed *c;
    ism_wire_mesh wire;         /* the attributes this request sends */
    const char *key;
    size_t points, faces;       /* Draco's, for the stats */
} encode_job;

static bool encode_draco(encode_job *j, ism_draco_output *d, char *why, size_t n)
{
    const ism_wire_mesh *w = &j->wire;
    ism_draco_input in = {
        .nverts = w->nverts,
        .ntris = w->ntris,
        .pos = w->pos,
        .tri = w->tri,
        .normal = w->normal,
        .mean_curvature = w->mean_curvature,
        .gauss_curvature = w->gauss_curvature,
        .vertex_class = w->vertex_class,
        .position_bits = j->req->position_bits,
        .normal_bits = j->req->normal_bits,
        .curvature_bits = j->req->curvature_bits,
        .tools = NULL,
    };
    ism_corner_split split = {0};
    if (ism_corner_split_needed(w)) { /* labels, crease sides: vertices split where they change */
        if (!ism_corner_split_build(w, &split)) {
            snprintf(why, n, "out of memory splitting the vertices along the cells");
            return false;
        }
        in.tri = split.tri;
        in.npoints = split.npoints;
        in.point_vertex = split.point_vertex;
        in.point_cell = split.point_cell;
        in.point_sheet = split.point_sheet;
        in.point_normal = split.point_normal;
    }
    bool ok = ism_draco_encode(&in, d);
    ism_corner_split_free(&split);
    if (!ok) {
        snprintf(why, n, "%s", d->error);
        return false;
    }
    j->points = d->points;
    j->faces = d->faces;
    return true;
}

/* Fills body with the file; false with a reason in why. */
static bool encode_body(encode_job *j, ism_buf *body, char *why, size_t n)
{
    ism_mesh none;
    ism_mesh_init(&none);
    bool empty = j->c->empty;
    const ism_mesh *m = empty ? &none : &j->c->mesh;
    ism_draco_output d;
    memset(&d, 0, sizeof d);
    bool ok = true;
    switch (j->req->format) {
    case ISM_FORMAT_DRC:
        if (!empty && (ok = encode_draco(j, &d, why, n))) {
            take(body, d.data, d.len);
            d.data = NULL;
        }
        break;
    case ISM_FORMAT_GLB: {
        bool draco = !empty && !j->req->plain_glb;
        if (draco && !(ok = encode_draco(j, &d, why, n)))
            break;
        ism_glb_input gi = {&j->c->mesh, &j->wire, draco ? &d : NULL, &j->c->features, j->key};
        unsigned char *glb;
        size_t len;
        if ((ok = ism_glb_build(&gi, &glb, &len)))
            take(body, glb, len);
        else
            snprintf(why, n, "out of memory building the glb");
        break;
    }
    case ISM_FORMAT_PLY:
        ok = empty ? ism_write_ply(m, ism_buf_write, body)
                   : ism_write_ply_wire(m, &j->wire, ism_buf_write, body);
        break;
    case ISM_FORMAT_OBJ:
        ok = ism_write_obj_features(m, empty ? NULL : &j->wire, empty ? NULL : &j->c->features,
                                    ism_buf_write, body);
        break;
    case ISM_FORMAT_STL:
        ok = ism_write_stl(m, ism_buf_write, body);
        break;
    case ISM_FORMAT_PNG: {
        unsigned char *png;
        size_t len;
        if ((ok = ism_thumbnail_png(m, j->req->poly.box, &png, &len)))
            take(body, png, len);
        break;
    }
    default:
        ok = false;
    }
    if (!ok && !why[0])
        snprintf(why, n, "out of memory writing the %s file", ism_format_name(j->req->format));
    free(d.data);
    return ok;
}

/* The edge of req's finest cells: the box's longest side / 2^max_depth. */
static double finest_cell(const ism_request *req)
{
    double side = 0;
    for (int k = 0; k < 3; k++)
        side = fmax(side, req->poly.box[k + 3] - req->poly.box[k]);
    return ldexp(side, -req->poly.max_depth);
}

/* Curvature the mesh can show: one over its finest cell (the same bits as 2^max_depth / side:
 * ldexp scales by a power of 2 exactly). */
static double curvature_limit(const ism_request *req)
{
    return 1 / finest_cell(req);
}

/* The encoding of c that req asks for: body, stats, features; status 200. */
static bool encode(const ism_request *req, const ism_computed *c, double t_start,
                   const ism_pipeline_hooks *hooks, ism_pipeline_result *r)
{
    double t = ism_now_ms();
    encode_job job = {.req = req, .c = c, .key = r->key};
    ism_computed_wire(c, req->attributes, &job.wire);
    char why[200] = "";
    if (!encode_body(&job, &r->body, why, sizeof why)) {
        ism_buf_free(&r->body);
        return fail_with(r, 500, "encode_failed", "encoding failed: %s", why);
    }
    if (cancelled(hooks))
        return fail_with(r, 499, "cancelled", "%s", "the request was cancelled");
    ism_stats_input si;
    memset(&si, 0, sizeof si);
    memcpy(si.timings_ms, c->timings_ms, sizeof si.timings_ms);
    si.timings_ms[ISM_TIME_ENCODE] = ism_now_ms() - t;
    si.timings_ms[ISM_TIME_TOTAL] = ism_now_ms() - t_start;
    si.key = r->key;
    si.format = r->format;
    si.bytes = r->body.len;
    si.features_bytes = c->features_len;
    si.empty = c->empty;
    si.vertices = c->mesh.nverts;
    si.triangles = c->mesh.ntris;
    si.encoded_points = job.points;
    si.encoded_faces = job.faces;
    si.surface = c->stats_json;
    si.surface_len = c->stats_len;
    size_t slen;
    char *stats = ism_stats_json(&si, &slen);
    char *features = malloc(c->features_len + 1);
    if (!stats || !features) {
        free(stats);
        free(features);
        return fail_with(r, 500, "no_memory", "%s", "out of memory writing the stats");
    }
    take(&r->stats, stats, slen);
    memcpy(features, c->features_json, c->features_len);
    features[c->features_len] = 0;
    take(&r->features, features, c->features_len);
    r->status = 200;
    r->content_type = ism_format_mime(req->format);
    report(hooks, 1.0);
    return true;
}

/* What the computation keeps only until the computed surface is made. */
typedef struct scratch {
    ism_analysis an;
    bool have_analysis;
    ism_locus_check check;
    ism_poly_stats ps;
    ism_conform_stats cs;
    ism_curve_fns cf;       /* requested curves, cut into the mesh */
    ism_cut cut;
    ism_arrangement arr;
    bool have_curves;
    ism_remesh_stats rs;    /* the quality pass's figures */
    bool have_remesh;
    ism_simplify_stats ss;  /* the simplification's */
    bool have_simplify;
} scratch;

/* Cuts the mesh along the requested curves, runs the simplification (under max_error) and
 * the quality pass when asked (after the cut, so curve edges are protected and the cut's
 * slivers improved) and builds the curves' arrangement into s. */
static bool cut_curves(const ism_request *req, const ism_tape *tape,
                       const ism_pipeline_hooks *hooks, ism_pipeline_result *r,
                       ism_computed *c, scratch *s)
{
    ism_req_error e;
    if (!ism_curve_fns_build(req, &s->cf, &e))
        return fail(r, &e);
    if (!ism_curve_fns_add_crease(&s->cf, tape))
        return fail_with(r, 500, "no_memory", "%s", "out of memory cutting the crease");
    ism_error err;
    memset(&err, 0, sizeof err);
    double t = ism_now_ms();
    if (s->cf.n && !ism_curves_cut_mesh(tape, s->cf.fns, s->cf.n, req->poly.box, &c->mesh, &s->cut,
                                        &err))
        return fail_with(r, 500, "no_memory", "%s", err.message);
    c->timings_ms[ISM_TIME_SINGULAR] += ism_now_ms() - t; /* the curves are singular stages too */
    if (ism_simplify_after(req->simplify, req->poly.max_error)) {
        if (!ism_simplify_pass(tape, &c->locus, &s->cut, req->poly.max_error,
                               hooks ? hooks->cancel : NULL, &c->mesh, &s->ss, &err))
            return fail_with(r, 500, "no_memory", "%s", err.message);
        s->have_simplify = true;
        if (cancelled(hooks))
            return fail_with(r, 499, "cancelled", "%s", "the request was cancelled");
    }
    if (req->quality == ISM_QUALITY_GOOD) {
        if (!ism_quality_pass(tape, &c->locus, &s->cut, req->poly.max_error,
                              hooks ? hooks->cancel : NULL, &c->mesh, &s->rs, &err))
            return fail_with(r, 500, "no_memory", "%s", err.message);
        s->have_remesh = true;
        if (cancelled(hooks))
            return fail_with(r, 499, "cancelled", "%s", "the request was cancelled");
    }
    if (!s->cf.n)
        return true;
    t = ism_now_ms();
    const double *b = req->poly.box; /* curve ends on the locus: as the locus check's */
    if (!ism_arrangement_build(&c->mesh, &s->cut, &c->locus, ISM_LOCUS_ON_REL * ism_box_diagonal(b),
                               &s->arr))
        return fail_with(r, 500, "no_memory", "%s", "out of memory building the arrangement");
    c->timings_ms[ISM_TIME_SINGULAR] += ism_now_ms() - t;
    s->have_curves = true;
    return true;
}

/* A preview ("preview": true): the polygoniser's mesh alone into c->mesh — no singular
 * locus, conformance, double sheets, curves or analysis (c->locus stays empty), and only
 * the coarse search for pieces hidden from the cells' corners (thin_coarse: Newton probes
 * in nodes whose corners all share a sign, so a small ball or a thin tube between the
 * lattice lines still shows, followed only while it stays hidden; +9% CPU over the presets'
 * previews at depth 4; where f has a min/max kink also in the faces of nodes with both
 * signs, so a CSG frame's thin bars show). The full search looks at those faces
 * everywhere, and without a locus it chases every singular point's nappes
 * ISM_THIN_BLIND_DEPTH levels down (kummer at depth 4: 12584 triangles and 749 ms instead
 * of 1880 and 97 ms at load 24); the refined mesh has them. */
static bool polygonise_preview(const ism_tape *tape, const ism_poly_options *po,
                               const ism_pipeline_hooks *hooks, ism_pipeline_result *r,
                               ism_computed *c, scratch *s)
{
    ism_error err;
    memset(&err, 0, sizeof err);
    ism_poly_options o = *po;
    o.thin_search = true;
    o.thin_coarse = true;
    double t = ism_now_ms();
    enum ism_poly_status st = ism_polygonise(tape, &o, &c->mesh, &s->ps, &err);
    c->timings_ms[ISM_TIME_POLYGONISE] = ism_now_ms() - t;
    if (!polygonise_status(r, st, &err, tape, &o, true))
        return false;
    if (cancelled(hooks))
        return fail_with(r, 499, "cancelled", "%s", "the request was cancelled");
    r->polygonised = true;
    if (!ism_mesh_drop_loose(&c->mesh)) /* segments travel nowhere without a locus */
        return fail_with(r, 500, "no_memory", "%s", "out of memory tidying the mesh");
    report(hooks, 0.92);
    return true;
}

/* Polygonises and analyses req's surface into c->mesh (locus into c->locus). */
static bool polygonise_and_analyse(const ism_request *req, const ism_tape *tape,
                                   const ism_pipeline_limits *lim,
                                   const ism_pipeline_hooks *hooks, ism_pipeline_result *r,
                                   ism_computed *c, scratch *s)
{
    ism_error err;
    memset(&err, 0, sizeof err);
    ism_poly_options o;
    ism_request_poly_options(req, &o);
    o.max_triangles = lim->max_triangles;
    o.max_memory = lim->max_memory;
    o.threads = lim->threads;
    progress_map pm = {hooks, 0.02, 0.85};
    o.progress = polygoniser_progress;
    o.progress_ctx = &pm;
    o.cancel = hooks ? hooks->cancel : NULL;
    o.deadline_ms = hooks ? hooks->deadline_ms : 0;
    char why[400];
    ism_resolvable rv = ism_resolvable_check(tape, req->poly.box, why, sizeof why);
    if (rv == ISM_RESOLVABLE_NO_MEMORY)
        return fail_with(r, 500, "no_memory", "%s", "out of memory checking the expression");
    if (rv != ISM_RESOLVABLE_OK)
        return fail_with(r, 422, "unresolvable", "%s", why);
    if (req->preview)
        return polygonise_preview(tape, &o, hooks, r, c, s);
    ism_surface_times times;
    enum ism_poly_status st =
        ism_mesh_surface(tape, &o, &c->mesh, &c->locus, &s->ps, &s->cs, &times, &err);
    c->timings_ms[ISM_TIME_SINGULAR] = times.singular_ms;
    c->timings_ms[ISM_TIME_POLYGONISE] = times.polygonise_ms;
    if (!polygonise_status(r, st, &err, tape, &o, false))
        return false;
    if (cancelled(hooks))
        return fail_with(r, 499, "cancelled", "%s", "the request was cancelled");
    r->polygonised = true;
    if (!cut_curves(req, tape, hooks, r, c, s))
        return false;

    double t = ism_now_ms();
    ism_analysis_options ao;
    ism_analysis_options_default(&ao);
    ao.curvature = true;
    ao.accuracy = true;
    ao.threads = lim->threads;
    ao.max_error = o.max_error; /* measured as the polygoniser did (0: none) */
    if (!ism_analyse(&c->mesh, tape, &ao, &s->an, &err))
        return fail_with(r, 500, "internal", "mesh analysis failed: %s", err.message);
    s->have_analysis = true;
    if (!ism_locus_check_mesh(&c->locus, req->poly.box, &c->mesh, &s->an, &s->check, &err))
        return fail_with(r, 500, "no_memory", "%s", err.message);
    c->timings_ms[ISM_TIME_ANALYSE] = ism_now_ms() - t;
    report(hooks, 0.92);
    if (cancelled(hooks))
        return fail_with(r, 499, "cancelled", "%s", "the request was cancelled");
    return true;
}

/* Per-triangle labels into c: the arrangement's cells, and the double sheets' ranges (those
 * are the polygoniser's triangle order: a triangle of a cut mesh takes its parent's). */
static bool label_triangles(ism_computed *c, const scratch *s)
{
    size_t nt = c->mesh.ntris;
    if (s->have_curves && nt) {
        c->tri_cell = malloc(nt * sizeof *c->tri_cell);
        if (!c->tri_cell)
            return false;
        memcpy(c->tri_cell, s->arr.tri_face, nt * sizeof *c->tri_cell);
    }
    const ism_locus *l = &c->locus;
    const uint32_t *parent = s->cut.tri_parent;
    if (l->nsheets && nt) {
        c->tri_sheet = malloc(nt);
        if (!c->tri_sheet)
            return false;
        for (size_t t = 0; t < nt; t++)
            c->tri_sheet[t] = ism_locus_sheet_of(l, parent ? parent[t] : t) != 0;
    }
    c->wire.tri_cell = c->tri_cell;
    c->wire.tri_sheet = c->tri_sheet;
    return true;
}

/* The drawing tolerance of the features JSON's mesh polylines (proto/features.h's digits
 * table): a part of the mesh's bound E, or on the depth path (no E) of the finest cell's edge, which sets
 * how far that mesh is from the surface there. */
static double draw_tolerance(const ism_request *req)
{
    if (req->poly.max_error > 0)
        return ISM_FEATURES_DRAW_TOL_REL * req->poly.max_error;
    return ISM_FEATURES_DRAW_TOL_REL * finest_cell(req);
}

/* Wire attributes (with the crease sides' normals), features and the surface's stats into c. */
static bool gather(const ism_request *req, const ism_tape *tape, ism_pipeline_result *r,
                   ism_computed *c, scratch *s)
{
    double t = ism_now_ms();
    const ism_analysis *an = s->have_analysis ? &s->an : NULL; /* none in a preview */
    if (!ism_wire_mesh_build(&c->mesh, an, ISM_ATTR_ALL, curvature_limit(req), &c->wire) ||
        !ism_wire_corner_normals(tape, an, &c->mesh, s->cut.edges ? &s->cut : NULL, &c->wire,
                                 &c->wire.ncorner_normals, &c->corner_at, &c->corner_normal,
                                 &c->corner_locus))
        return fail_with(r, 500, "no_memory", "%s", "out of memory preparing the mesh for the wire");
    c->wire.corner_at = c->corner_at;
    c->wire.corner_normal = c->corner_normal;
    c->wire.corner_locus = c->corner_locus;
    if (s->an.vertex_class && c->mesh.nverts) {
        c->vertex_class = malloc(c->mesh.nverts);
        if (!c->vertex_class)
            return fail_with(r, 500, "no_memory", "%s", "out of memory keeping the classes");
        memcpy(c->vertex_class, s->an.vertex_class, c->mesh.nverts);
    }
    c->wire.vertex_class = c->vertex_class;
    if (!label_triangles(c, s))
        return fail_with(r, 500, "no_memory", "%s", "out of memory labelling the triangles");
    c->empty = c->wire.live_triangles == 0;
    ism_mesh none;
    ism_mesh_init(&none);
    const ism_mesh *fm = c->empty ? &none : &c->mesh;
    if (!ism_features_build(c->empty ? NULL : an, &c->features))
        return fail_with(r, 500, "no_memory", "%s", "out of memory collecting the features");
    if (s->have_curves && !c->empty && !ism_features_add_arcs(&c->features, &s->arr, s->cf.fns))
        return fail_with(r, 500, "no_memory", "%s", "out of memory collecting the curves");
    c->features.locus = &c->locus;
    c->features.check = c->empty || !an ? NULL : &s->check;
    c->features.arrangement = s->have_curves ? &s->arr : NULL;
    c->features.cut_fns = s->cf.fns;
    c->features.draw_tol = draw_tolerance(req);
    c->features_json = ism_features_json(fm, &c->features, &c->features_len);
    c->features.check = NULL; /* the check does not outlive the computation */
    c->features.arrangement = NULL;
    c->features.cut_fns = NULL;
    if (!c->features_json)
        return fail_with(r, 500, "no_memory", "%s", "out of memory writing the features");
    c->timings_ms[ISM_TIME_FEATURES] = ism_now_ms() - t;
    ism_stats_input si;
    memset(&si, 0, sizeof si);
    si.poly = &s->ps;
    si.analysis = an;
    si.locus = req->preview ? NULL : &c->locus;
    si.check = an ? &s->check : NULL;
    si.conform = req->preview ? NULL : &s->cs;
    si.preview = req->preview;
    si.max_error = req->poly.max_error;
    si.remesh = s->have_remesh ? &s->rs : NULL;
    si.simplify = s->have_simplify ? &s->ss : NULL;
    c->stats_json = ism_stats_surface_json(&si, &c->stats_len);
    if (!c->stats_json)
        return fail_with(r, 500, "no_memory", "%s", "out of memory writing the stats");
    return true;
}

/* The computed surface of a prepared request (c->surface_key set by the caller). */
static bool compute(const ism_request *req, const ism_tape *tape, const ism_pipeline_limits *lim,
                    const ism_pipeline_hooks *hooks, ism_pipeline_result *r, ism_computed *c)
{
    scratch s;
    memset(&s, 0, sizeof s);
    bool ok = polygonise_and_analyse(req, tape, lim, hooks, r, c, &s) &&
              gather(req, tape, r, c, &s);
    ism_locus_check_free(&s.check);
    ism_arrangement_free(&s.arr);
    ism_cut_free(&s.cut);
    ism_curve_fns_free(&s.cf);
    if (s.have_analysis)
        ism_analysis_free(&s.an);
    return ok;
}

/* The computed surface's entry bytes into r->computed. */
static bool keep_computed(const ism_computed *c, ism_pipeline_result *r)
{
    ism_frame_builder b = {0};
    if (!ism_computed_write(c, &b)) {
        ism_frame_builder_free(&b);
        return fail_with(r, 500, "no_memory", "%s", "out of memory storing the computed mesh");
    }
    take(&r->computed, b.data, b.len);
    return true;
}

bool ism_pipeline_run(const char *json, size_t len, const char *format_override,
                      const ism_pipeline_limits *lim, const ism_pipeline_hooks *hooks,
                      ism_pipeline_result *r)
{
    ism_pipeline_limits dl;
    lim = limits_or_default(lim, &dl); /* the computation reads it too */
    double t_start = ism_now_ms(), decode_ms, compile_ms;
    ism_request req;
    ism_tape *tape = NULL;
    if (!prepare(json, len, format_override, lim, r, &req, &tape, &decode_ms, &compile_ms))
        return false;
    report(hooks, 0.02);
    ism_computed c;
    ism_computed_init(&c);
    snprintf(c.surface_key, sizeof c.surface_key, "%s", r->surface_key);
    c.timings_ms[ISM_TIME_DECODE] = decode_ms;
    c.timings_ms[ISM_TIME_COMPILE] = compile_ms;
    bool ok = compute(&req, tape, lim, hooks, r, &c) &&
              (!hooks || !hooks->keep_computed || keep_computed(&c, r)) &&
              encode(&req, &c, t_start, hooks, r);
    if (!ok) {
        ism_buf_free(&r->features);
        ism_buf_free(&r->stats);
        ism_buf_free(&r->computed);
    }
    ism_computed_free(&c);
    ism_tape_free(tape);
    ism_request_free(&req);
    return ok;
}

bool ism_pipeline_encode_stored(const char *json, size_t len, const char *format_override,
                                const ism_pipeline_limits *lim, const void *stored,
                                size_t stored_len, ism_pipeline_result *r)
{
    double t_start = ism_now_ms(), decode_ms, compile_ms;
    ism_request req;
    ism_tape *tape = NULL;
    if (!prepare(json, len, format_override, lim, r, &req, &tape, &decode_ms, &compile_ms))
        return false;
    ism_computed c;
    char why[96];
    bool ok = false;
    if (!ism_computed_read(stored, stored_len, &c, why, sizeof why)) {
        r->status = 0; /* not usable: the caller computes */
        ism_buf_free(&r->body);
    } else if (strcmp(c.surface_key, r->surface_key) != 0) {
        r->status = 0;
        ism_computed_free(&c);
    } else {
        ok = encode(&req, &c, t_start, NULL, r);
        ism_computed_free(&c);
    }
    if (!ok) {
        ism_buf_free(&r->features);
        ism_buf_free(&r->stats);
    }
    ism_tape_free(tape);
    ism_request_free(&req);
    return ok;
}
