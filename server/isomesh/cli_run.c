/* cli_run.c — what the `isomesh` command does once its flags are read: find the surface
 * (flags, a surfaces file, or a built-in preset), compile and polygonise it, analyse the
 * mesh, write the file atomically and print the statistics; or run a request file through
 * the service pipeline; or list the built-in surfaces. */
#include "server/isomesh/cli.h"
#include "core/util/clock.h"
#include "core/util/parallel.h"
#include "core/util/side.h"

#include "core/analysis/analysis.h"
#include "core/mesh/write_mesh.h"
#include "core/octree/mesher.h"
#include "proto/presets.h"
#include "proto/features.h"
#include "proto/request.h"
#include "proto/stats.h"
#include "core/singular/check.h"
#include "core/singular/surface.h"
#include "core/remesh/quality_pass.h"
#include "server/common/fit_error.h"
#include "server/common/fd_io.h"
#include "server/common/pipeline.h"

#include <ctype.h>
#include <errno.h>
#include <jansson.h>
#include <limits.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <time.h>
#include <unistd.h>

#define MAX_REQUEST_FILE (1 << 20)

void ism_cli_run_free(ism_cli_run *run)
{
    for (size_t i = 0; i < run->nparams; i++)
        free((char *)run->params[i].name);
    for (size_t i = 0; i < run->nlets; i++) {
        free((char *)run->lets[i].name);
        free((char *)run->lets[i].source);
    }
    free(run->params);
    free(run->lets);
    if (run->surfaces_json)
        json_decref(run->surfaces_json);
    memset(run, 0, sizeof *run);
}

bool ism_cli_write_file(const char *path, const void *data, size_t len)
{
    char err[PATH_MAX + 200];
    if (ism_replace_file(path, data, len, 0644, err, sizeof err))
        return true;
    fprintf(stderr, "isomesh: cannot write %s\n", err);
    return false;
}

/* ---- the surface ------------------------------------------------------------------- */

static bool has_param(const ism_cli_run *run, const char *name)
{
    for (size_t i = 0; i < run->nparams; i++)
        if (strcmp(run->params[i].name, name) == 0)
            return true;
    return false;
}

/* Adds a default that the command line did not set. */
static bool default_param(ism_cli_run *run, const char *name, double value)
{
    if (has_param(run, name))
        return true;
    char buf[96];
    snprintf(buf, sizeof buf, "%s=%.17g", name, value);
    return ism_cli_add_param(run, buf);
}

/* Lets given on the command line come after the surface's own (they may use them). */
static bool prepend_let(ism_cli_run *run, size_t at, const char *name, const char *src)
{
    char *buf = malloc(strlen(name) + strlen(src) + 2);
    if (!buf)
        return false;
    sprintf(buf, "%s=%s", name, src);
    bool ok = ism_cli_add_let(run, buf);
    free(buf);
    if (!ok)
        return false;
    ism_let last = run->lets[run->nlets - 1];
    memmove(run->lets + at + 1, run->lets + at, (run->nlets - 1 - at) * sizeof *run->lets);
    run->lets[at] = last;
    return true;
}

/* A -p that the built-in surface does not have is refused, as a request's "params" is:
 * a misspelt name would otherwise be ignored without a word. */
static bool preset_has_params(const ism_cli_run *run, const ism_preset *p)
{
    for (size_t i = 0; i < run->nparams; i++) {
        if (ism_preset_has_param(p, run->params[i].name))
            continue;
        char names[256];
        ism_preset_param_names(p, names, sizeof names);
        fprintf(stderr, "isomesh: --param %s: the surface '%s' has no parameter %s (it has %s)\n",
                run->params[i].name, p->name, run->params[i].name, names);
        return false;
    }
    return true;
}

static bool use_preset(ism_cli_run *run, const ism_preset *p)
{
    run->expr = p->expr;
    run->preset = p;
    for (size_t i = 0; i < p->nlets; i++)
        if (!prepend_let(run, i, p->lets[i].name, p->lets[i].source))
            return false;
    for (size_t i = 0; i < p->nparams; i++)
        if (!default_param(run, p->params[i].name, p->params[i].value))
            return false;
    if (!run->box_given)
        memcpy(run->options.box, p->box, sizeof p->box);
    if (!run->depth_given) {
        run->options.min_depth = p->min_depth;
        run->options.max_depth = p->max_depth;
    }
    return true;
}

/* Reports a surfaces file of the wrong shape (what was expected where) and returns 2. */
static int shape_error(const ism_cli_run *run, const char *where, const char *expected)
{
    fprintf(stderr, "isomesh: %s: %s: expected %s (see examples/surfaces.json)\n",
            run->surfaces_file, where, expected);
    return 2;
}

/* The entry's let (an object of strings, in order) and params (an object of numbers). */
static int surface_lets_and_params(ism_cli_run *run, json_t *s, const char *where)
{
    char at[160];
    json_t *let = json_object_get(s, "let"), *params = json_object_get(s, "params"), *v;
    const char *key;
    if (let && !json_is_object(let)) {
        snprintf(at, sizeof at, "%s.let", where);
        return shape_error(run, at, "an object of named expressions (strings)");
    }
    if (params && !json_is_object(params)) {
        snprintf(at, sizeof at, "%s.params", where);
        return shape_error(run, at, "an object of numbers");
    }
    size_t n = 0;
    json_object_foreach(let, key, v) {
        snprintf(at, sizeof at, "%s.let.%.60s", where, key);
        if (!json_is_string(v))
            return shape_error(run, at, "a string (an expression)");
        if (!prepend_let(run, n++, key, json_string_value(v)))
            return shape_error(run, at, "a name of letters, digits and _ (at most 63 bytes)");
    }
    json_object_foreach(params, key, v) {
        snprintf(at, sizeof at, "%s.params.%.60s", where, key);
        if (!json_is_number(v))
            return shape_error(run, at, "a number");
        if (!default_param(run, key, json_number_value(v)))
            return shape_error(run, at, "a name of letters, digits and _ (at most 63 bytes)");
    }
    return 0;
}

/* The entry's box: six numbers, each min below its max. */
static int surface_box(ism_cli_run *run, json_t *s, const char *where)
{
    json_t *box = json_object_get(s, "box");
    if (!box)
        return 0;
    char at[160];
    snprintf(at, sizeof at, "%s.box", where);
    bool ok = json_array_size(box) == 6;
    for (size_t k = 0; ok && k < 6; k++)
        ok = json_is_number(json_array_get(box, k));
    for (size_t k = 0; ok && k < 3; k++)
        ok = json_number_value(json_array_get(box, k)) <
             json_number_value(json_array_get(box, k + 3));
    if (!ok)
        return shape_error(run, at, "six numbers xmin ymin zmin xmax ymax zmax, each min < max");
    if (!run->box_given)
        for (int k = 0; k < 6; k++)
            run->options.box[k] = json_number_value(json_array_get(box, (size_t)k));
    return 0;
}

/* A surface from a file shaped like examples/surfaces.json (and shared/surfaces.json):
 * {"surfaces": [{"name", "expr", "params"?, "let"?, "box"?}, ...]}. */
static int use_surfaces_file(ism_cli_run *run)
{
    json_error_t je;
    json_t *root = json_load_file(run->surfaces_file, JSON_REJECT_DUPLICATES, &je);
    if (!root && je.line < 1) { /* not read at all: no position to give */
        fprintf(stderr, "isomesh: %s: cannot read the surfaces file: %s\n", run->surfaces_file,
                je.text);
        return 2;
    }
    if (!root) {
        fprintf(stderr, "isomesh: %s: line %d, column %d: %s\n", run->surfaces_file, je.line,
                je.column, je.text);
        return 2;
    }
    run->surfaces_json = root;
    json_t *list = json_object_get(root, "surfaces"), *s;
    if (!json_is_object(root) || !json_is_array(list))
        return shape_error(run, "$", "an object with a \"surfaces\" array");
    size_t i;
    json_array_foreach(list, i, s) {
        char where[64];
        snprintf(where, sizeof where, "$.surfaces[%zu]", i);
        const char *name = json_string_value(json_object_get(s, "name"));
        if (!json_is_object(s) || !name)
            return shape_error(run, where, "an object with a \"name\" string");
        if (strcmp(name, run->surface) != 0)
            continue;
        run->expr = json_string_value(json_object_get(s, "expr"));
        if (!run->expr) {
            strncat(where, ".expr", sizeof where - strlen(where) - 1);
            return shape_error(run, where, "a string (the expression of f)");
        }
        int rc = surface_lets_and_params(run, s, where);
        return rc ? rc : surface_box(run, s, where);
    }
    fprintf(stderr, "isomesh: %s: no surface named '%s'\n", run->surfaces_file, run->surface);
    return 2;
}

static int resolve_surface(ism_cli_run *run)
{
    if (run->surface && run->expr) {
        fprintf(stderr, "isomesh: give either -e or --surface, not both\n");
        return 2;
    }
    if (run->surface && run->surfaces_file)
        return use_surfaces_file(run);
    if (run->surface) {
        const ism_preset *p = ism_preset_find(run->surface);
        if (!p) {
            fprintf(stderr, "isomesh: no built-in surface named '%s' (try --list)\n", run->surface);
            return 2;
        }
        if (!preset_has_params(run, p))
            return 2;
        return use_preset(run, p) ? 0 : 1;
    }
    if (!run->expr) {
        fprintf(stderr, "isomesh: no surface: give -e EXPR or --surface NAME (try --help)\n");
        return 2;
    }
    return 0;
}

/* ---- output -------------------------------------------------------------------------- */

static const char *extension(const char *path)
{
    const char *dot = strrchr(path, '.');
    const char *slash = strrchr(path, '/');
    return dot && (!slash || dot > slash) ? dot + 1 : "";
}

/* The output's format: its extension in lower case (m.PLY is a PLY file) into buf (8 bytes),
 * "" when too long to be one. */
static const char *format_of(const char *path, char buf[8])
{
    const char *ext = extension(path);
    size_t n = strlen(ext);
    if (n >= 8)
        n = 0;
    for (size_t i = 0; i < n; i++)
        buf[i] = (char)tolower((unsigned char)ext[i]);
    buf[n] = 0;
    return buf;
}

typedef bool (*writer_fn)(const ism_mesh *, ism_write_fn, void *);

static writer_fn writer_for(const char *path)
{
    char buf[8];
    const char *ext = format_of(path, buf);
    if (strcmp(ext, "ply") == 0)
        return ism_write_ply;
    if (strcmp(ext, "obj") == 0)
        return ism_write_obj;
    if (strcmp(ext, "stl") == 0)
        return ism_write_stl;
    return NULL;
}

static bool write_mesh(const char *path, const ism_mesh *m)
{
    ism_buf b = {0};
    bool ok = writer_for(path)(m, ism_buf_write, &b) && ism_cli_write_file(path, b.data, b.len);
    ism_buf_free(&b);
    return ok;
}

/* The mesh file, written beside the analysis (both only read the mesh), so that writing a
 * large PLY does not wait for the analysis's passes on one thread. */
typedef struct mesh_write {
    const char *path;
    const ism_mesh *mesh;
    bool ok;
} mesh_write;

static void write_job(void *arg)
{
    mesh_write *w = arg;
    w->ok = write_mesh(w->path, w->mesh);
}

/* What one command-line run produced, for its stats and features. */
typedef struct run_products {
    const ism_mesh *mesh;
    const ism_poly_stats *poly;
    const ism_analysis *analysis;  /* NULL when not analysed */
    const ism_locus *locus;
    const ism_locus_check *check;  /* NULL when not analysed */
    const ism_conform_stats *conform;
    double max_error;              /* the requested bound, 0 when none */
    const ism_remesh_stats *remesh;/* the quality pass's figures, NULL when it did not run */
    const ism_simplify_stats *simplify; /* the simplification's, NULL when it did not run */
} run_products;

static void print_stats(const run_products *p, const char *format, const double *timings)
{
    ism_stats_input in;
    memset(&in, 0, sizeof in);
    in.key = "";
    in.format = format;
    in.empty = p->mesh->ntris == 0;
    in.vertices = p->mesh->nverts;
    in.triangles = p->mesh->ntris;
    in.poly = p->poly;
    in.analysis = p->analysis;
    in.locus = p->locus;
    in.check = p->check;
    in.conform = p->conform;
    in.max_error = p->max_error;
    in.remesh = p->remesh;
    in.simplify = p->simplify;
    memcpy(in.timings_ms, timings, sizeof in.timings_ms);
    size_t len;
    char *json = ism_stats_json(&in, &len);
    if (json) {
        fwrite(json, 1, len, stdout);
        fputc('\n', stdout);
        free(json);
    }
}

/* The features JSON (proto/features.h) written atomically to path. */
static bool write_features(const char *path, const run_products *p)
{
    ism_mesh none;
    ism_mesh_init(&none);
    bool empty = p->mesh->ntris == 0 || !p->analysis;
    const ism_mesh *m = empty ? &none : p->mesh;
    ism_features f;
    if (!ism_features_build(empty ? NULL : p->analysis, &f))
        return false;
    f.locus = p->locus;
    f.check = empty ? NULL : p->check;
    size_t len;
    char *json = ism_features_json(m, &f, &len);
    bool ok = json && ism_cli_write_file(path, json, len);
    free(json);
    ism_features_free(&f);
    return ok;
}

/* Says what an empty mesh means: nothing at all, or only lower-dimensional parts. */
static void explain_empty(const ism_locus *l)
{
    if (l->npoints == 0 && l->ncurves == 0)
        fprintf(stderr, "isomesh: the surface does not meet the box: the mesh is empty\n");
    else
        fprintf(stderr, "isomesh: no sheet of the surface in the box, only %zu singular points "
                "and %zu singular curves (see --features)\n", l->npoints, l->ncurves);
}

/* --dual asked for the dual mesh and the dual mesher declined: says why; exit status 1. */
static int dual_declined(enum ism_dual_reason why)
{
    fprintf(stderr, "isomesh: --dual: the dual mesher declined (%s: %s); without --dual the "
            "primal polygons make the mesh\n", ism_dual_reason_name(why),
            ism_dual_reason_text(why));
    return 1;
}

static bool nothing_to_do(const ism_cli_run *run)
{
    if (run->output || run->print_stats || run->features_output)
        return false;
    fprintf(stderr, "isomesh: nothing to do: give -o FILE, --stats and/or --features FILE\n");
    return true;
}

/* Analysis and the check against the locus, when stats or features are asked for, on
 * `threads` threads in all. */
static bool analyse_run(const ism_cli_run *run, const ism_mesh *mesh, const ism_tape *tape,
                        const ism_locus *locus, int threads, ism_analysis *an,
                        ism_locus_check *chk)
{
    if (!run->print_stats && !run->features_output)
        return false;
    ism_analysis_options ao;
    ism_analysis_options_default(&ao);
    ao.threads = threads;
    ao.max_error = run->options.max_error; /* measured as the polygoniser did (0: none) */
    ism_error err;
    if (!ism_analyse(mesh, tape, &ao, an, &err))
        return false;
    if (ism_locus_check_mesh(locus, run->options.box, mesh, an, chk, &err))
        return true;
    ism_analysis_free(an);
    return false;
}

int ism_cli_run_surface(ism_cli_run *run)
{
    if (nothing_to_do(run))
        return 2;
    if (run->output && !writer_for(run->output)) {
        fprintf(stderr, "isomesh: -o %s: unknown extension '.%s' (use .ply, .obj or .stl)\n",
                run->output, extension(run->output));
        return 2;
    }
    int st = resolve_surface(run);
    if (st)
        return st;
    if (!run->error_given) /* as a request does: 1e-3 of the box diagonal */
        run->options.max_error = ism_request_default_error(run->options.box);
    else if (run->options.max_error > 0) { /* a request's range, once the box is known */
        ism_req_error rerr;
        if (!ism_request_error_in_range(run->options.max_error, run->options.box,
                                        "--max-error", &rerr)) {
            fprintf(stderr, "isomesh: %s\n", rerr.message);
            return 2;
        }
    }
    if (run->options.max_error > 0 && !run->depth_given) /* as a request does: the bound */
        run->options.max_depth = /* decides, not the depth */
            ism_preset_bound_depth(run->preset, ISM_REQ_DEFAULT_MAX_DEPTH_LIMIT);
    run->options.dual = run->options.max_error > 0 && !run->no_dual; /* as a request does */
    double timings[ISM_TIME_COUNT] = {0};
    double t0 = ism_now_ms();
    ism_error err;
    memset(&err, 0, sizeof err);
    ism_tape *tape = ism_tape_compile(run->expr, run->params, run->nparams, run->lets,
                                      run->nlets, NULL, &err);
    char msg[512];
    if (!tape) {
        fprintf(stderr, "isomesh: %s\n", ism_error_format(&err, msg, sizeof msg));
        return 2;
    }
    enum ism_dual_reason why; /* known before meshing (min/max in f): no mesh made */
    if (run->require_dual &&
        (why = ism_dual_declined_before(tape, &run->options)) != ISM_DUAL_WHY_NONE) {
        ism_tape_free(tape);
        return dual_declined(why);
    }
    double t1 = ism_now_ms();
    timings[ISM_TIME_COMPILE] = t1 - t0;
    ism_mesh mesh;
    ism_mesh_init(&mesh);
    ism_locus locus;
    ism_locus_init(&locus);
    ism_poly_stats ps;
    ism_surface_times times;
    ism_conform_stats cs;
    enum ism_poly_status ps_status = ism_mesh_surface(tape, &run->options, &mesh, &locus, &ps,
                                                      &cs, &times, &err);
    timings[ISM_TIME_SINGULAR] = times.singular_ms;
    timings[ISM_TIME_POLYGONISE] = times.polygonise_ms;
    double t2 = ism_now_ms();
    int status = 0;
    if (ps_status != ISM_POLY_OK) {
        /* the budget's flag and the knobs that make the mesh smaller; under a bound, the
         * --max-error that fits (coarse passes, server/common/fit_error.h) */
        const char *hint = ps_status != ISM_POLY_TOO_BIG ? ""
                           : run->options.max_error > 0
                               ? ": --max-triangles raises it, a larger --max-error makes fewer"
                               : ": --max-triangles raises it, a smaller -d MAX makes fewer";
        char fit_hint[96] = "";
        double fit = ps_status == ISM_POLY_TOO_BIG && run->options.max_error > 0
                         ? ism_fit_error(tape, &run->options, false)
                         : 0;
        char buf[32];
        if (fit > 0)
            snprintf(fit_hint, sizeof fit_hint, " (--max-error %s fits)",
                     ism_three_digits(fit, 1, buf));
        fprintf(stderr, "isomesh: %s%s%s\n", ism_error_format(&err, msg, sizeof msg), hint,
                fit_hint);
        status = ps_status == ISM_POLY_BAD_OPTIONS ? 2 : 1;
        goto done;
    }
    if (run->require_dual && ps.mesher != ISM_MESHER_DUAL) {
        status = dual_declined(ps.dual_declined);
        goto done;
    }
    if (mesh.ntris == 0)
        explain_empty(&locus);
    ism_simplify_stats ss;
    bool simplify = ism_simplify_after(run->simplify, run->options.max_error);
    if (simplify &&
        !ism_simplify_pass(tape, &locus, NULL, run->options.max_error, NULL, &mesh, &ss, &err)) {
        fprintf(stderr, "isomesh: %s\n", ism_error_format(&err, msg, sizeof msg));
        status = 1;
        goto done;
    }
    ism_remesh_stats rs;
    if (run->quality == ISM_QUALITY_GOOD &&
        !ism_quality_pass(tape, &locus, NULL, run->options.max_error, NULL, &mesh, &rs, &err)) {
        fprintf(stderr, "isomesh: %s\n", ism_error_format(&err, msg, sizeof msg));
        status = 1;
        goto done;
    }
    ism_analysis an;
    memset(&an, 0, sizeof an);
    ism_locus_check chk;
    memset(&chk, 0, sizeof chk);
    mesh_write mw = {run->output, &mesh, true};
    ism_side writer;
    /* on a thread of its own when the run has several and analyses, taken from the
     * analysis's so that the run keeps to --threads; else after the analysis's time is
     * taken, so that "analyse" never counts the writing */
    int threads = ism_threads_resolve(run->options.threads);
    bool beside = run->output && threads > 1 && (run->print_stats || run->features_output);
    if (beside)
        ism_side_start(&writer, true, write_job, &mw);
    bool analysed = analyse_run(run, &mesh, tape, &locus, beside ? threads - 1 : threads, &an,
                                &chk);
    timings[ISM_TIME_ANALYSE] = ism_now_ms() - t2;
    if (beside)
        ism_side_join(&writer);
    else if (run->output)
        write_job(&mw);
    if (!mw.ok)
        status = 1;
    run_products prod = {&mesh, &ps, analysed ? &an : NULL, &locus, analysed ? &chk : NULL, &cs,
                         run->options.max_error,
                         run->quality == ISM_QUALITY_GOOD ? &rs : NULL,
                         simplify ? &ss : NULL};
    if (run->features_output && status == 0 && !write_features(run->features_output, &prod))
        status = 1;
    timings[ISM_TIME_TOTAL] = ism_now_ms() - t0;
    if (run->print_stats && status == 0) {
        char fmt[8];
        print_stats(&prod, format_of(run->output ? run->output : "", fmt), timings);
    }
    if (analysed) {
        ism_locus_check_free(&chk);
        ism_analysis_free(&an);
    }
done:
    ism_locus_free(&locus);
    ism_mesh_free(&mesh);
    ism_tape_free(tape);
    return status;
}

/* ---- request files ------------------------------------------------------------------- */

static char *read_file(const char *path, size_t *len)
{
    char *text, err[512];
    int rc = ism_read_file(path, MAX_REQUEST_FILE, &text, len, NULL, err, sizeof err);
    if (rc == 0)
        fprintf(stderr, "isomesh: cannot open %s: %s\n", path, strerror(ENOENT));
    else if (rc < 0)
        fprintf(stderr, "isomesh: %s\n", err);
    return rc == 1 ? text : NULL;
}

int ism_cli_run_request_file(ism_cli_run *run, const char *path)
{
    if (nothing_to_do(run))
        return 2;
    char fmt[8];
    const char *format = run->output ? format_of(run->output, fmt) : NULL;
    if (format && ism_format_lookup(format) < 0) {
        fprintf(stderr, "isomesh: -o %s: unknown extension '.%s' (a request file writes",
                run->output, extension(run->output));
        for (int f = 0; f < ISM_FORMAT_COUNT; f++)
            fprintf(stderr, "%s.%s", f ? ", " : " ", ism_format_name((enum ism_format)f));
        fprintf(stderr, ")\n");
        return 2;
    }
    size_t len;
    char *json = read_file(path, &len);
    if (!json)
        return 2;
    ism_pipeline_limits lim;
    ism_pipeline_limits_default(&lim);
    lim.max_depth = ISM_MAX_DEPTH_LIMIT;
    lim.threads = run->options.threads;
    ism_pipeline_result r;
    memset(&r, 0, sizeof r);
    bool ok = ism_pipeline_run(json, len, format, &lim, NULL, &r);
    free(json);
    int status = 0;
    if (!ok) {
        json_t *e = json_loadb((const char *)r.body.data, r.body.len, 0, NULL);
        const char *m = json_string_value(json_object_get(json_object_get(e, "error"), "message"));
        fprintf(stderr, "isomesh: %s: %s\n", path, m ? m : "the request failed");
        json_decref(e);
        status = r.status == 400 || r.status == 422 ? 2 : 1;
    } else {
        if (run->output && !ism_cli_write_file(run->output, r.body.data, r.body.len))
            status = 1;
        if (run->features_output && status == 0 &&
            !ism_cli_write_file(run->features_output, r.features.data, r.features.len))
            status = 1;
        if (run->print_stats && status == 0) {
            fwrite(r.stats.data, 1, r.stats.len, stdout);
            fputc('\n', stdout);
        }
    }
    ism_pipeline_result_free(&r);
    return status;
}

int ism_cli_list_surfaces(ism_cli_run *run)
{
    (void)run;
    for (size_t i = 0; i < ism_preset_count(); i++) {
        const ism_preset *p = ism_preset_at(i);
        printf("%-18s %s\n", p->name, p->about);
    }
    return 0;
}
