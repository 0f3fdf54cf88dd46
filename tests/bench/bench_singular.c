/* bench_singular.c — what the singular-locus stage (core/singular/find.h) costs beside the
 * polygoniser: for every preset at its default box and depth, the polygoniser's time and the
 * stage's time with the same thread count (each the shortest of a few runs: the least
 * disturbed on a shared machine), their ratio (the goal: <= 25%), and what the stage
 * found. Prints one JSON object per line.
 *
 *   bench_singular [--threads N] [--repeats N] */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "core/octree/polygonise.h"
#include "core/singular/find.h"
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

static double polygonise_ms(const ism_tape *t, const ism_preset *p, int threads)
{
    ism_poly_options o;
    ism_poly_options_default(&o);
    memcpy(o.box, p->box, sizeof o.box);
    o.min_depth = p->min_depth;
    o.max_depth = p->max_depth;
    o.threads = threads;
    ism_mesh mesh;
    ism_mesh_init(&mesh);
    ism_poly_stats st;
    ism_error err;
    double t0 = ism_now_ms();
    enum ism_poly_status s = ism_polygonise(t, &o, &mesh, &st, &err);
    double ms = ism_now_ms() - t0;
    ism_mesh_free(&mesh);
    return s == ISM_POLY_OK ? ms : -1.0;
}

static double locus_ms(const ism_tape *t, const ism_preset *p, int threads, ism_locus *l)
{
    ism_locus_options o;
    ism_locus_options_default(&o);
    memcpy(o.box, p->box, sizeof o.box);
    o.max_depth = p->max_depth;
    o.threads = threads;
    ism_locus_init(l);
    ism_error err;
    double t0 = ism_now_ms();
    bool ok = ism_locus_find(t, &o, l, &err);
    double ms = ism_now_ms() - t0;
    return ok ? ms : -1.0;
}

int main(int argc, char **argv)
{
    int threads = 0, repeats = 3;
    for (int i = 1; i + 1 < argc; i += 2) {
        if (strcmp(argv[i], "--threads") == 0)
            threads = atoi(argv[i + 1]);
        else if (strcmp(argv[i], "--repeats") == 0)
            repeats = atoi(argv[i + 1]);
    }
    for (size_t i = 0; i < ism_preset_count(); i++) {
        const ism_preset *p = ism_preset_at(i);
        ism_tape *t = compile_preset(p);
        if (!t)
            return 1;
        double poly = -1, stage = -1;
        ism_locus l = { 0 };
        for (int r = 0; r < repeats; r++) {
            double a = polygonise_ms(t, p, threads);
            if (a >= 0 && (poly < 0 || a < poly))
                poly = a;
            ism_locus_free(&l);
            double b = locus_ms(t, p, threads, &l);
            if (b >= 0 && (stage < 0 || b < stage))
                stage = b;
        }
        size_t certified = 0;
        for (size_t k = 0; k < l.npoints; k++)
            certified += l.points[k].certified;
        printf("{\"preset\": \"%s\", \"depth\": %d, \"polygonise_ms\": %.2f, \"singular_ms\": %.2f, "
               "\"ratio\": %.4f, \"points\": %zu, \"certified\": %zu, \"boxes\": %zu, "
               "\"boxes_visited\": %llu, \"incomplete\": %s}\n",
               p->name, p->max_depth, poly, stage, poly > 0 ? stage / poly : -1.0, l.npoints,
               certified, l.nboxes, (unsigned long long)l.boxes_visited,
               l.incomplete ? "true" : "false");
        fflush(stdout);
        ism_locus_free(&l);
        ism_tape_free(t);
    }
    return 0;
}
