/* compile.c — ism_tape_compile: checks the request against the limits, binds parameters
 * (as folded constants) and lets (in order, each a shared sub-graph), parses the main
 * expression and lowers the graph to a tape. */
#include "core/expr/expr.h"
#include "core/expr/emit.h"
#include "core/expr/graph.h"
#include "core/expr/names.h"
#include "core/expr/parser.h"

#include <locale.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <string.h>

void ism_expr_limits_default(ism_expr_limits *lim)
{
    lim->max_source = 16384;
    lim->max_nodes = 20000;
    lim->max_depth = 200;
    lim->max_exponent = 64;
    lim->max_lets = 64;
    lim->max_params = 64;
}

__attribute__((format(printf, 3, 4)))
static bool fail_in(ism_error *err, const char *where, const char *fmt, ...)
{
    if (!err)
        return false;
    memset(err, 0, sizeof *err);
    snprintf(err->where, sizeof err->where, "%s", where);
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(err->message, sizeof err->message, fmt, ap);
    va_end(ap);
    return false;
}

static bool check_length(const char *src, const char *where, const ism_expr_limits *lim,
                         ism_error *err, size_t *len)
{
    *len = strnlen(src, lim->max_source + 1);
    if (*len > lim->max_source)
        return fail_in(err, where, "expression too long: more than %zu bytes (limit)",
                       lim->max_source);
    return true;
}

static bool bind_params(ism_parse_ctx *c, const ism_param *params, size_t nparams)
{
    char msg[160];
    for (size_t i = 0; i < nparams; i++) {
        const char *name = params[i].name;
        if (!name)
            return fail_in(c->err, "", "parameter number %zu has no name", i + 1);
        size_t len = strnlen(name, 64);
        if (!ism_names_check_new(c->names, name, len, "parameter", msg, sizeof msg))
            return fail_in(c->err, "", "%s", msg);
        if (!isfinite(params[i].value))
            return fail_in(c->err, "", "parameter '%s' is not a finite number", name);
        uint32_t node = ism_graph_const(c->graph, params[i].value);
        if (node == ISM_G_NONE || !ism_names_add(c->names, name, len, ISM_N_PARAM, node))
            return fail_in(c->err, "", "out of memory");
    }
    return true;
}

static bool bind_lets(ism_parse_ctx *c, const ism_let *lets, size_t nlets)
{
    char msg[160];
    for (size_t i = 0; i < nlets; i++) {
        const char *name = lets[i].name;
        if (!name)
            return fail_in(c->err, "", "let number %zu has no name", i + 1);
        size_t len = strnlen(name, 64);
        char where[64];
        snprintf(where, sizeof where, "%.*s", (int)len, name);
        if (!ism_names_check_new(c->names, name, len, "let", msg, sizeof msg))
            return fail_in(c->err, where, "%s", msg);
        if (!lets[i].source)
            return fail_in(c->err, where, "the let has no expression");
        size_t srclen;
        if (!check_length(lets[i].source, where, c->lim, c->err, &srclen))
            return false;
        c->lets++;
        uint32_t node = ism_parse_source(c, lets[i].source, srclen, where, false);
        if (node == ISM_G_NONE)
            return false;
        if (!ism_names_add(c->names, name, len, ISM_N_LET, node))
            return fail_in(c->err, where, "out of memory");
    }
    return true;
}

static bool check_counts(size_t nparams, size_t nlets, const ism_expr_limits *lim,
                         ism_error *err)
{
    if (nparams > lim->max_params)
        return fail_in(err, "", "too many parameters: %zu (limit %zu)", nparams,
                       lim->max_params);
    if (nlets > lim->max_lets)
        return fail_in(err, "", "too many lets: %zu (limit %zu)", nlets, lim->max_lets);
    return true;
}

ism_tape *ism_tape_compile(const char *source,
                           const ism_param *params, size_t nparams,
                           const ism_let *lets, size_t nlets,
                           const ism_expr_limits *lim, ism_error *err)
{
    ism_expr_limits defaults;
    if (!lim) {
        ism_expr_limits_default(&defaults);
        lim = &defaults;
    }
    if (err)
        memset(err, 0, sizeof *err);
    if (!source) {
        ism_error_set(err, "no expression given");
        return NULL;
    }
    if ((nparams && !params) || (nlets && !lets)) {
        ism_error_set(err, "parameters or lets counted but not given");
        return NULL;
    }
    size_t srclen;
    if (!check_counts(nparams, nlets, lim, err) || !check_length(source, "", lim, err, &srclen))
        return NULL;
    locale_t c_locale = newlocale(LC_NUMERIC_MASK, "C", (locale_t)0);
    if (c_locale == (locale_t)0) {
        ism_error_set(err, "out of memory");
        return NULL;
    }
    ism_graph graph;
    ism_names names = { 0 };
    ism_graph_init(&graph, 4 * lim->max_nodes + nparams + 64);
    ism_parse_ctx c = { .graph = &graph, .names = &names, .lim = lim, .nodes = 0, .lets = 0,
                        .all_lets = lets, .nall_lets = nlets, .c_locale = c_locale,
                        .err = err };
    ism_tape *t = NULL;
    if (bind_params(&c, params, nparams) && bind_lets(&c, lets, nlets)) {
        uint32_t root = ism_parse_source(&c, source, srclen, "", true);
        if (root != ISM_G_NONE) {
            t = ism_emit_tape(&graph, root);
            if (!t)
                ism_error_set(err, "out of memory compiling the expression");
        }
    }
    ism_names_free(&names);
    ism_graph_free(&graph);
    freelocale(c_locale);
    return t;
}
