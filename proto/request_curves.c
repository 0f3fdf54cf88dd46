/* request_curves.c — the request's "curves" list: strict decoding of each entry (a plane
 * stack, levels of g, the intersection with g = 0, a silhouette) with the JSON path of every
 * bad value, and its written-out form for the canonical request and the cache key. */
#include "proto/request_internal.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

static const char *const kind_names[ISM_REQ_CURVE_KIND_COUNT] = {"plane", "levels", "surface",
                                                                 "silhouette"};

static bool bad(ism_req_error *err, const char *path, const char *what)
{
    return ism_req_error_set(err, 400, "bad_request", path, "%s", what);
}

/* [a, b, c], not all zero. */
static bool read_vec3(const json_t *v, const char *path, double out[3], ism_req_error *err)
{
    if (!json_is_array(v) || json_array_size(v) != 3)
        return bad(err, path, "expected an array of 3 numbers");
    for (size_t k = 0; k < 3; k++) {
        char p[160];
        ism_rq_path_index(p, path, k);
        if (!ism_rq_read_number(json_array_get(v, k), p, &out[k], err))
            return false;
    }
    if (out[0] == 0 && out[1] == 0 && out[2] == 0)
        return bad(err, path, "the vector must not be zero");
    return true;
}

/* A non-empty array of numbers; *budget counts the cuts left. */
static bool read_values(const json_t *v, const char *path, ism_req_curve *c, size_t *budget,
                        ism_req_error *err)
{
    if (!json_is_array(v))
        return bad(err, path, "expected an array of numbers");
    size_t n = json_array_size(v);
    if (n == 0)
        return bad(err, path, "the list is empty (give at least one value)");
    if (n > *budget)
        return ism_req_error_set(err, 400, "bad_request", path,
                                 "more than %d curves in all", ISM_REQ_MAX_CURVES);
    *budget -= n;
    if (!(c->values = malloc(n * sizeof *c->values)))
        return ism_req_error_set(err, 500, "no_memory", "", "out of memory");
    for (size_t i = 0; i < n; i++) {
        char p[160];
        ism_rq_path_index(p, path, i);
        if (!ism_rq_read_number(json_array_get(v, i), p, &c->values[c->nvalues++], err))
            return false;
    }
    return true;
}

static bool read_expr(const json_t *v, const char *path, ism_req_curve *c, ism_req_error *err)
{
    if (!v)
        return bad(err, path, "missing the expression g(x, y, z)");
    if (!json_is_string(v) || !*json_string_value(v))
        return bad(err, path, "expected a non-empty expression string");
    if (strlen(json_string_value(v)) > ISM_REQ_MAX_SOURCE)
        return ism_req_error_set(err, 422, "over_limit", path,
                                 "the expression is longer than %d bytes", ISM_REQ_MAX_SOURCE);
    if (!(c->expr = strdup(json_string_value(v))))
        return ism_req_error_set(err, 500, "no_memory", "", "out of memory");
    return true;
}

static int kind_of(const json_t *v)
{
    for (int k = 0; json_is_string(v) && k < ISM_REQ_CURVE_KIND_COUNT; k++)
        if (strcmp(json_string_value(v), kind_names[k]) == 0)
            return k;
    return -1;
}

static bool decode_entry(const json_t *v, const char *path, ism_req_curve *c, size_t *budget,
                         ism_req_error *err)
{
    static const char *const fields[ISM_REQ_CURVE_KIND_COUNT][4] = {
        {"kind", "normal", "offsets", NULL}, {"kind", "expr", "values", NULL},
        {"kind", "expr", NULL, NULL}, {"kind", "direction", NULL, NULL}};
    char p[160];
    if (!json_is_object(v))
        return bad(err, path, "expected an object with a \"kind\"");
    ism_rq_path_key(p, path, "kind");
    c->kind = kind_of(json_object_get(v, "kind"));
    if (c->kind < 0)
        return bad(err, p, "expected one of: plane, levels, surface, silhouette");
    if (!ism_rq_check_fields(v, path, fields[c->kind], err))
        return false;
    const char *vec = c->kind == ISM_REQ_CURVE_PLANE ? "normal" : "direction";
    const char *list = c->kind == ISM_REQ_CURVE_PLANE ? "offsets" : "values";
    if (c->kind == ISM_REQ_CURVE_PLANE || c->kind == ISM_REQ_CURVE_SILHOUETTE) {
        ism_rq_path_key(p, path, vec);
        if (!json_object_get(v, vec))
            return bad(err, p, "missing");
        if (!read_vec3(json_object_get(v, vec), p, c->v, err))
            return false;
    }
    if (c->kind == ISM_REQ_CURVE_LEVELS || c->kind == ISM_REQ_CURVE_SURFACE) {
        ism_rq_path_key(p, path, "expr");
        if (!read_expr(json_object_get(v, "expr"), p, c, err))
            return false;
    }
    if (c->kind == ISM_REQ_CURVE_PLANE || c->kind == ISM_REQ_CURVE_LEVELS) {
        ism_rq_path_key(p, path, list);
        if (!json_object_get(v, list))
            return bad(err, p, "missing");
        return read_values(json_object_get(v, list), p, c, budget, err);
    }
    if (*budget == 0)
        return ism_req_error_set(err, 400, "bad_request", path, "more than %d curves in all",
                                 ISM_REQ_MAX_CURVES);
    --*budget;
    return true;
}

bool ism_request_decode_curves(const json_t *v, ism_request *req, ism_req_error *err)
{
    if (!json_is_array(v))
        return ism_req_error_set(err, 400, "bad_request", "$.curves",
                                 "expected an array, got %s", ism_rq_type_name(v));
    size_t n = json_array_size(v), budget = ISM_REQ_MAX_CURVES;
    if (n > ISM_REQ_MAX_CURVES)
        return ism_req_error_set(err, 400, "bad_request", "$.curves",
                                 "%zu curves, more than the limit %d", n, ISM_REQ_MAX_CURVES);
    if (n && !(req->curves = calloc(n, sizeof *req->curves)))
        return ism_req_error_set(err, 500, "no_memory", "", "out of memory");
    for (size_t i = 0; i < n; i++) {
        char p[160];
        ism_rq_path_index(p, "$.curves", i);
        req->ncurves = i + 1;
        if (!decode_entry(json_array_get(v, i), p, &req->curves[i], &budget, err))
            return false;
    }
    return true;
}

void ism_request_free_curves(ism_request *req)
{
    for (size_t i = 0; i < req->ncurves; i++) {
        free(req->curves[i].values);
        free(req->curves[i].expr);
    }
    free(req->curves);
    req->curves = NULL;
    req->ncurves = 0;
}

/* The expression as written, or (tape_text) its compiled canonical text. */
static void write_expr(ism_jw *w, const ism_request *req, const char *src, bool tape_text)
{
    ism_req_error e;
    ism_tape *t = tape_text ? ism_request_compile_source(req, src, "", &e) : NULL;
    size_t n = t ? ism_tape_canonical(t, NULL, 0) : 0;
    char *text = n ? malloc(n + 1) : NULL;
    if (text && ism_tape_canonical(t, text, n + 1) == n)
        ism_jw_string_n(w, text, n);
    else
        ism_jw_string(w, src);
    free(text);
    ism_tape_free(t);
}

void ism_request_write_curves(ism_jw *w, const ism_request *req, bool tape_text)
{
    if (!req->ncurves)
        return;
    ism_jw_key(w, "curves");
    ism_jw_array(w);
    for (size_t i = 0; i < req->ncurves; i++) {
        const ism_req_curve *c = &req->curves[i];
        ism_jw_object(w);
        ism_jw_key(w, "kind");
        ism_jw_string(w, kind_names[c->kind]);
        if (c->kind == ISM_REQ_CURVE_PLANE || c->kind == ISM_REQ_CURVE_SILHOUETTE) {
            ism_jw_key(w, c->kind == ISM_REQ_CURVE_PLANE ? "normal" : "direction");
            ism_jw_array(w);
            for (int k = 0; k < 3; k++)
                ism_jw_number(w, c->v[k]);
            ism_jw_array_end(w);
        }
        if (c->expr) {
            ism_jw_key(w, "expr");
            write_expr(w, req, c->expr, tape_text);
        }
        if (c->nvalues) {
            ism_jw_key(w, c->kind == ISM_REQ_CURVE_PLANE ? "offsets" : "values");
            ism_jw_array(w);
            for (size_t k = 0; k < c->nvalues; k++)
                ism_jw_number(w, c->values[k]);
            ism_jw_array_end(w);
        }
        ism_jw_object_end(w);
    }
    ism_jw_array_end(w);
}
