/* cli.h — the pieces of the `isomesh` command behind main.c: collecting the surface from
 * flags, a surfaces file or the built-in presets; running it through core; running a request
 * file through the service pipeline; writing output files atomically. */
#ifndef ISM_CLI_H
#define ISM_CLI_H

#include <stdbool.h>
#include <stddef.h>
#include "core/expr/expr.h"
#include "core/octree/polygonise.h"

typedef struct ism_cli_run {
    ism_poly_options options;
    const char *expr;           /* -e */
    const char *surface;        /* --surface */
    const struct ism_preset *preset; /* the built-in preset --surface named, or NULL */
    const char *surfaces_file;  /* --surfaces */
    const char *output;         /* -o */
    const char *features_output;/* --features */
    bool box_given, depth_given, print_stats;
    int quality;                /* --quality: enum ism_quality (raw unless given) */
    bool simplify;              /* --simplify: under --max-error, the simplification after
                                   meshing (ism_simplify_after, core/octree/mesher.h); off
                                   unless given (--no-simplify, the default, kept for scripts) */
    bool no_dual;               /* --no-dual: under --max-error, the primal polygons even
                                   where the dual mesh (the default) applies */
    bool require_dual;          /* --dual: the dual mesh or a failure naming why not */
    bool error_given;           /* --max-error E (or off): else the request's default bound,
                                   ism_request_default_error of the box */
    ism_param *params;          /* names owned */
    size_t nparams;
    ism_let *lets;              /* names and sources owned */
    size_t nlets;
    void *surfaces_json;        /* the loaded surfaces file (json_t *), kept while running */
} ism_cli_run;

void ism_cli_run_init(ism_cli_run *run);
void ism_cli_run_free(ism_cli_run *run);

/* Flag values; each prints a one-line error naming the flag and returns false. */
bool ism_cli_add_param(ism_cli_run *run, const char *name_eq_value);
bool ism_cli_add_let(ism_cli_run *run, const char *name_eq_expr);
bool ism_cli_parse_box(const char *s, double box[6]);
bool ism_cli_parse_depth(const char *s, int *min_depth, int *max_depth);
bool ism_cli_parse_int(const char *flag, const char *s, int lo, int hi, int *out);
bool ism_cli_parse_double(const char *flag, const char *s, double *out);

/* The commands; each returns the exit status (0, 1 or 2). */
int ism_cli_run_surface(ism_cli_run *run);
int ism_cli_run_request_file(ism_cli_run *run, const char *path);
int ism_cli_list_surfaces(ism_cli_run *run);

/* Writes len bytes to path through a temporary file in the same directory, fsynced and
 * renamed over path; nothing is left behind on failure. */
bool ism_cli_write_file(const char *path, const void *data, size_t len);

#endif
