/* bench_error.c — the measuring half of bench_equal_error.py: the five surfaces of the
 * equal-error comparison (sphere, torus, gyroid in a ball, Klein bottle, Barth's nodal
 * sextic in a ball), isomesh's run on them under max_error with its CPU time, and the one
 * error measure every tool's mesh is judged by: the distance from each triangle's centroid
 * to f = 0, in closed form for the sphere and the torus, else the length of the Newton
 * projection q <- q - f ∇f / |∇f|² (on the tape compiled from the same expression).
 *
 *   bench_error mesh NAME E [DEPTH [raw|simplify] [primal] [straddle] [crease] [repeat=N]]
 *                                        isomesh as the service does by default (core/
 *                                        singular/surface.h: the locus, the dual mesh where
 *                                        it applies, core/octree/dual.h, else the primal
 *                                        polygons and conformance; no simplification);
 *                                        simplify: then the simplification within E ("raw",
 *                                        the default, is accepted for old scripts);
 *                                        primal: not the dual mesh ("dual": false); straddle:
 *                                        the polygoniser's straddle option, core/octree/
 *                                        straddle.h ("dual" is accepted: the default);
 *                                        crease: the dual mesh also along a top min/max's
 *                                        crease (the option dual_crease, off by default,
 *                                        core/octree/dual_crease.h); one thread;
 *                                        repeat=N: the whole call N times in the process
 *                                        (the same mesh each time), cpu_s their mean and
 *                                        cpu_sd the runs' standard deviation (a run of a few
 *                                        ms is one scheduler slice: bench_equal_error.py
 *                                        repeats it to ~0.1 s of work)
 *   bench_error measure NAME FILE.ply [all]   (all: midpoints and corners too)
 *                                        a mesh from another tool (binary little-endian PLY:
 *                                        double x y z, faces as uchar count + int32 indices)
 *   bench_error eval NAME X,Y,Z[;...]    f at points (to check the other tools' formulas)
 *   bench_error list                     the surfaces, boxes and targets
 *
 * Each prints one JSON line. CPU seconds are the process's (CLOCK_PROCESS_CPUTIME_ID)
 * around the meshing call alone: no parsing, no writing, no measuring. */
#include <math.h>
#include <stdbool.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "core/eval/eval.h"
#include "core/octree/polygonise.h"
#include "core/remesh/quality_pass.h"
#include "core/singular/surface.h"

/* Newton projection: at most this many steps; it stops once a step is below STEP_TOL
 * (relative to the point's size: far below any target error of the bench). Points where it
 * does not converge (at a node ∇f vanishes and steps shrink only linearly) keep the distance
 * to the last iterate plus the last |f|/|∇f|, an honest over-estimate. */
#define NEWTON_STEPS 60
#define STEP_TOL 1e-14
#define MAX_PLY_HEADER 4096
#define MAX_POINTS 4096
/* repeat=N at most (a 4 ms torus run 1,000 times is 4 s) */
#define MAX_REPEAT 1000

enum dist_kind { DIST_NEWTON, DIST_SPHERE, DIST_TORUS };

typedef struct surface {
    const char *name;
    const char *expr;
    ism_param params[2];
    size_t nparams;
    double box[6];
    enum dist_kind kind;
    double targets[3]; /* max centroid distances the tools are compared at */
} surface;

#define BARTH6 "max(4*(phi^2*x^2 - y^2)*(phi^2*y^2 - z^2)*(phi^2*z^2 - x^2) - " \
               "(1 + 2*phi)*(x^2 + y^2 + z^2 - 1)^2, x^2 + y^2 + z^2 - 2.25)"

/* Kummer's quartic with its tetrahedral planes written out (proto/presets.c's lets):
 * closed, 4 real nodes at mu2 = 0.6667 — the dual mesh round isolated points (dual_balls.h);
 * 16 at mu2 = 2, leaving every box through four funnels (kummer-16-nodes: a box cut and
 * nodes, issue 16's Kummer-like target). */
#define KUMMER4 "(x^2 + y^2 + z^2 - mu2)^2 - (3*mu2 - 1)/(3 - mu2)*(w - z - sqrt(2)*x)*" \
                "(w - z + sqrt(2)*x)*(w + z + sqrt(2)*y)*(w + z - sqrt(2)*y)"

static const surface SURFACES[] = {
    {"sphere", "x^2 + y^2 + z^2 - r^2", {{"r", 1}}, 1, {-1.5, -1.5, -1.5, 1.5, 1.5, 1.5},
     DIST_SPHERE, {1e-2, 3e-3, 1e-3}},
    {"torus", "(x^2 + y^2 + z^2 + R^2 - r^2)^2 - 4*R^2*(x^2 + y^2)", {{"R", 1}, {"r", 0.3}}, 2,
     {-1.5, -1.5, -1.5, 1.5, 1.5, 1.5}, DIST_TORUS, {1e-2, 3e-3, 1e-3}},
    {"gyroid-ball",
     "max(sin(k*x)*cos(k*y) + sin(k*y)*cos(k*z) + sin(k*z)*cos(k*x), x^2 + y^2 + z^2 - 1.96)",
     {{"k", 4}}, 1, {-1.5, -1.5, -1.5, 1.5, 1.5, 1.5}, DIST_NEWTON, {1e-2, 3e-3, 1e-3}},
    {"klein-bottle",
     "(x^2 + y^2 + z^2 + 2*y - 1)*((x^2 + y^2 + z^2 - 2*y - 1)^2 - 8*z^2) + "
     "16*x*z*(x^2 + y^2 + z^2 - 2*y - 1)",
     {{0}}, 0, {-4, -4, -4, 4, 4, 4}, DIST_NEWTON, {3e-2, 1e-2, 3e-3}},
    {"kummer-4-nodes", KUMMER4, {{"mu2", 0.6667}, {"w", 1}}, 2, {-3, -3, -3, 3, 3, 3},
     DIST_NEWTON, {1e-2, 3e-3, 1e-3}},
    {"kummer-16-nodes", KUMMER4, {{"mu2", 2}, {"w", 1}}, 2, {-3, -3, -3, 3, 3, 3},
     DIST_NEWTON, {1e-2, 3e-3, 1e-3}},
    {"barth-sextic", BARTH6, {{"phi", 1.6180339887498949}}, 1,
     {-1.6, -1.6, -1.6, 1.6, 1.6, 1.6}, DIST_NEWTON, {1e-2, 3e-3, 1e-3}},
};
#define NSURFACES (sizeof SURFACES / sizeof SURFACES[0])

static const surface *find_surface(const char *name)
{
    for (size_t i = 0; i < NSURFACES; i++)
        if (strcmp(SURFACES[i].name, name) == 0)
            return &SURFACES[i];
    fprintf(stderr, "bench_error: unknown surface %s\n", name);
    return NULL;
}

static double cpu_seconds(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

/* ---- the error measure ---------------------------------------------------------------- */

typedef struct measurer {
    const surface *s;
    const ism_tape *t;
    ism_eval_ws *ws;
} measurer;

static double newton_distance(const measurer *m, const double p[3])
{
    double q[3] = {p[0], p[1], p[2]}, g[3], last = 0;
    for (int it = 0; it < NEWTON_STEPS; it++) {
        double f = ism_eval_gradient(m->t, m->ws, q[0], q[1], q[2], g);
        double gg = g[0] * g[0] + g[1] * g[1] + g[2] * g[2];
        if (!(gg > 0) || !isfinite(f))
            break;
        double size = 1 + fabs(q[0]) + fabs(q[1]) + fabs(q[2]);
        last = fabs(f) / sqrt(gg);
        if (last < STEP_TOL * size) {
            last = 0;
            break;
        }
        for (int k = 0; k < 3; k++)
            q[k] -= f * g[k] / gg;
    }
    double d = sqrt((q[0] - p[0]) * (q[0] - p[0]) + (q[1] - p[1]) * (q[1] - p[1]) +
                    (q[2] - p[2]) * (q[2] - p[2]));
    return d + last;
}

static double distance(const measurer *m, const double p[3])
{
    const surface *s = m->s;
    if (s->kind == DIST_SPHERE)
        return fabs(sqrt(p[0] * p[0] + p[1] * p[1] + p[2] * p[2]) - s->params[0].value);
    if (s->kind == DIST_TORUS) {
        double rho = sqrt(p[0] * p[0] + p[1] * p[1]) - s->params[0].value;
        return fabs(sqrt(rho * rho + p[2] * p[2]) - s->params[1].value);
    }
    return newton_distance(m, p);
}

typedef struct error_stats {
    double max, mean;
    double max_mid; /* the largest distance at an edge's midpoint */
    double max_vert; /* the largest distance at a triangle's corner */
    size_t triangles;
} error_stats;

/* The distances at the triangles' centroids; with all, at their edges' midpoints and their
 * corners too (each once per triangle using it: the same points again). isomesh's bound
 * holds at all three (the accuracy block's "met"); the comparison's measure is the
 * centroids', and --measure all (bench_equal_error.py) takes the largest of the three. */
static error_stats centroid_error(const measurer *m, const double *pos, const uint32_t *tri,
                                  size_t ntris, bool all)
{
    error_stats e = {0, 0, 0, 0, ntris};
    double sum = 0;
    for (size_t i = 0; i < ntris; i++) {
        const double *a = pos + 3 * tri[3 * i], *b = pos + 3 * tri[3 * i + 1],
                     *c = pos + 3 * tri[3 * i + 2];
        for (int k = 0; all && k < 3; k++) { /* each edge from both sides: the same midpoint */
            const double *u = pos + 3 * tri[3 * i + k], *v = pos + 3 * tri[3 * i + (k + 1) % 3];
            double q[3] = {0.5 * (u[0] + v[0]), 0.5 * (u[1] + v[1]), 0.5 * (u[2] + v[2])};
            e.max_mid = fmax(e.max_mid, distance(m, q));
            e.max_vert = fmax(e.max_vert, distance(m, u));
        }
        double p[3] = {(a[0] + b[0] + c[0]) / 3, (a[1] + b[1] + c[1]) / 3,
                       (a[2] + b[2] + c[2]) / 3};
        double d = distance(m, p);
        sum += d;
        if (d > e.max)
            e.max = d;
    }
    e.mean = ntris ? sum / (double)ntris : 0;
    return e;
}

/* ---- reading a mesh -------------------------------------------------------------------- */

typedef struct ply {
    size_t nverts, ntris;
    double *pos;
    uint32_t *tri;
} ply;

static bool read_header(FILE *f, size_t *nv, size_t *nf)
{
    char line[256];
    size_t total = 0;
    int props = 0;
    *nv = *nf = (size_t)-1;
    while (fgets(line, sizeof line, f) && (total += strlen(line)) < MAX_PLY_HEADER) {
        if (strcmp(line, "end_header\n") == 0)
            return props == 3 && *nv != (size_t)-1 && *nf != (size_t)-1;
        if (sscanf(line, "element vertex %zu", nv) == 1 || sscanf(line, "element face %zu", nf) == 1)
            continue;
        if (strncmp(line, "property double ", 16) == 0)
            props++;
        else if (strncmp(line, "property float", 14) == 0 ||
                 (strncmp(line, "property", 8) == 0 && !strstr(line, "list uchar int")))
            return false; /* only the layout the bench's writers use */
    }
    return false;
}

static bool read_ply(const char *path, ply *m)
{
    memset(m, 0, sizeof *m);
    FILE *f = fopen(path, "rb");
    if (!f)
        return false;
    size_t nv, nf;
    bool ok = read_header(f, &nv, &nf) && nv < ((size_t)1 << 28) && nf < ((size_t)1 << 28);
    if (ok) {
        m->pos = malloc((nv ? nv : 1) * 3 * sizeof *m->pos);
        m->tri = malloc((nf ? nf : 1) * 3 * sizeof *m->tri);
        ok = m->pos && m->tri && fread(m->pos, sizeof *m->pos, 3 * nv, f) == 3 * nv;
    }
    for (size_t i = 0; ok && i < nf; i++) {
        unsigned char n;
        int32_t v[3];
        ok = fread(&n, 1, 1, f) == 1 && n == 3 && fread(v, sizeof v[0], 3, f) == 3;
        for (int k = 0; ok && k < 3; k++) {
            ok = v[k] >= 0 && (size_t)v[k] < nv;
            m->tri[3 * i + k] = (uint32_t)v[k];
        }
    }
    fclose(f);
    m->nverts = nv;
    m->ntris = nf;
    return ok;
}

/* ---- the commands ----------------------------------------------------------------------- */

static ism_tape *compile(const surface *s)
{
    ism_error err;
    ism_tape *t = ism_tape_compile(s->expr, s->params, s->nparams, NULL, 0, NULL, &err);
    if (!t)
        fprintf(stderr, "bench_error: %s: %s\n", s->name, err.message);
    return t;
}

/* One meshing call (the surface pipeline, then the simplification when asked) into *mesh
 * and *locus (initialised here); its CPU seconds in *cpu, the polygonise part in *poly_cpu.
 * ISM_POLY_OK or the failure (err says why). */
static enum ism_poly_status mesh_once(const ism_tape *t, const ism_poly_options *o, bool asked,
                                      ism_mesh *mesh, ism_locus *locus, ism_poly_stats *ps,
                                      ism_surface_times *times, ism_simplify_stats *ss,
                                      double *cpu, double *poly_cpu, ism_error *err)
{
    ism_mesh_init(mesh);
    ism_locus_init(locus);
    ism_conform_stats cs;
    memset(ss, 0, sizeof *ss);
    double c0 = cpu_seconds();
    enum ism_poly_status st = ism_mesh_surface(t, o, mesh, locus, ps, &cs, times, err);
    double c1 = cpu_seconds();
    if (st == ISM_POLY_OK && ism_simplify_after(asked, o->max_error) &&
        !ism_simplify_pass(t, locus, NULL, o->max_error, NULL, mesh, ss, err))
        st = ISM_POLY_NO_MEMORY;
    *cpu = cpu_seconds() - c0;
    *poly_cpu = c1 - c0;
    return st;
}

static int cmd_mesh(const surface *s, const ism_tape *t, measurer *m, double e, int depth,
                    bool asked, bool straddle, bool dual, bool crease, int repeat)
{
    ism_poly_options o;
    ism_poly_options_default(&o);
    memcpy(o.box, s->box, sizeof o.box);
    o.max_error = e;
    o.max_depth = depth;
    o.threads = 1;
    o.straddle = straddle;
    o.dual = dual;
    o.dual_crease = crease;
    ism_mesh mesh;
    ism_locus locus;
    ism_poly_stats ps;
    ism_surface_times times;
    ism_error err;
    ism_simplify_stats ss;
    double sum = 0, sum2 = 0, cpu = 0, poly_cpu = 0;
    enum ism_poly_status st = ISM_POLY_OK;
    for (int r = 0; r < repeat && st == ISM_POLY_OK; r++) {
        if (r) { /* the same mesh again: only the time is wanted */
            ism_locus_free(&locus);
            ism_mesh_free(&mesh);
        }
        st = mesh_once(t, &o, asked, &mesh, &locus, &ps, &times, &ss, &cpu, &poly_cpu, &err);
        sum += cpu;
        sum2 += cpu * cpu;
    }
    if (st != ISM_POLY_OK) {
        fprintf(stderr, "bench_error: %s: %s\n", s->name, err.message);
        ism_locus_free(&locus);
        ism_mesh_free(&mesh);
        return 1;
    }
    double mean = sum / repeat;
    double sd = repeat > 1 ? sqrt(fmax(0, (sum2 - sum * mean) / (repeat - 1))) : 0;
    bool simplify = ism_simplify_after(asked, e);
    error_stats es = centroid_error(m, mesh.pos, mesh.tri, mesh.ntris, true);
    printf("{\"cpu_s\": %.6f, \"cpu_sd\": %.6f, \"runs\": %d, \"mesh_cpu_ms\": %.3f, "
           "\"simplify_cpu_ms\": %.3f, "
           "\"poly_ms\": %.3f, \"singular_ms\": %.3f, \"simplify_ms\": %.3f, "
           "\"triangles_raw\": %zu, \"triangles\": %zu, "
           "\"max_c\": %.6g, \"max_m\": %.6g, \"max_v\": %.6g, \"max_all\": %.6g, "
           "\"mean_c\": %.6g, \"rounds\": %llu, "
           "\"missed\": %llu, \"mesher\": \"%s\", \"dual_declined\": \"%s\"}\n",
           mean, sd, repeat, 1e3 * poly_cpu, 1e3 * (cpu - poly_cpu), times.polygonise_ms,
           times.singular_ms, ss.time_ms,
           simplify ? ss.triangles_before : es.triangles, es.triangles, es.max, es.max_mid,
           es.max_vert, fmax(es.max, fmax(es.max_mid, es.max_vert)), es.mean, (unsigned long long)ps.error_rounds, (unsigned long long)ps.error_missed_nodes,
           ism_mesher_name(ps.mesher), ism_dual_reason_name(ps.dual_declined));
    ism_locus_free(&locus);
    ism_mesh_free(&mesh);
    return 0;
}

/* N from a word repeat=N among argv[from..argc), else 1; 0 when N is not in 1..MAX_REPEAT. */
static int repeat_word(int argc, char **argv, int from)
{
    for (int i = from; i < argc; i++)
        if (strncmp(argv[i], "repeat=", 7) == 0) {
            char *end;
            long n = strtol(argv[i] + 7, &end, 10);
            return *end == 0 && n >= 1 && n <= MAX_REPEAT ? (int)n : 0;
        }
    return 1;
}

/* Is word one of argv[from..argc)? */
static bool has_word(int argc, char **argv, int from, const char *word)
{
    for (int i = from; i < argc; i++)
        if (strcmp(argv[i], word) == 0)
            return true;
    return false;
}

static int cmd_measure(const measurer *m, const char *path, bool all)
{
    ply p;
    if (!read_ply(path, &p)) {
        fprintf(stderr, "bench_error: cannot read %s (binary PLY, double x y z)\n", path);
        free(p.pos);
        free(p.tri);
        return 1;
    }
    error_stats es = centroid_error(m, p.pos, p.tri, p.ntris, all);
    printf("{\"triangles\": %zu, \"max_c\": %.6g, \"mean_c\": %.6g", es.triangles, es.max,
           es.mean);
    if (all)
        printf(", \"max_m\": %.6g, \"max_v\": %.6g, \"max_all\": %.6g", es.max_mid,
               es.max_vert, fmax(es.max, fmax(es.max_mid, es.max_vert)));
    printf("}\n");
    free(p.pos);
    free(p.tri);
    return 0;
}

static int cmd_eval(const measurer *m, const char *text)
{
    printf("[");
    int n = 0;
    for (const char *c = text; *c && n < MAX_POINTS; n++) {
        double x, y, z;
        int used;
        if (sscanf(c, "%lf,%lf,%lf%n", &x, &y, &z, &used) != 3)
            return 1;
        printf("%s%.17g", n ? ", " : "", ism_eval_point(m->t, m->ws, x, y, z));
        c += used;
        c += *c == ';';
    }
    printf("]\n");
    return 0;
}

static int cmd_list(void)
{
    printf("[");
    for (size_t i = 0; i < NSURFACES; i++) {
        const surface *s = &SURFACES[i];
        printf("%s{\"name\": \"%s\", \"box\": [%g, %g, %g, %g, %g, %g], \"params\": {", i ? ", " : "",
               s->name, s->box[0], s->box[1], s->box[2], s->box[3], s->box[4], s->box[5]);
        for (size_t k = 0; k < s->nparams; k++)
            printf("%s\"%s\": %.17g", k ? ", " : "", s->params[k].name, s->params[k].value);
        printf("}, \"targets\": [%g, %g, %g]}", s->targets[0], s->targets[1], s->targets[2]);
    }
    printf("]\n");
    return 0;
}

int main(int argc, char **argv)
{
    if (argc == 2 && strcmp(argv[1], "list") == 0)
        return cmd_list();
    if (argc < 4) {
        fprintf(stderr, "usage: bench_error mesh NAME E [DEPTH [raw|simplify] [primal] [straddle] [crease] "
                        "[repeat=N]] | measure NAME FILE.ply [all] | "
                        "eval NAME X,Y,Z[;...] | list\n");
        return 2;
    }
    const surface *s = find_surface(argv[2]);
    ism_tape *t = s ? compile(s) : NULL;
    if (!t)
        return 1;
    measurer m = {s, t, ism_eval_ws_new(t)};
    int rc = 2;
    if (strcmp(argv[1], "mesh") == 0 && repeat_word(argc, argv, 5) == 0)
        fprintf(stderr, "bench_error: repeat=N wants N in 1..%d\n", MAX_REPEAT);
    else if (strcmp(argv[1], "mesh") == 0)
        rc = cmd_mesh(s, t, &m, atof(argv[3]), argc > 4 ? atoi(argv[4]) : 10,
                      has_word(argc, argv, 5, "simplify"),
                      has_word(argc, argv, 5, "straddle"), !has_word(argc, argv, 5, "primal"),
                      has_word(argc, argv, 5, "crease"), repeat_word(argc, argv, 5));
    else if (strcmp(argv[1], "measure") == 0)
        rc = cmd_measure(&m, argv[3], has_word(argc, argv, 4, "all"));
    else if (strcmp(argv[1], "eval") == 0)
        rc = cmd_eval(&m, argv[3]);
    ism_eval_ws_free(m.ws);
    ism_tape_free(t);
    return rc;
}
