/* request_compile.c — from a decoded request to what core runs: the compiled tape (with the
 * parser's error mapped back to the JSON path of the text it came from: $.expr, $.let.NAME,
 * $.params.NAME) and the polygoniser's options. */
#include "proto/request.h"

#include <stdio.h>
#include <string.h>

/* Where in the request the failing source was written. */
static void error_path(const ism_request *req, const ism_error *e, char *path, size_t n)
{
    if (e->where[0]) {
        for (size_t i = 0; i < req->nlets; i++)
            if (strcmp(req->lets[i].name, e->where) == 0) {
                snprintf(path, n, "%s", req->let_paths[i]);
                return;
            }
        for (size_t i = 0; i < req->nparams; i++)
            if (strcmp(req->params[i].name, e->where) == 0) {
                snprintf(path, n, "$.params.%s", e->where);
                return;
            }
    }
    snprintf(path, n, "%s", req->preset ? "$.preset" : "$.expr");
}

/* A compile error without a position is a bound on the whole expression (its size, its
 * node count, its nesting), which is a limit (422); everything else is a mistake in the
 * text (400). */
static bool is_limit(const ism_error *e)
{
    return e->line == 0 && e->column == 0;
}

ism_tape *ism_request_compile(const ism_request *req, ism_req_error *err)
{
    ism_expr_limits lim;
    ism_expr_limits_default(&lim);
    if (lim.max_source > ISM_REQ_MAX_SOURCE)
        lim.max_source = ISM_REQ_MAX_SOURCE;
    ism_error e;
    memset(&e, 0, sizeof e);
    ism_tape *t = ism_tape_compile(req->expr, req->params, req->nparams, req->lets, req->nlets,
                                   &lim, &e);
    if (t)
        return t;
    char path[160];
    error_path(req, &e, path, sizeof path);
    if (is_limit(&e)) {
        ism_req_error_set(err, 422, "over_limit", path, "%s", e.message);
    } else {
        char where[48] = "";
        if (e.line > 1)
            snprintf(where, sizeof where, "line %d, column %d", e.line, e.column);
        else
            snprintf(where, sizeof where, "column %d", e.column);
        ism_req_error_set(err, 400, "bad_expression", path, "%s: %s", where, e.message);
        err->line = e.line;
        err->column = e.column;
    }
    return NULL;
}

void ism_request_poly_options(const ism_request *req, ism_poly_options *o)
{
    ism_poly_options_default(o);
    memcpy(o->box, req->box, sizeof o->box);
    o->min_depth = req->min_depth;
    o->max_depth = req->max_depth;
    o->gradient_test = req->gradient;
    o->double_root_eps = req->double_root_eps;
    o->double_root_iters = req->double_root_iters;
    o->stitch_tol = req->stitch;
    o->flat_normal = req->flat_normal;
    o->flat_plane = req->flat_plane;
}
