/* analysis_torus.c — times the mesh analysis on a large torus grid (nu × nv quads, 2·nu·nv
 * triangles, vertices exactly on the torus): connectivity and quality alone, then everything
 * with the curvature and accuracy from f on 1 and on all threads; prints the figures that
 * must come out (χ = 0, genus 1, ∫K dA ≈ 0) beside the times and the peak memory.
 *
 *   build/release/bench/analysis_torus [nu nv]      (default 1000 500: 1M triangles) */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <sys/resource.h>
#include <time.h>

#include "core/analysis/analysis.h"
#include "core/expr/expr.h"
#include "core/util/clock.h"

#define PI 3.14159265358979323846

static bool torus_grid(ism_mesh *m, int nu, int nv, double R, double r)
{
    if (!ism_mesh_reserve(m, (size_t)nu * nv, 2 * (size_t)nu * nv))
        return false;
    for (int i = 0; i < nu; i++)
        for (int j = 0; j < nv; j++) {
            double u = 2 * PI * i / nu, v = 2 * PI * j / nv;
            double p[3] = {(R + r * cos(v)) * cos(u), (R + r * cos(v)) * sin(u), r * sin(v)};
            ism_mesh_add_vertex(m, p, NULL);
        }
    for (int i = 0; i < nu; i++)
        for (int j = 0; j < nv; j++) {
            uint32_t a = i * nv + j, b = ((i + 1) % nu) * nv + j;
            uint32_t c = ((i + 1) % nu) * nv + (j + 1) % nv, d = i * nv + (j + 1) % nv;
            ism_mesh_add_triangle(m, a, b, c);
            ism_mesh_add_triangle(m, a, c, d);
        }
    return true;
}

static bool run(const char *what, const ism_mesh *m, const ism_tape *f, int threads)
{
    ism_analysis_options o;
    ism_analysis_options_default(&o);
    o.threads = threads;
    ism_analysis a;
    ism_error err;
    double t0 = ism_now_s();
    if (!ism_analyse(m, f, &o, &a, &err)) {
        fprintf(stderr, "analysis failed: %s\n", err.message);
        return false;
    }
    double ms = (ism_now_s() - t0) * 1e3;
    printf("%-34s %9.1f ms   chi %ld  genus %ld  edges %zu  intK %+.2e  max|f|/|grad f| %.2e\n",
           what, ms, a.euler, a.genus, a.edges, a.total_gauss, a.max_dist_vertex);
    ism_analysis_free(&a);
    return true;
}

int main(int argc, char **argv)
{
    int nu = argc > 2 ? atoi(argv[1]) : 1000, nv = argc > 2 ? atoi(argv[2]) : 500;
    if (nu < 3 || nv < 3 || (double)nu * nv > 5e7) {
        fprintf(stderr, "usage: %s [nu nv] (3 <= nu, nv; nu*nv <= 5e7)\n", argv[0]);
        return 2;
    }
    double R = 2, r = 0.5;
    ism_param p[2] = {{"R", R}, {"r", r}};
    ism_error err;
    ism_tape *f = ism_tape_compile("(x^2+y^2+z^2+R^2-r^2)^2 - 4*R^2*(x^2+y^2)", p, 2, NULL, 0,
                                   NULL, &err);
    ism_mesh m;
    ism_mesh_init(&m);
    if (!f || !torus_grid(&m, nu, nv, R, r)) {
        fprintf(stderr, "set-up failed\n");
        return 1;
    }
    printf("torus grid %d x %d: %zu vertices, %zu triangles, mesh %.1f MB\n", nu, nv, m.nverts,
           m.ntris, ism_mesh_bytes(&m) / 1e6);
    bool ok = run("connectivity + quality (no f)", &m, NULL, 1) &&
              run("everything, 1 thread", &m, f, 1) && run("everything, all threads", &m, f, 0);
    struct rusage ru;
    getrusage(RUSAGE_SELF, &ru);
    printf("peak resident memory %.1f MB (mesh included)\n", ru.ru_maxrss / 1e3);
    ism_mesh_free(&m);
    ism_tape_free(f);
    return ok ? 0 : 1;
}
