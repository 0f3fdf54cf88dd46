/* request_compile.c — from a decoded request to what core runs: the compiled tape (with the
 * parser's error mapped back to the JSON path of the text it came from: $.expr, $.let.NAME,
 * $.params.NAME) and the polygoniser's options. */
#include "proto/request.h"

#include <stdio.h>
#include <string.h>

/* The parameter a positionless message is about ("parameter 'x' would shadow ..."), or -1. */
static long param_named_in(const ism_request *req, const char *message)
{
    if (strncmp(message, "parameter", 9) != 0)
        return -1;
    const char *q = strchr(message, '\'');
    const char *e = q ? strchr(q + 1, '\'') : NULL;
    if (!e)
        return -1;
    for (size_t i = 0; i < req->nparams; i++)
        if (strlen(req->params[i].name) == (size_t)(e - q - 1) &&
            strncmp(req->params[i].name, q + 1, (size_t)(e - q - 1)) == 0)
            return (long)i;
    return -1;
}

/* Where in the request the failing source was written (fallback: the source's own path). */
static void error_path(const ism_request *req, const ism_error *e, const char *fallback,
                       char *path, size_t n)
{
    if (e->where[0]) {
        for (size_t i = 0; i < req->nlets; i++)
            if (strcmp(req->lets[i].name, e->where) == 0) {
                snprintf(path, n, "%s", req->let_paths[i]);
                return;
            }
    }
    long p = e->where[0] ? -1 : param_named_in(req, e->message);
    if (p >= 0) {
        snprintf(path, n, "$.params.%s", req->params[p].name);
        return;
    }
    snprintf(path, n, "%s", fallback);
}

/* The parser says "(limit ...)" for every bound on size, nesting, exponent and counts: those
 * are limits (422); everything else is a mistake in the text (400). */
static bool is_limit(const ism_error *e)
{
    return strstr(e->message, "limit") != NULL;
}

ism_tape *ism_request_compile(const ism_request *req, ism_req_error *err)
{
    return ism_request_compile_source(req, req->expr, req->preset ? "$.preset" : "$.expr", err);
}

ism_tape *ism_request_compile_source(const ism_request *req, const char *src, const char *at,
                                     ism_req_error *err)
{
    ism_expr_limits lim;
    ism_expr_limits_default(&lim);
    if (lim.max_source > ISM_REQ_MAX_SOURCE)
        lim.max_source = ISM_REQ_MAX_SOURCE;
    ism_error e;
    memset(&e, 0, sizeof e);
    ism_tape *t = ism_tape_compile(src, req->params, req->nparams, req->lets, req->nlets,
                                   &lim, &e);
    if (t)
        return t;
    char path[160];
    error_path(req, &e, at, path, sizeof path);
    if (strstr(e.message, "out of memory")) {
        ism_req_error_set(err, 500, "no_memory", path, "%s", e.message);
    } else if (e.line == 0 && e.column == 0) {
        ism_req_error_set(err, is_limit(&e) ? 422 : 400,
                          is_limit(&e) ? "over_limit" : "bad_expression", path, "%s",
                          e.message);
    } else {
        char where[48] = "";
        if (e.line > 1)
            snprintf(where, sizeof where, "line %d, column %d", e.line, e.column);
        else
            snprintf(where, sizeof where, "column %d", e.column);
        ism_req_error_set(err, is_limit(&e) ? 422 : 400,
                          is_limit(&e) ? "over_limit" : "bad_expression", path, "%s: %s",
                          where, e.message);
        err->line = e.line;
        err->column = e.column;
    }
    return NULL;
}

void ism_request_poly_options(const ism_request *req, ism_poly_options *o)
{
    *o = req->poly;
}
