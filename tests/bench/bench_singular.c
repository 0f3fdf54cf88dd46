/* bench_singular.c — what the singular-locus stage (core/singular/find.h) costs beside the
 * polygoniser: for every preset at its default box, on the two paths a preset is meshed by —
 * "bound", the default error bound users get (max_error ISM_REQ_DEFAULT_ERROR_REL of the box
 * diagonal, the preset's bound depth, the dual mesher: what `isomesh --surface P` does) and
 * "depth", the depth-driven path at the preset's depth (max_error null) — the polygoniser's
 * time and the
 * stage's time with the same thread count (each the shortest of a few runs: the least
 * disturbed on a shared machine), their ratio (the goal: <= 25%), the same in process
 * CPU time (cpu_ratio: what the phases cost, which other load on the machine does not
 * stretch), and what the stage found. Prints one JSON object per line and path ("path":
 * "bound" or "depth"), and last per path {"worst": NAME, "path": P, "ratio": R, "worst_cpu":
 * NAME, "cpu_ratio": R} (the presets with the largest ratios).
 *
 *   bench_singular [--threads N] [--repeats N] [--preset NAME] [--path bound|depth|both] */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "core/octree/polygonise.h"
#include "core/singular/surface.h"
#include "core/util/clock.h"
#include "proto/presets.h"
#include "proto/request.h"

static ism_tape *compile_preset(const ism_preset *p)
{
    ism_param prm[16];
    ism_let lets[16];
    for (size_t i = 0; i < p->nparams && i < 16; i++)
        prm[i] = (ism_param){ p->params[i].name, p->params[i].value };
    for (size_t i = 0; i < p->nlets && i < 16; i++)
        lets[i] = p->lets[i];
    ism_error err;
    ism_tape *t = ism_tape_compile(p->expr, prm, p->nparams, lets, p->nlets, NULL, &err);
    if (!t)
        fprintf(stderr, "bench_singular: %s: %s\n", p->name, err.message);
    return t;
}

/* One run of the whole surface (core/singular/surface.c): the polygoniser's time and the
 * singular stage's (locus from f, conformance, double sheets), measured inside one call. */
static bool surface_ms(const ism_tape *t, const ism_preset *p, bool bound, int threads,
                       ism_locus *l, ism_surface_times *times, ism_conform_stats *cs)
{
    ism_poly_options o;
    ism_poly_options_default(&o);
    memcpy(o.box, p->box, sizeof o.box);
    o.min_depth = p->min_depth;
    o.max_depth = p->max_depth;
    if (bound) { /* as the CLI and a request without "max_error" do (server/isomesh/cli_run.c) */
        o.max_error = ism_request_default_error(o.box);
        o.max_depth = ism_preset_bound_depth(p, ISM_REQ_DEFAULT_MAX_DEPTH_LIMIT);
        o.dual = true;
    }
    o.threads = threads;
    ism_mesh mesh;
    ism_mesh_init(&mesh);
    ism_locus_init(l);
    ism_poly_stats st;
    ism_error err;
    enum ism_poly_status s = ism_mesh_surface(t, &o, &mesh, l, &st, cs, times, &err);
    ism_mesh_free(&mesh);
    return s == ISM_POLY_OK;
}

/* The worst ratios of one path so far. */
typedef struct worst_row {
    const char *name, *name_cpu;
    double ratio, ratio_cpu;
} worst_row;

/* One preset on one path: the shortest of repeats runs, printed as one JSON line. */
static void run_preset(const ism_tape *t, const ism_preset *p, bool bound, int threads,
                       int repeats, worst_row *w)
{
    double poly = -1, stage = -1, conform = -1, poly_cpu = -1, stage_cpu = -1;
    ism_locus l = { 0 };
    int depth = 0;
    for (int r = 0; r < repeats; r++) {
        ism_surface_times tm;
        ism_conform_stats cs;
        ism_locus_free(&l);
        if (!surface_ms(t, p, bound, threads, &l, &tm, &cs))
            continue;
        depth = bound ? ism_preset_bound_depth(p, ISM_REQ_DEFAULT_MAX_DEPTH_LIMIT) : p->max_depth;
        if (poly < 0 || tm.polygonise_ms < poly)
            poly = tm.polygonise_ms;
        if (stage < 0 || tm.singular_ms < stage) {
            stage = tm.singular_ms;
            conform = cs.time_ms;
        }
        if (poly_cpu < 0 || tm.polygonise_cpu_ms < poly_cpu)
            poly_cpu = tm.polygonise_cpu_ms;
        if (stage_cpu < 0 || tm.singular_cpu_ms < stage_cpu)
            stage_cpu = tm.singular_cpu_ms;
    }
    size_t certified = 0;
    for (size_t k = 0; k < l.npoints; k++)
        certified += l.points[k].certified;
    printf("{\"preset\": \"%s\", \"path\": \"%s\", \"depth\": %d, \"polygonise_ms\": %.2f, "
           "\"singular_ms\": %.2f, \"conform_ms\": %.2f, "
           "\"ratio\": %.4f, \"polygonise_cpu_ms\": %.2f, \"singular_cpu_ms\": %.2f, "
           "\"cpu_ratio\": %.4f, \"points\": %zu, \"certified\": %zu, \"boxes\": %zu, "
           "\"boxes_visited\": %llu, \"incomplete\": %s}\n",
           p->name, bound ? "bound" : "depth", depth, poly, stage, conform,
           poly > 0 ? stage / poly : -1.0, poly_cpu, stage_cpu,
           poly_cpu > 0 ? stage_cpu / poly_cpu : -1.0, l.npoints, certified, l.nboxes,
           (unsigned long long)l.boxes_visited, l.incomplete ? "true" : "false");
    fflush(stdout);
    if (poly > 0 && stage / poly > w->ratio) {
        w->ratio = stage / poly;
        w->name = p->name;
    }
    if (poly_cpu > 0 && stage_cpu / poly_cpu > w->ratio_cpu) {
        w->ratio_cpu = stage_cpu / poly_cpu;
        w->name_cpu = p->name;
    }
    ism_locus_free(&l);
}

int main(int argc, char **argv)
{
    int threads = 0, repeats = 3;
    const char *only = NULL, *path = "both";
    for (int i = 1; i + 1 < argc; i += 2) {
        if (strcmp(argv[i], "--threads") == 0)
            threads = atoi(argv[i + 1]);
        else if (strcmp(argv[i], "--repeats") == 0)
            repeats = atoi(argv[i + 1]);
        else if (strcmp(argv[i], "--preset") == 0)
            only = argv[i + 1];
        else if (strcmp(argv[i], "--path") == 0)
            path = argv[i + 1];
    }
    bool paths[2] = { strcmp(path, "depth") != 0, strcmp(path, "bound") != 0 }; /* bound, depth */
    worst_row worst[2] = { { NULL, NULL, -1.0, -1.0 }, { NULL, NULL, -1.0, -1.0 } };
    for (size_t i = 0; i < ism_preset_count(); i++) {
        const ism_preset *p = ism_preset_at(i);
        if (only && strcmp(only, p->name) != 0)
            continue;
        ism_tape *t = compile_preset(p);
        if (!t)
            return 1;
        for (int k = 0; k < 2; k++)
            if (paths[k])
                run_preset(t, p, k == 0, threads, repeats, &worst[k]);
        ism_tape_free(t);
    }
    for (int k = 0; k < 2; k++)
        if (worst[k].name && worst[k].name_cpu)
            printf("{\"worst\": \"%s\", \"path\": \"%s\", \"ratio\": %.4f, \"worst_cpu\": \"%s\", "
                   "\"cpu_ratio\": %.4f}\n", worst[k].name, k == 0 ? "bound" : "depth",
                   worst[k].ratio, worst[k].name_cpu, worst[k].ratio_cpu);
    return 0;
}
