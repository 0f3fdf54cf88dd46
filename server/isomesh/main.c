/* main.c — the `isomesh` command: polygonise one surface given on the command line (an
 * expression or a named surface) into a PLY/OBJ/STL file, run one JSON request file through
 * the service's pipeline, or serve as a worker process of isomeshd (`--worker`).
 * Bad input is a one-line error and exit status 2; no partial file is ever left behind. */
#include <errno.h>
#include <getopt.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "server/isomesh/cli.h"
#include "core/octree/tolerances.h"
#include "core/remesh/quality_pass.h"
#include "core/util/pool.h"
#include "server/isomesh/sandbox.h"
#include "server/isomesh/worker.h"

/* The usage text; the tolerances' lines are printed from their table where %s stands. */
static const char usage_text[] =
    "usage:\n"
    "  isomesh -e EXPR [-p NAME=VALUE]... [--let NAME=EXPR]... [options] -o FILE\n"
    "  isomesh --surface NAME [--surfaces FILE] [options] -o FILE\n"
    "  isomesh REQUEST.json -o FILE       run one service request (any format)\n"
    "  isomesh --worker                   worker process of isomeshd (framed stdin/stdout)\n"
    "  isomesh --worker --sandbox-selftest open|create|socket|exec|fork|exec-memory|write-fd|allowed\n"
    "                                     enter the worker's sandbox, try one thing, report\n"
    "\n"
    "Polygonises f(x, y, z) = 0 with the non-manifold adaptive octree algorithm of Balsys &\n"
    "Suffern and writes binary PLY (with normals), OBJ or binary STL, chosen by the output\n"
    "file's extension (.ply .obj .stl; a request file may also ask for .drc and .glb).\n"
    "\n"
    "surface:\n"
    "  -e, --expr EXPR          the function: x y z, parameters, + - * / ^n, sqrt sin cos tan\n"
    "                           exp log abs min max pow, pi e; `let NAME = EXPR` lines first\n"
    "  -p, --param NAME=VALUE   a parameter (repeatable)\n"
    "      --let NAME=EXPR      a named sub-expression, may use earlier ones (repeatable)\n"
    "      --surface NAME       a named surface: built-in presets, or from --surfaces\n"
    "      --surfaces FILE      a JSON file of named surfaces, shaped like the repository's\n"
    "                           examples/surfaces.json: {\"surfaces\": [{\"name\", \"expr\",\n"
    "                           \"params\"?, \"let\"?, \"box\"?}]}\n"
    "      --list               list the built-in surfaces and exit\n"
    "octree:\n"
    "  -b, --box X0,Y0,Z0,X1,Y1,Z1   search box, the octree root (default -1,-1,-1,1,1,1\n"
    "                           or the surface's own box)\n"
    "  -d, --depth MIN:MAX      subdivision depths (default 3:7; MAX at most 16)\n"
    "      --threads N          threads for this run, every one counted (default: all\n"
    "                           cores; output identical)\n"
    "%s"   /* the tolerances, from core/octree/tolerances.h */
    "      --max-error E|off    subdivide until the triangles lie within E of the surface\n"
    "                           (model units, measured at centroids and edge midpoints);\n"
    "                           depth MAX is then only a safety limit (default 10 under a\n"
    "                           bound). Default: 1e-3 x the box diagonal, as a request's.\n"
    "                           off (or 0): no bound, the flatness test (--flat-plane) and\n"
    "                           depth MAX decide (the paper's octree). On a closed surface\n"
    "                           without min/max whose singular points, if any, are nodes or\n"
    "                           isolated points (no singular curve) the mesh is made by\n"
    "                           dual contouring: one vertex per leaf, cells sized\n"
    "                           by the error (fewer triangles, one thread); the stats'\n"
    "                           polygoniser.mesher says which mesher ran and dual_declined\n"
    "                           why not the dual one. Either mesh is the mesher's own,\n"
    "                           within E, not simplified unless --simplify\n"
    "      --no-dual            under a bound, the primal polygons everywhere\n"
    "      --dual               under a bound, the dual mesh or nothing: when the dual\n"
    "                           mesher declines (min/max in f, a singular curve, the box\n"
    "                           cuts the surface ...), fail with its reason (exit status 1)\n"
    "                           and write no file\n"
    "      --simplify           under a bound, then collapse edges wherever the mesh\n"
    "                           stays within E (measured at every new centroid and edge\n"
    "                           midpoint; features, topology and orientation kept): the\n"
    "                           fewest triangles for the error, at 1-7x the meshing's CPU\n"
    "      --no-simplify        the default: the mesher's triangles (kept for scripts)\n"
    "      --straddle           under a bound, move the primal polygons' vertices where\n"
    "                           the surface bends one way 0.9 E toward its convex side and\n"
    "                           size the cells for it (no min/max, no singular locus)\n"
    "      --max-triangles N    budget; stop with an error beyond it (default 4000000)\n"
    "      --quality Q          raw (default): the polygoniser's triangles; good: then\n"
    "                           flip edges toward Delaunay and relax vertices along the\n"
    "                           surface (back on f = 0 by Newton), never across a boundary,\n"
    "                           non-manifold edge, crease, curve or at a singular point\n"
    "output:\n"
    "  -o, --output FILE        .ply, .obj or .stl (written to a temporary name, renamed)\n"
    "      --stats              print the statistics as JSON on standard output\n"
    "      --features FILE      write the features JSON: the singular locus found from f\n"
    "                           (certified points, singular curves, double sheets) and the\n"
    "                           mesh's non-manifold edges and points checked against it\n"
    "  -h, --help               this text\n"
    "With a request file only -o, --stats, --features and --threads apply: the file says\n"
    "everything about the surface and its mesh.\n"
    "exit status: 0 done, 1 the run failed (budget, memory, --dual declined), 2 bad input.\n";

enum long_only {
    OPT_LET = 256, OPT_SURFACE, OPT_SURFACES, OPT_LIST, OPT_THREADS, OPT_MAX_TRIS,
    OPT_MAX_ERROR, OPT_NO_SIMPLIFY, OPT_SIMPLIFY, OPT_STRADDLE, OPT_DUAL, OPT_NO_DUAL, OPT_STATS, OPT_WORKER, OPT_FEATURES, OPT_QUALITY,
    OPT_TOLERANCE, /* OPT_TOLERANCE + i: the table's tolerance i */
};

static const struct option base_options[] = {
    {"expr", required_argument, 0, 'e'},
    {"param", required_argument, 0, 'p'},
    {"let", required_argument, 0, OPT_LET},
    {"surface", required_argument, 0, OPT_SURFACE},
    {"surfaces", required_argument, 0, OPT_SURFACES},
    {"list", no_argument, 0, OPT_LIST},
    {"box", required_argument, 0, 'b'},
    {"depth", required_argument, 0, 'd'},
    {"threads", required_argument, 0, OPT_THREADS},
    {"max-triangles", required_argument, 0, OPT_MAX_TRIS},
    {"max-error", required_argument, 0, OPT_MAX_ERROR},
    {"quality", required_argument, 0, OPT_QUALITY},
    {"no-simplify", no_argument, 0, OPT_NO_SIMPLIFY},
    {"simplify", no_argument, 0, OPT_SIMPLIFY},
    {"straddle", no_argument, 0, OPT_STRADDLE},
    {"dual", no_argument, 0, OPT_DUAL},
    {"no-dual", no_argument, 0, OPT_NO_DUAL},
    {"output", required_argument, 0, 'o'},
    {"stats", no_argument, 0, OPT_STATS},
    {"features", required_argument, 0, OPT_FEATURES},
    {"worker", no_argument, 0, OPT_WORKER},
    {"help", no_argument, 0, 'h'},
};
#define NBASE_OPTIONS (sizeof base_options / sizeof base_options[0])

/* base_options, then one option per tolerance, then the terminator. */
static void all_options(struct option *out)
{
    memcpy(out, base_options, sizeof base_options);
    for (int i = 0; i < ISM_TOLERANCE_COUNT; i++)
        out[NBASE_OPTIONS + i] =
            (struct option){ism_tolerances[i].flag, required_argument, 0, OPT_TOLERANCE + i};
    out[NBASE_OPTIONS + ISM_TOLERANCE_COUNT] = (struct option){0, 0, 0, 0};
}

static void print_usage(void)
{
    char lines[ISM_TOLERANCE_COUNT * 128] = "", *at = lines;
    for (int i = 0; i < ISM_TOLERANCE_COUNT; i++) {
        const ism_tolerance *t = &ism_tolerances[i];
        char flag[40];
        snprintf(flag, sizeof flag, "%s %s", t->flag, t->is_int ? "N" : "V");
        at += snprintf(at, (size_t)(lines + sizeof lines - at), "      --%-18s %s (default %g)\n",
                       flag, t->help, t->def);
    }
    printf(usage_text, lines);
}

/* Parses a tolerance's value: a number inside its range (a whole one for an int field). */
static bool parse_tolerance(ism_poly_options *o, const ism_tolerance *t, const char *arg)
{
    char flag[40];
    double v;
    snprintf(flag, sizeof flag, "--%s", t->flag);
    if (!ism_cli_parse_double(flag, arg, &v))
        return false;
    if (!ism_tolerance_accepts(t, v)) {
        fprintf(stderr, "isomesh: %s: %s is not %s in [%g, %g]\n", flag, arg,
                t->is_int ? "a whole number" : "a number", t->lo, t->hi);
        return false;
    }
    ism_tolerance_set(o, t, v);
    return true;
}

/* The flag's long name ("max-error"; -o is "output"), for messages. */
static const char *flag_name(const struct option *opts, int opt)
{
    for (const struct option *o = opts; o->name; o++)
        if (o->val == opt)
            return o->name;
    return "?";
}

/* getopt's short options (a leading ':' reports a missing value as ':'); is_flag reads the
 * same string, so a short flag added here is known there too. */
static const char short_opts[] = ":e:p:b:d:o:h";

/* Is a flag's value really the next flag (`--surface -o x.ply`: the value was forgotten)?
 * Exactly one of the short flags, or -- and a long flag's name (numbers like -1 are values). */
static bool is_flag(const struct option *opts, const char *arg)
{
    if (arg[0] != '-')
        return false;
    if (arg[1] && !arg[2] && arg[1] != ':' && strchr(short_opts, arg[1]))
        return true;
    if (arg[1] != '-')
        return false;
    size_t n = strcspn(arg + 2, "=");
    for (const struct option *o = opts; o->name; o++)
        if (strlen(o->name) == n && strncmp(o->name, arg + 2, n) == 0)
            return true;
    return false;
}

/* Flags that apply beside a request file: where the result goes and how many threads. */
static bool applies_to_request_file(int opt)
{
    return opt == 'o' || opt == OPT_STATS || opt == OPT_FEATURES || opt == OPT_THREADS;
}

/* The flags' combinations; false after printing the error (exit status 2). */
static bool check_combination(const ism_cli_run *run, const char *request_file,
                              const char *surface_flag)
{
    if (request_file && surface_flag) {
        fprintf(stderr, "isomesh: --%s: not with a request file (%s says everything about the "
                "surface and its mesh: set it there); beside one only -o, --stats, --features "
                "and --threads apply\n", surface_flag, request_file);
        return false;
    }
    if (run->require_dual && run->no_dual) {
        fprintf(stderr, "isomesh: --dual and --no-dual: give one of them\n");
        return false;
    }
    if ((run->require_dual || run->simplify || run->options.straddle) && run->error_given &&
        !(run->options.max_error > 0)) {
        fprintf(stderr, "isomesh: --%s needs a bound, not --max-error off: %s\n",
                run->require_dual ? "dual" : run->simplify ? "simplify" : "straddle",
                run->require_dual ? "the dual mesher sizes its cells by it"
                : run->simplify   ? "the simplification keeps the mesh within it"
                                  : "the vertices move by a share of it");
        return false;
    }
    if (run->surfaces_file && !run->surface) {
        fprintf(stderr, "isomesh: --surfaces %s needs --surface NAME: which of its surfaces\n",
                run->surfaces_file);
        return false;
    }
    return true;
}

/* Applies one option to the run; false (after printing the error) on a bad value. */
static bool apply_option(ism_cli_run *run, int opt, const char *arg)
{
    ism_poly_options *o = &run->options;
    switch (opt) {
    case 'e': run->expr = arg; return true;
    case 'p': return ism_cli_add_param(run, arg);
    case OPT_LET: return ism_cli_add_let(run, arg);
    case OPT_SURFACE: run->surface = arg; return true;
    case OPT_SURFACES: run->surfaces_file = arg; return true;
    case 'b': return ism_cli_parse_box(arg, o->box) && (run->box_given = true);
    case 'd': return ism_cli_parse_depth(arg, &o->min_depth, &o->max_depth) &&
                     (run->depth_given = true);
    case OPT_THREADS: return ism_cli_parse_int("--threads", arg, 0, ISM_MAX_THREADS, &o->threads);
    case OPT_MAX_ERROR:
        run->error_given = true;
        if (strcmp(arg, "off") == 0) {
            o->max_error = 0;
            return true;
        }
        if (!ism_cli_parse_double("--max-error", arg, &o->max_error))
            return false;
        if (o->max_error >= 0)
            return true;
        fprintf(stderr, "isomesh: --max-error: %s is below 0 (a distance; off or 0: no "
                "bound)\n", arg);
        return false;
    case OPT_MAX_TRIS: {
        int n;
        if (!ism_cli_parse_int("--max-triangles", arg, 1, 2000000000, &n))
            return false;
        o->max_triangles = (size_t)n;
        return true;
    }
    case OPT_NO_SIMPLIFY: run->simplify = false; return true;
    case OPT_SIMPLIFY: run->simplify = true; return true;
    case OPT_STRADDLE: o->straddle = true; return true;
    case OPT_DUAL: run->require_dual = true; return true;
    case OPT_NO_DUAL: run->no_dual = true; return true;
    case OPT_QUALITY:
        if ((run->quality = ism_quality_lookup(arg)) >= 0)
            return true;
        fprintf(stderr, "isomesh: --quality %s: expected raw or good\n", arg);
        return false;
    case 'o': run->output = arg; return true;
    case OPT_STATS: run->print_stats = true; return true;
    case OPT_FEATURES: run->features_output = arg; return true;
    default:
        if (opt >= OPT_TOLERANCE && opt < OPT_TOLERANCE + ISM_TOLERANCE_COUNT)
            return parse_tolerance(o, &ism_tolerances[opt - OPT_TOLERANCE], arg);
        return false;
    }
}

int main(int argc, char **argv)
{
    if (argc == 2 && strcmp(argv[1], "--worker") == 0)
        return ism_worker_main(STDIN_FILENO, STDOUT_FILENO);
    if (argc == 4 && strcmp(argv[1], "--worker") == 0 &&
        strcmp(argv[2], "--sandbox-selftest") == 0)
        return ism_sandbox_selftest(argv[3]);

    if (argc == 1) { /* nothing given: how to start, rather than "nothing to do" */
        fprintf(stderr, "usage: isomesh --surface NAME -o FILE | -e EXPR -o FILE | REQUEST.json "
                "-o FILE (--list: the surfaces; --help: every option)\n");
        return 2;
    }
    ism_cli_run run;
    ism_cli_run_init(&run);
    bool list = false;
    /* the first flag given that describes the surface or its mesh (refused beside a request
     * file, which says it all) */
    const char *surface_flag = NULL;
    int opt;
    struct option long_options[NBASE_OPTIONS + ISM_TOLERANCE_COUNT + 1];
    all_options(long_options);
    opterr = 0;
    while ((opt = getopt_long(argc, argv, short_opts, long_options, NULL)) != -1) {
        if (opt == 'h') {
            print_usage();
            ism_cli_run_free(&run);
            return 0;
        }
        if (opt == OPT_LIST) {
            list = true;
            continue;
        }
        if (opt == OPT_WORKER) {
            fprintf(stderr, "isomesh: --worker takes no other arguments\n");
            ism_cli_run_free(&run);
            return 2;
        }
        if (opt == '?' || opt == ':') {
            fprintf(stderr, "isomesh: %s option '%s' (try --help)\n",
                    opt == ':' ? "missing value for" : "unknown", argv[optind - 1]);
            ism_cli_run_free(&run);
            return 2;
        }
        const char *name = flag_name(long_options, opt);
        if (optarg && is_flag(long_options, optarg)) {
            fprintf(stderr, "isomesh: missing value for --%s (the next word, '%s', is a flag)\n",
                    name, optarg);
            ism_cli_run_free(&run);
            return 2;
        }
        if (!applies_to_request_file(opt) && !surface_flag)
            surface_flag = name;
        if (!apply_option(&run, opt, optarg)) {
            ism_cli_run_free(&run);
            return 2;
        }
    }
    int status;
    const char *request_file = optind == argc - 1 ? argv[optind] : NULL;
    if (optind < argc - 1) {
        fprintf(stderr, "isomesh: unexpected argument '%s': one request file at most, and -o "
                "FILE for the output (try --help)\n", argv[optind + 1]);
        status = 2;
    } else if (!list && !check_combination(&run, request_file, surface_flag))
        status = 2;
    else if (list)
        status = ism_cli_list_surfaces(&run);
    else if (request_file)
        status = ism_cli_run_request_file(&run, request_file);
    else
        status = ism_cli_run_surface(&run);
    ism_cli_run_free(&run);
    return status;
}
