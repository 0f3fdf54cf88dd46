/* bench_threads.c — the measuring half of bench_threads.py: one run of the polygoniser
 * (ism_polygonise alone: no singular locus, no conformance, no analysis) on a surface of the
 * thread-scaling goal, at a depth, on a number of threads. Prints one JSON line: wall and
 * process CPU around the call, and per phase the polygoniser's own figures (wall time_ms,
 * cpu_ms, serial_ms, critical_ms, even_ms: polygonise.h), the evaluations (point, gradient,
 * interval), the mesh's size and a hash of its bytes
 * (positions, normals, triangles) to check that every thread count makes the same mesh.
 *
 *   bench_threads NAME DEPTH THREADS     NAME: gyroid-ball | barth-sextic
 *   bench_threads list */
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "core/octree/polygonise.h"
#include "core/util/clock.h"

typedef struct surface {
    const char *name;
    const char *expr;
    ism_param params[1];
    size_t nparams;
    double box[6];
} surface;

/* The gyroid cut by a ball (the gallery's preset), and Barth's sextic with 65 nodes, cut by a
 * ball as bench_error.c has it. */
static const surface SURFACES[] = {
    {"gyroid-ball",
     "max(sin(k*x)*cos(k*y) + sin(k*y)*cos(k*z) + sin(k*z)*cos(k*x), x^2 + y^2 + z^2 - 1.96)",
     {{"k", 4}}, 1, {-1.5, -1.5, -1.5, 1.5, 1.5, 1.5}},
    {"barth-sextic",
     "max(4*(phi^2*x^2 - y^2)*(phi^2*y^2 - z^2)*(phi^2*z^2 - x^2) - "
     "(1 + 2*phi)*(x^2 + y^2 + z^2 - 1)^2, x^2 + y^2 + z^2 - 2.25)",
     {{"phi", 1.6180339887498949}}, 1, {-1.6, -1.6, -1.6, 1.6, 1.6, 1.6}},
};
#define NSURFACES (sizeof SURFACES / sizeof SURFACES[0])

/* FNV-1a over bytes, continued from h. */
static uint64_t fnv(uint64_t h, const void *p, size_t n)
{
    const unsigned char *b = p;
    for (size_t i = 0; i < n; i++)
        h = (h ^ b[i]) * 0x100000001b3ull;
    return h;
}

static void print_phases(const char *key, const double v[ISM_PHASE_COUNT])
{
    printf(", \"%s\": [%.3f, %.3f, %.3f, %.3f]", key, v[ISM_PHASE_OCTREE], v[ISM_PHASE_CRACKS],
           v[ISM_PHASE_POLYGONS], v[ISM_PHASE_MESH]);
}

static int run(const surface *s, int depth, int threads)
{
    ism_error err;
    ism_tape *t = ism_tape_compile(s->expr, s->params, s->nparams, NULL, 0, NULL, &err);
    if (!t) {
        fprintf(stderr, "bench_threads: %s: %s\n", s->name, err.message);
        return 1;
    }
    ism_poly_options o;
    ism_poly_options_default(&o);
    memcpy(o.box, s->box, sizeof o.box);
    o.max_depth = depth;
    o.threads = threads;
    ism_mesh m;
    ism_mesh_init(&m);
    ism_poly_stats st;
    double w0 = ism_now_ms(), c0 = ism_cpu_ms();
    enum ism_poly_status rc = ism_polygonise(t, &o, &m, &st, &err);
    double wall = ism_now_ms() - w0, cpu = ism_cpu_ms() - c0;
    if (rc != ISM_POLY_OK) {
        fprintf(stderr, "bench_threads: %s: %s\n", s->name, err.message);
        ism_tape_free(t);
        return 1;
    }
    uint64_t h = fnv(0xcbf29ce484222325ull, m.pos, m.nverts * 3 * sizeof *m.pos);
    h = fnv(h, m.normal, m.nverts * 3 * sizeof *m.normal);
    h = fnv(h, m.tri, m.ntris * 3 * sizeof *m.tri);
    printf("{\"surface\": \"%s\", \"depth\": %d, \"threads\": %d, \"wall_ms\": %.3f, "
           "\"process_cpu_ms\": %.3f, \"triangles\": %zu, \"vertices\": %zu, \"hash\": \"%016llx\", "
           "\"phases\": [\"octree\", \"breaks\", \"polygons\", \"weld\"]",
           s->name, depth, st.threads, wall, cpu, m.ntris, m.nverts, (unsigned long long)h);
    print_phases("time_ms", st.time_ms);
    print_phases("cpu_ms", st.cpu_ms);
    print_phases("serial_ms", st.serial_ms);
    print_phases("critical_ms", st.critical_ms);
    print_phases("even_ms", st.even_ms);
    printf(", \"evals\": [%llu, %llu, %llu]", (unsigned long long)st.evals_point,
           (unsigned long long)st.evals_gradient, (unsigned long long)st.evals_interval);
    printf("}\n");
    ism_mesh_free(&m);
    ism_tape_free(t);
    return 0;
}

int main(int argc, char **argv)
{
    if (argc == 2 && strcmp(argv[1], "list") == 0) {
        for (size_t i = 0; i < NSURFACES; i++)
            printf("%s\n", SURFACES[i].name);
        return 0;
    }
    if (argc != 4) {
        fprintf(stderr, "usage: bench_threads NAME DEPTH THREADS | list\n");
        return 2;
    }
    for (size_t i = 0; i < NSURFACES; i++)
        if (strcmp(SURFACES[i].name, argv[1]) == 0)
            return run(&SURFACES[i], atoi(argv[2]), atoi(argv[3]));
    fprintf(stderr, "bench_threads: unknown surface %s\n", argv[1]);
    return 2;
}
