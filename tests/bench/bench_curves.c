/* bench_curves.c — the issue-14 benchmark: an ellipsoid cut by 200 random quadrics (seeded:
 * reproducible), the arrangement built, its size, the Euler check and the time per half-edge
 * pair (cut + arrangement; the mesh's own time apart), printed as one JSON line beside the
 * seed paper's figure (CGAL, exact: 79,532 V, 155,176 E, 75,646 F in 399.8 s, 2.5-6 ms per
 * half-edge pair). Usage: bench_curves [--depth D] [--quadrics N] [--threads N] */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include "core/curves/curves.h"
#include "core/octree/polygonise.h"
#include "core/util/clock.h"

/* CPU time of this process (the machine may be shared: wall time then overstates). */
static double cpu_ms(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
    return (double)ts.tv_sec * 1e3 + (double)ts.tv_nsec / 1e6;
}

#define SEED_MS_PER_PAIR (399.8e3 / 155176.0) /* the paper's time over its edge count */

/* A 64-bit LCG (Knuth's MMIX constants): the same quadrics on every machine. */
static double uniform(uint64_t *s)
{
    *s = *s * 6364136223846793005ULL + 1442695040888963407ULL;
    return (double)(*s >> 11) / 9007199254740992.0;
}

/* A random quadric through a random point near the ellipsoid: a small sphere or hyperboloid
 * of random axes, written as an expression. */
static void quadric(uint64_t *s, char *buf, size_t n)
{
    double c[3], a[3];
    for (int k = 0; k < 3; k++) {
        c[k] = (2 * uniform(s) - 1) * (k == 0 ? 2.0 : k == 1 ? 1.5 : 1.0);
        a[k] = (uniform(s) < 0.2 ? -1 : 1) * (0.5 + 2 * uniform(s));
    }
    double r = 0.3 + 0.9 * uniform(s);
    snprintf(buf, n, "%.17g*(x-%.17g)^2 + %.17g*(y-%.17g)^2 + %.17g*(z-%.17g)^2 - %.17g",
             a[0], c[0], a[1], c[1], a[2], c[2], r * r);
}

/* FNV-1a over the cut mesh's positions and triangles and the cut's edges: equal hashes, the
 * same results bit for bit (a change meant to save work only can be checked by it). */
static uint64_t result_hash(const ism_mesh *m, const ism_cut *c)
{
    uint64_t h = 1469598103934665603ULL;
    const unsigned char *parts[3] = {(const void *)m->pos, (const void *)m->tri,
                                     (const void *)c->edges};
    size_t len[3] = {3 * m->nverts * sizeof *m->pos, 3 * m->ntris * sizeof *m->tri,
                     c->nedges * sizeof *c->edges};
    for (int k = 0; k < 3; k++)
        for (size_t i = 0; i < len[k]; i++)
            h = (h ^ parts[k][i]) * 1099511628211ULL;
    return h;
}

/* FNV-1a over n bytes at p, continuing h. */
static uint64_t fnv(uint64_t h, const void *p, size_t n)
{
    const unsigned char *b = p;
    for (size_t i = 0; i < n; i++)
        h = (h ^ b[i]) * 1099511628211ULL;
    return h;
}

/* The same over the arrangement, field by field (its structs have padding): vertices,
 * edges, faces, curves, the edges' vertex chains and the triangles' faces. */
static uint64_t arrangement_hash(const ism_arrangement *a, size_t ntris)
{
    uint64_t h = 1469598103934665603ULL;
    for (size_t i = 0; i < a->nvertices; i++) {
        const ism_arr_vertex *v = &a->vertices[i];
        int f[3] = {v->degree, v->type, v->point};
        h = fnv(fnv(h, &v->v, sizeof v->v), f, sizeof f);
    }
    for (size_t i = 0; i < a->nedges; i++) {
        const ism_arr_edge *e = &a->edges[i];
        uint32_t f[4] = {e->from, e->to, e->curve, e->fn};
        size_t z[2] = {e->first, e->count};
        h = fnv(fnv(fnv(h, f, sizeof f), &e->length, sizeof e->length), z, sizeof z);
    }
    for (size_t i = 0; i < a->nfaces; i++) {
        const ism_arr_face *f = &a->faces[i];
        size_t z[2] = {f->first, f->ntris};
        long l[2] = {f->euler, f->euler_open};
        uint32_t u[2] = {f->boundary, f->component};
        h = fnv(fnv(fnv(fnv(h, z, sizeof z), &f->area, sizeof f->area), l, sizeof l), u,
                sizeof u);
    }
    for (size_t i = 0; i < a->ncurves; i++) {
        const ism_arr_curve *c = &a->curves[i];
        uint32_t u[2] = {c->fn, c->closed};
        h = fnv(fnv(fnv(h, u, sizeof u), &c->length, sizeof c->length), &c->nedges,
                sizeof c->nedges);
    }
    h = fnv(h, a->chain, a->nchain * sizeof *a->chain);
    return a->tri_face ? fnv(h, a->tri_face, ntris * sizeof *a->tri_face) : h;
}

int main(int argc, char **argv)
{
    int depth = 8, nq = 200, threads = 0;
    for (int i = 1; i + 1 < argc; i += 2) {
        if (!strcmp(argv[i], "--depth"))
            depth = atoi(argv[i + 1]);
        else if (!strcmp(argv[i], "--quadrics"))
            nq = atoi(argv[i + 1]);
        else if (!strcmp(argv[i], "--threads"))
            threads = atoi(argv[i + 1]);
    }
    ism_error err;
    ism_tape *f = ism_tape_compile("x^2/4 + y^2/2.25 + z^2 - 1", NULL, 0, NULL, 0, NULL, &err);
    ism_poly_options o;
    ism_poly_options_default(&o);
    const double box[6] = {-2.3, -1.8, -1.3, 2.3, 1.8, 1.3};
    memcpy(o.box, box, sizeof box);
    o.min_depth = 4;
    o.max_depth = depth;
    o.threads = threads;
    ism_mesh m;
    ism_mesh_init(&m);
    ism_poly_stats ps;
    double t0 = ism_now_ms();
    if (!f || ism_polygonise(f, &o, &m, &ps, &err) != ISM_POLY_OK || !ism_mesh_drop_loose(&m)) {
        fprintf(stderr, "bench_curves: meshing failed: %s\n", err.message);
        return 1;
    }
    double t1 = ism_now_ms();
    size_t tris_before = m.ntris;
    ism_tape **g = calloc((size_t)nq, sizeof *g);
    ism_cut_fn *fns = calloc((size_t)nq, sizeof *fns);
    uint64_t seed = 14;
    for (int i = 0; i < nq; i++) {
        char src[512];
        quadric(&seed, src, sizeof src);
        g[i] = ism_tape_compile(src, NULL, 0, NULL, 0, NULL, &err);
        fns[i] = (ism_cut_fn){.tape = g[i], .kind = ISM_CUT_INTERSECTION, .source = i};
    }
    ism_cut cut;
    ism_arrangement arr;
    double t2 = ism_now_ms(), c2 = cpu_ms();
    if (!ism_curves_cut(f, fns, (size_t)nq, box, &m, &cut, &arr, &err)) {
        fprintf(stderr, "bench_curves: %s\n", err.message);
        return 1;
    }
    double t3 = ism_now_ms(), c3 = cpu_ms();
    double pair_ms = arr.nedges ? (t3 - t2) / (double)arr.nedges : 0;
    printf("{\"quadrics\": %d, \"depth\": %d, \"triangles_before\": %zu, \"triangles\": %zu, "
           "\"vertices\": %zu, \"edges\": %zu, \"faces\": %zu, \"euler_ok\": %s, "
           "\"euler\": %ld, \"unrefined\": %zu, \"mesh_ms\": %.1f, \"cut_ms\": %.1f, "
           "\"cut_cpu_ms\": %.1f, \"ms_per_pair\": %.5f, \"seed_ms_per_pair\": %.3f, "
           "\"ratio\": %.5f, \"cpu_ratio\": %.5f, \"hash\": \"%016llx\", \"worst_f\": %.17g, \"worst_g\": %.17g, \"arrangement_hash\": \"%016llx\"}\n",
           nq, depth, tris_before, m.ntris, arr.nvertices, arr.nedges, arr.nfaces,
           arr.euler_ok ? "true" : "false", arr.euler_arr, cut.unrefined, t1 - t0, t3 - t2,
           c3 - c2, pair_ms, SEED_MS_PER_PAIR, pair_ms / SEED_MS_PER_PAIR,
           arr.nedges ? (c3 - c2) / (double)arr.nedges / SEED_MS_PER_PAIR : 0,
           (unsigned long long)result_hash(&m, &cut), cut.worst_f, cut.worst_g,
           (unsigned long long)arrangement_hash(&arr, m.ntris));
    ism_arrangement_free(&arr);
    ism_cut_free(&cut);
    for (int i = 0; i < nq; i++)
        ism_tape_free(g[i]);
    free(g);
    free(fns);
    ism_mesh_free(&m);
    ism_tape_free(f);
    return 0;
}
