/* pipeline.h — one surface request from JSON to bytes: decode and validate (proto), compile
 * the expression, polygonise, analyse (core), encode in the requested format (proto).
 * Shared by `isomesh request.json -o out.drc` and by the worker processes of isomeshd.
 *
 * The cache key names the mesh and its encoding options but not the file format, so one key
 * has one .drc, .glb, .ply, .obj and .stl. The surface key names the surface and its accuracy
 * only: a run computes the surface once (polygonise, analyse, features: proto/computed.h),
 * then encodes it; with keep_computed the computed surface comes back too, and
 * ism_pipeline_encode_stored makes any other format, quantisation or attribute set of that
 * surface from it without polygonising (the daemon's cache entry "<surface key>.mesh").
 * Both paths share the encoder, so the bytes are the same either way.
 *
 * An empty surface (no triangle) is status 200 with: an empty body for drc, a valid glTF with
 * one empty scene for glb, PLY/OBJ/STL files with no vertex, and "empty": true in the stats.
 * The features JSON (format: proto/features.h) comes with every successful run, whatever the
 * format. Error bodies: {"error": {"code", "message", "path"?, "line"?, "column"?}}
 * (proto/request.h). */
#ifndef ISM_PIPELINE_H
#define ISM_PIPELINE_H

#include <stddef.h>
#include <stdbool.h>

/* A heap byte buffer (free with ism_buf_free). */
typedef struct ism_buf {
    unsigned char *data;
    size_t len, cap;
} ism_buf;

void ism_buf_free(ism_buf *b);

/* Appends n bytes to the buffer ctx (an ism_buf *), growing it; returns n, or 0 when out of
 * memory. Shaped as core's ism_write_fn, so mesh writers can fill a buffer. */
size_t ism_buf_write(void *ctx, const void *p, size_t n);

/* Limits the operator sets on the daemon (flags) or the command line; a request over one
 * gets status 422 naming the limit. */
typedef struct ism_pipeline_limits {
    int max_depth;            /* default 10 */
    size_t max_triangles;     /* default 4,000,000 */
    size_t max_memory;        /* bytes for the polygoniser (default 2 GiB) */
    int threads;              /* polygoniser threads (0 = cores) */
} ism_pipeline_limits;

void ism_pipeline_limits_default(ism_pipeline_limits *l);

typedef struct ism_pipeline_result {
    int status;               /* 200 ok; 400 bad request; 422 over a limit; 500 internal */
    char key[65];             /* hex cache key (set as soon as the request is decoded) */
    char surface_key[65];     /* hex key of the surface alone (no encoding options) */
    bool polygonised;         /* this run polygonised (not encoded from a stored surface) */
    char format[8];           /* "drc", "glb", "ply", "obj", "stl" */
    const char *content_type; /* MIME type of body */
    ism_buf body;             /* the mesh file, or the error JSON when status != 200 */
    ism_buf stats;            /* stats JSON: polygoniser + analysis figures, key, timings */
    ism_buf features;         /* non-manifold features JSON (curves, points) for the viewer */
    ism_buf canonical;        /* the canonical request JSON (defaults filled in) */
    ism_buf computed;         /* the computed surface's entry (hooks->keep_computed only) */
} ism_pipeline_result;

void ism_pipeline_result_free(ism_pipeline_result *r);

/* Progress in [0, 1]; cancel polled often (non-zero stops the run with status 499);
 * deadline_ms (an ism_now_ms() time, 0 = none): the singular stages stop past it and the
 * stats and features say the locus is incomplete (the mesh is still answered). */
typedef struct ism_pipeline_hooks {
    void (*progress)(void *ctx, double fraction);
    void *ctx;
    const volatile int *cancel;
    double deadline_ms;
    bool keep_computed;       /* fill result.computed (proto/computed.h's entry) */
} ism_pipeline_hooks;

/* Runs one request. format_override ("drc", ...) replaces the request's format when not NULL.
 * Always fills r (status and body say what happened); returns true when status is 200. */
bool ism_pipeline_run(const char *json, size_t len, const char *format_override,
                      const ism_pipeline_limits *lim, const ism_pipeline_hooks *hooks,
                      ism_pipeline_result *r);

/* Encodes the request from a stored computed surface (an entry ism_pipeline_run returned in
 * computed) instead of polygonising. Status 0 (false, nothing else filled but the keys) when
 * the entry is not usable — another version, damaged, or another surface: the caller then
 * runs ism_pipeline_run. Otherwise like ism_pipeline_run. */
bool ism_pipeline_encode_stored(const char *json, size_t len, const char *format_override,
                                const ism_pipeline_limits *lim, const void *stored,
                                size_t stored_len, ism_pipeline_result *r);

/* Decodes and validates only (no geometry): fills key, format, canonical, or status 400/422
 * with the error JSON in body. Lets the daemon answer cache hits without a worker. */
bool ism_pipeline_key(const char *json, size_t len, const char *format_override,
                      const ism_pipeline_limits *lim, ism_pipeline_result *r);

#endif
