/* curve_fns.c — from the decoded "curves" entries to cut functions: a plane n·p = d is
 * g = n·p − d, a level g = c is g − c, an intersection is g, a silhouette ∇f·d (core
 * evaluates it from f's Hessian). Each expression is compiled with the request's params and
 * lets, its errors naming $.curves[i].expr. */
#include "proto/curve_fns.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static const int cut_kind[ISM_REQ_CURVE_KIND_COUNT] = {
    ISM_CUT_SECTION, ISM_CUT_LEVEL, ISM_CUT_INTERSECTION, ISM_CUT_SILHOUETTE};

void ism_curve_fns_free(ism_curve_fns *c)
{
    for (size_t i = 0; i < c->ntapes; i++)
        ism_tape_free(c->tapes[i]);
    free(c->tapes);
    free(c->fns);
    memset(c, 0, sizeof *c);
}

/* The functions of entry i appended to out. */
static void add_entry(const ism_req_curve *c, size_t i, const ism_tape *t, ism_curve_fns *out)
{
    size_t nv = c->nvalues ? c->nvalues : 1;
    for (size_t k = 0; k < nv; k++) {
        ism_cut_fn *fn = &out->fns[out->n++];
        memset(fn, 0, sizeof *fn);
        fn->kind = cut_kind[c->kind];
        fn->source = (int)i;
        fn->index = (int)k;
        fn->tape = t;
        if (c->kind == ISM_REQ_CURVE_PLANE || c->kind == ISM_REQ_CURVE_SILHOUETTE)
            memcpy(fn->n, c->v, sizeof fn->n);
        fn->c = c->nvalues ? c->values[k] : 0;
    }
}

bool ism_curve_fns_build(const ism_request *req, ism_curve_fns *out, ism_req_error *err)
{
    memset(out, 0, sizeof *out);
    size_t total = 0;
    for (size_t i = 0; i < req->ncurves; i++)
        total += req->curves[i].nvalues ? req->curves[i].nvalues : 1;
    out->fns = calloc(total + 1, sizeof *out->fns);
    out->tapes = calloc(req->ncurves + 1, sizeof *out->tapes);
    if (!out->fns || !out->tapes) {
        ism_curve_fns_free(out);
        return ism_req_error_set(err, 500, "no_memory", "", "out of memory");
    }
    out->ntapes = req->ncurves;
    for (size_t i = 0; i < req->ncurves; i++) {
        const ism_req_curve *c = &req->curves[i];
        if (c->expr) {
            char path[160];
            snprintf(path, sizeof path, "$.curves[%zu].expr", i);
            if (!(out->tapes[i] = ism_request_compile_source(req, c->expr, path, err))) {
                ism_curve_fns_free(out);
                return false;
            }
        }
        add_entry(c, i, out->tapes[i], out);
    }
    return true;
}

bool ism_curve_fns_add_crease(ism_curve_fns *c, const ism_tape *f)
{
    ism_cut_fn crease;
    if (!ism_cut_crease_fn(f, &crease))
        return true;
    ism_cut_fn *fns = realloc(c->fns, (c->n + 1) * sizeof *fns);
    if (!fns)
        return false;
    memmove(fns + 1, fns, c->n * sizeof *fns);
    fns[0] = crease;
    c->fns = fns;
    c->n++;
    return true;
}
