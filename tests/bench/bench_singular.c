/* bench_singular.c — what the singular-locus stage (core/singular/find.h) costs beside the
 * polygoniser: for every preset at its default box and depth, the polygoniser's time and the
 * stage's time with the same thread count (each the shortest of a few runs: the least
 * disturbed on a shared machine), their ratio (the goal: <= 25%), the same in process
 * CPU time (cpu_ratio: what the phases cost, which other load on the machine does not
 * stretch), and what the stage found. Prints one JSON object per line, and last {"worst":
 * NAME, "ratio": R, "worst_cpu": NAME, "cpu_ratio": R} (the presets with the largest ratios).
 *
 *   bench_singular [--threads N] [--repeats N] [--preset NAME] */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "core/octree/polygonise.h"
#include "core/singular/surface.h"
#include "core/util/clock.h"
#include "proto/presets.h"

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
static bool surface_ms(const ism_tape *t, const ism_preset *p, int threads, ism_locus *l,
                       ism_surface_times *times, ism_conform_stats *cs)
{
    ism_poly_options o;
    ism_poly_options_default(&o);
    memcpy(o.box, p->box, sizeof o.box);
    o.min_depth = p->min_depth;
    o.max_depth = p->max_depth;
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

int main(int argc, char **argv)
{
    int threads = 0, repeats = 3;
    const char *only = NULL, *worst = NULL, *worst_cpu = NULL;
    double worst_ratio = -1.0, worst_cpu_ratio = -1.0;
    for (int i = 1; i + 1 < argc; i += 2) {
        if (strcmp(argv[i], "--threads") == 0)
            threads = atoi(argv[i + 1]);
        else if (strcmp(argv[i], "--repeats") == 0)
            repeats = atoi(argv[i + 1]);
        else if (strcmp(argv[i], "--preset") == 0)
            only = argv[i + 1];
    }
    for (size_t i = 0; i < ism_preset_count(); i++) {
        const ism_preset *p = ism_preset_at(i);
        if (only && strcmp(only, p->name) != 0)
            continue;
        ism_tape *t = compile_preset(p);
        if (!t)
            return 1;
        double poly = -1, stage = -1, conform = -1, poly_cpu = -1, stage_cpu = -1;
        ism_locus l = { 0 };
        for (int r = 0; r < repeats; r++) {
            ism_surface_times tm;
            ism_conform_stats cs;
            ism_locus_free(&l);
            if (!surface_ms(t, p, threads, &l, &tm, &cs))
                continue;
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
        printf("{\"preset\": \"%s\", \"depth\": %d, \"polygonise_ms\": %.2f, \"singular_ms\": %.2f, "
               "\"conform_ms\": %.2f, "
               "\"ratio\": %.4f, \"polygonise_cpu_ms\": %.2f, \"singular_cpu_ms\": %.2f, "
               "\"cpu_ratio\": %.4f, \"points\": %zu, \"certified\": %zu, \"boxes\": %zu, "
               "\"boxes_visited\": %llu, \"incomplete\": %s}\n",
               p->name, p->max_depth, poly, stage, conform, poly > 0 ? stage / poly : -1.0,
               poly_cpu, stage_cpu, poly_cpu > 0 ? stage_cpu / poly_cpu : -1.0, l.npoints,
               certified, l.nboxes, (unsigned long long)l.boxes_visited,
               l.incomplete ? "true" : "false");
        fflush(stdout);
        if (poly > 0 && stage / poly > worst_ratio) {
            worst_ratio = stage / poly;
            worst = p->name;
        }
        if (poly_cpu > 0 && stage_cpu / poly_cpu > worst_cpu_ratio) {
            worst_cpu_ratio = stage_cpu / poly_cpu;
            worst_cpu = p->name;
        }
        ism_locus_free(&l);
        ism_tape_free(t);
    }
    if (worst && worst_cpu)
        printf("{\"worst\": \"%s\", \"ratio\": %.4f, \"worst_cpu\": \"%s\", \"cpu_ratio\": %.4f}\n",
               worst, worst_ratio, worst_cpu, worst_cpu_ratio);
    return 0;
}
