/* request.h — a surface request as it crosses the wire: strict decoding of the JSON body into
 * typed, validated values (defaults filled in, presets expanded), compiling its expression,
 * its canonical form and the cache key, and the error JSON a client gets back.
 *
 * The request format is described for clients in proto/request.schema.json and
 * proto/openapi.yaml; keep the three in step. Decoding is strict: unknown fields, duplicate
 * keys, invalid UTF-8, trailing garbage and non-finite numbers are rejected, and every error
 * names the JSON path and the reason ("$.depth.max: 14 is above the limit 10").
 *
 * Statuses: 400 when the request is malformed (JSON syntax, unknown or missing field, wrong
 * type, inconsistent values, an expression that does not compile); 422 when a well-formed
 * value lies outside a published range or limit (depth, box size, bits, sizes). */
#ifndef ISM_REQUEST_H
#define ISM_REQUEST_H

#include <stddef.h>
#include <stdbool.h>
#include "core/expr/expr.h"
#include "core/octree/polygonise.h"
#include "core/remesh/quality_pass.h"

/* Published limits (also in request.schema.json and openapi.yaml). */
#define ISM_REQ_MAX_BYTES       (256 * 1024) /* request body */
#define ISM_REQ_MAX_MIN_DEPTH   6            /* subdivision regardless of flatness: 8^6 nodes */
#define ISM_REQ_DEFAULT_MAX_DEPTH_LIMIT 10   /* operator's limit unless set otherwise */
#define ISM_REQ_MAX_COORD       1e6          /* |box coordinate| */
#define ISM_REQ_MIN_SIDE_REL    1e-6         /* box side >= this * max(1, largest |coord|) */
#define ISM_REQ_MAX_NAME        63           /* parameter / let name bytes */
#define ISM_REQ_MAX_PARAMS      64
#define ISM_REQ_MAX_LETS        64
#define ISM_REQ_MAX_SOURCE      16384        /* bytes of one expression or let source */
#define ISM_REQ_MIN_ERROR_REL   1e-9         /* max_error >= this * the box diagonal: finer
                                                is below what doubles resolve there */
#define ISM_REQ_DEFAULT_ERROR_REL 1e-3       /* max_error when not given: this * the box
                                                diagonal. Accuracy is the request's knob
                                                (issue 15), so a request says how far its
                                                triangles may lie from f = 0 even when it
                                                says nothing: 1e-3 of the diagonal is under
                                                a pixel of a 1,000-pixel view of the box,
                                                and the dual mesher meets it on the smooth
                                                presets with good triangles (sphere preset:
                                                1,068 triangles, smallest angle 25.6 deg,
                                                where the depth path gave 5,384 and 0.97
                                                deg). "max_error": null: the depth path */
#define ISM_REQ_MAX_CURVES      256          /* curves: entries, and offsets + values in all
                                                (each one cut of the mesh) */

/* PNG: a thumbnail picture of the mesh (proto/thumbnail.h), encoded like any format. */
enum ism_format { ISM_FORMAT_DRC, ISM_FORMAT_GLB, ISM_FORMAT_PLY, ISM_FORMAT_OBJ,
                  ISM_FORMAT_STL, ISM_FORMAT_PNG, ISM_FORMAT_COUNT };

/* Per-vertex attributes a client may ask for (bit set). Draco unique ids: draco_encode.h. */
enum ism_attr {
    ISM_ATTR_NORMAL = 1 << 0,
    ISM_ATTR_MEAN_CURVATURE = 1 << 1,
    ISM_ATTR_GAUSS_CURVATURE = 1 << 2,
    ISM_ATTR_CLASS = 1 << 3,
};
#define ISM_ATTR_ALL (ISM_ATTR_NORMAL | ISM_ATTR_MEAN_CURVATURE | ISM_ATTR_GAUSS_CURVATURE | \
                      ISM_ATTR_CLASS)
/* What a request that leaves output.attributes out gets: what the viewer draws by default
 * (its shaded view, web/js/state.js COLOR_ATTRIBUTES). The curvatures and the class are sent
 * only when asked: the curvatures are a large part of a curved surface's bytes
 * (proto/draco_encode.cc). The key writes the resolved set, so leaving it out and naming it
 * give one key. */
#define ISM_ATTR_DEFAULT ISM_ATTR_NORMAL

/* Defaults of the output section. */
#define ISM_REQ_DEFAULT_POSITION_BITS 14
#define ISM_REQ_DEFAULT_NORMAL_BITS 10
#define ISM_REQ_DEFAULT_CURVATURE_BITS 14 /* 0 = float32 as computed (~2 B/triangle each) */

/* One entry of "curves": a stack of planes n·p = d, levels g = c, the intersection with
 * g = 0, or the silhouette seen along a direction. */
enum ism_req_curve_kind { ISM_REQ_CURVE_PLANE, ISM_REQ_CURVE_LEVELS, ISM_REQ_CURVE_SURFACE,
                          ISM_REQ_CURVE_SILHOUETTE, ISM_REQ_CURVE_KIND_COUNT };

typedef struct ism_req_curve {
    int kind;                  /* enum ism_req_curve_kind */
    double v[3];               /* plane normal or silhouette direction */
    double *values;            /* plane offsets or level values (owned) */
    size_t nvalues;
    char *expr;                /* g for levels and surface (owned), else NULL */
} ism_req_curve;

typedef struct ism_request {
    char *preset;              /* preset name, or NULL when the request wrote an expression */
    char *expr;                /* the expression (the preset's when preset is set) */
    ism_param *params;         /* every parameter (a preset's defaults filled in), names owned */
    size_t nparams;
    ism_let *lets;             /* in order; names and sources owned */
    size_t nlets;
    char **let_paths;          /* JSON path of each let's source, for errors */
    /* The polygoniser's options the request sets: box, min_depth, max_depth, max_error
     * (ISM_REQ_DEFAULT_ERROR_REL of the box diagonal when not given; 0 for "max_error":
     * null: then the flatness tolerances and depth.max decide) and the tolerances
     * (core/octree/tolerances.h); the others keep ism_poly_options_default's values. */
    ism_poly_options poly;
    int quality;               /* enum ism_quality: "raw" (default) or "good" (the quality
                                  pass after meshing, core/remesh/) */
    bool simplify;             /* "simplify": under max_error, the simplification after
                                  meshing (core/remesh/simplify.h) when true; false (the
                                  default, ism_simplify_after in core/octree/mesher.h) keeps
                                  the mesher's triangles; true without max_error is
                                  refused, 400 */
    enum ism_format format;
    int position_bits;         /* Draco position quantisation (6..24) */
    int normal_bits;           /* Draco normal quantisation (4..16) */
    int curvature_bits;        /* 0 (float32) or 8..24 */
    unsigned attributes;       /* enum ism_attr bits */
    ism_req_curve *curves;     /* the "curves" list (empty when not given) */
    size_t ncurves;
    bool plain_glb;            /* output.draco false: a glb without Draco (plain accessors) */
    bool preview;              /* "preview": true: a quick picture for live exploration — the
                                  polygoniser's mesh only (no search for hidden thin
                                  pieces, no singular locus, conformance, analysis or
                                  features); positions and normals are sent.
                                  Not with "curves" or "quality": "good" (400). */
} ism_request;

/* What the operator allows. */
typedef struct ism_request_limits {
    int max_depth;             /* highest depth.max accepted (capped at ISM_MAX_DEPTH_LIMIT) */
} ism_request_limits;

typedef struct ism_req_error {
    int status;                /* 400, 422 (or, from the pipeline, 499 / 500) */
    char code[32];             /* bad_json, bad_request, bad_expression, over_limit, ... */
    char path[160];            /* JSON path like "$.depth.max", "" when none */
    int line, column;          /* 1-based position in the JSON text or the expression; 0 none */
    char message[400];         /* one line, starting with the path when there is one */
    double max_error_that_fits; /* too_big under a bound: an E the same request was seen to
                                   mesh within the triangle budget; 0 none */
} ism_req_error;

/* The error bound a request (or the CLI) gets when it does not give one:
 * ISM_REQ_DEFAULT_ERROR_REL of box's diagonal. */
double ism_request_default_error(const double box[6]);

/* A bound E for box: above 0, at least ISM_REQ_MIN_ERROR_REL of its diagonal and at most the
 * diagonal, or a 422 naming path ("$.max_error"; the CLI's "--max-error") and the limit. */
bool ism_request_error_in_range(double e, const double box[6], const char *path,
                                ism_req_error *err);

/* v > 0 to three significant digits into buf, rounded up (dir 1), down (-1) or to nearest (0),
 * returning buf: a limit or a bound in a message, without 17 digits of a box diagonal. */
const char *ism_three_digits(double v, int dir, char buf[32]);

/* Decodes and validates a JSON request. lim may be NULL for the default limits. On failure
 * returns false, fills err, and leaves req empty (safe to free). */
bool ism_request_decode(const char *json, size_t len, const ism_request_limits *lim,
                        ism_request *req, ism_req_error *err);

void ism_request_free(ism_request *req);

/* Replaces the format by name ("drc", "glb", "ply", "obj", "stl", "png"); 400 on an unknown name. */
bool ism_request_set_format(ism_request *req, const char *name, ism_req_error *err);

const char *ism_format_name(enum ism_format f);
const char *ism_format_mime(enum ism_format f);
/* The format called name, or -1. */
int ism_format_lookup(const char *name);
/* The MIME type of the format called name (application/octet-stream when unknown). The one
 * list of formats and their types is proto/format.c. */
const char *ism_format_mime_of(const char *name);

/* Compiles the request's expression (with its params and lets). On failure fills err (400
 * with the expression's path and the parser's line and column; 422 for a size limit). */
ism_tape *ism_request_compile(const ism_request *req, ism_req_error *err);

/* Compiles src (written at JSON path `path`) with the request's params and lets; errors as
 * ism_request_compile's, naming path. */
ism_tape *ism_request_compile_source(const ism_request *req, const char *src, const char *path,
                                     ism_req_error *err);

/* The polygoniser's options for this request (budget fields left at their defaults). */
void ism_request_poly_options(const ism_request *req, ism_poly_options *o);

/* The canonical request: a valid request JSON (expression form, presets written out, every
 * default filled in, numbers in shortest round-trip form, keys in a fixed order, no format).
 * Running it again gives the same mesh. Returns malloc'd text, NULL when out of memory. */
char *ism_request_canonical(const ism_request *req, size_t *len);

/* The text the cache key hashes: ISM_MESHER_VERSION, the compiled tape's canonical text
 * (parameters folded in, so a preset and its written-out expression agree), box, depths,
 * tolerances and the encoding options that change the bytes (bits only for attributes that
 * are sent). Never the format. malloc'd; NULL when out of memory. */
char *ism_request_key_material(const ism_request *req, const ism_tape *tape, size_t *len);

/* Digits of every key (mesh and surface keys): BLAKE2b-256 in lowercase hex. */
#define ISM_KEY_HEX_LEN 64

/* BLAKE2b-256 (libsodium crypto_generichash) of the key material, as 64 hex digits + NUL.
 * False when out of memory or libsodium fails to start. */
bool ism_request_key(const ism_request *req, const ism_tape *tape, char hex[ISM_KEY_HEX_LEN + 1]);

/* The surface key: the same without the encoding options (bits, attributes, Draco speed).
 * It names the computed surface (proto/computed.h) that every encoding is made from. */
char *ism_request_surface_key_material(const ism_request *req, const ism_tape *tape,
                                       size_t *len);
bool ism_request_surface_key(const ism_request *req, const ism_tape *tape,
                             char hex[ISM_KEY_HEX_LEN + 1]);

/* True for exactly ISM_KEY_HEX_LEN lowercase hex digits (the one key check). */
bool ism_key_valid(const char *key);

/* Error helpers. ism_req_error_set formats the message; the path, when not empty, is
 * prefixed to it ("$.box: ..."). Returns false for `return ism_req_error_set(...)`. */
bool ism_req_error_set(ism_req_error *err, int status, const char *code, const char *path,
                       const char *fmt, ...) __attribute__((format(printf, 5, 6)));

/* The error JSON: {"error": {"code", "message", "path"?, "line"?, "column"?,
 * "max_error_that_fits"?}}. malloc'd. */
char *ism_req_error_json(const ism_req_error *err, size_t *len);

#endif
