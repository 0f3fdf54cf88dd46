/* bench_wire.c — what a mesh costs on the wire: Draco bytes per triangle and encode time for
 * polygoniser meshes of about 10k, 100k and 1M triangles at 11, 14 and 16 position bits, with
 * positions only, with normals (the service's default attributes) and with every attribute;
 * the encoder speed settings; curvature quantisation; the non-manifold side data beside the
 * payload. Each mesh
 * is also written as binary PLY into the directory given with --out (the reference tools of
 * bench_wire.py read it). Prints one JSON object per line.
 *
 *   bench_wire [--out DIR] [--quick] [--tools]   (--quick: only the small and middle meshes;
 *                                                 --tools: only the tool table, on tool_cases) */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "core/analysis/analysis.h"
#include "core/util/clock.h"
#include "core/mesh/write_mesh.h"
#include "core/octree/polygonise.h"
#include "proto/draco_encode.h"
#include "proto/features.h"
#include "proto/glb.h"
#include "proto/request.h"
#include "proto/wire_mesh.h"

typedef struct bench_case {
    const char *name;
    const char *request;
    int repeats;
} bench_case;

/* Polygoniser meshes of the three sizes (flatness tightened to reach the size). */
static const bench_case cases[] = {
    {"torus-16k", "{\"preset\": \"torus\"}", 9},
    {"sphere-85k", "{\"preset\": \"sphere\", \"depth\": {\"max\": 7}, "
                   "\"tolerances\": {\"flat_normal\": 0.999}}", 5},
    {"gyroid-1M", "{\"preset\": \"gyroid-ball\", \"depth\": {\"max\": 8}, "
                  "\"tolerances\": {\"flat_normal\": 0.99999, \"flat_plane\": 1e-6}}", 3},
    {"klein-80k", "{\"preset\": \"klein-bottle\"}", 5},
    {"steiner", "{\"preset\": \"steiner-roman\"}", 5},
    {"kummer-16", "{\"preset\": \"kummer-16-nodes\", \"depth\": {\"max\": 8}}", 5},
};

/* The presets of issue 16's encoding goal at their default depth and at depth 9: only the
 * tool table (--tools). */
static const bench_case tool_cases[] = {
    {"torus-d7", "{\"preset\": \"torus\"}", 5},
    {"torus-d9", "{\"preset\": \"torus\", \"depth\": {\"max\": 9}}", 3},
    {"gyroid-d7", "{\"preset\": \"gyroid-ball\"}", 3},
    {"gyroid-d9", "{\"preset\": \"gyroid-ball\", \"depth\": {\"max\": 9}}", 2},
    {"klein-d8", "{\"preset\": \"klein-bottle\"}", 3},
    {"kummer16-d9", "{\"preset\": \"kummer-16-nodes\"}", 2},
};

static int cmp_double(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

/* This thread's CPU milliseconds (a loaded machine stretches wall time, not this). */
static double thread_cpu_ms(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
    return (double)ts.tv_sec * 1e3 + (double)ts.tv_nsec / 1e6;
}

/* Shortest encode time over repeats, in CPU time of the encoding thread (the least disturbed
 * by other work on a shared machine); bytes of the (deterministic) output. */
static bool measure(const ism_draco_input *in, int repeats, size_t *bytes, double *ms)
{
    double t[16];
    for (int r = 0; r < repeats && r < 16; r++) {
        ism_draco_output d;
        double t0 = thread_cpu_ms();
        if (!ism_draco_encode(in, &d)) {
            fprintf(stderr, "bench_wire: %s\n", d.error);
            return false;
        }
        t[r] = thread_cpu_ms() - t0;
        *bytes = d.len;
        free(d.data);
    }
    qsort(t, (size_t)repeats, sizeof t[0], cmp_double);
    *ms = t[0];
    return true;
}

static size_t file_write(void *ctx, const void *p, size_t n) { return fwrite(p, 1, n, ctx); }

static ism_draco_input input_of(const ism_wire_mesh *w, unsigned attrs, int bits, int cbits,
                                const ism_draco_tools *tools)
{
    ism_draco_input in = {
        .nverts = w->nverts,
        .ntris = w->ntris,
        .pos = w->pos,
        .tri = w->tri,
        .normal = (attrs & ISM_ATTR_NORMAL) ? w->normal : NULL,
        .mean_curvature = (attrs & ISM_ATTR_MEAN_CURVATURE) ? w->mean_curvature : NULL,
        .gauss_curvature = (attrs & ISM_ATTR_GAUSS_CURVATURE) ? w->gauss_curvature : NULL,
        .vertex_class = (attrs & ISM_ATTR_CLASS) ? w->vertex_class : NULL,
        .position_bits = bits,
        .normal_bits = ISM_REQ_DEFAULT_NORMAL_BITS,
        .curvature_bits = cbits,
        .tools = tools,
    };
    return in;
}

/* Bytes of the uncompressed LINES / POINTS primitives a .glb carries beside the surface. */
static size_t glb_side_bytes(const ism_features *f)
{
    size_t b = 0;
    const ism_polylines *lines[2] = {&f->curves, &f->boundaries};
    for (int i = 0; i < 2; i++) {
        size_t nv = lines[i]->n ? lines[i]->start[lines[i]->n] : 0;
        b += nv * 12 + (nv - (nv ? lines[i]->n : 0)) * 8;
    }
    return b + f->npoints * 12;
}

/* Draco's tool choices on the service's default payload (normals, 14 bits) and on every
 * attribute, each beside the service's: the table that chose ism_draco_default_tools. These
 * meshes carry no crease-side split points or cell labels, unlike the service's payload on a
 * CSG surface (draco_encode.cc gives both). */
static bool run_tools(const bench_case *c, const ism_wire_mesh *w)
{
    static const struct {
        const char *name;
        unsigned attrs;
    } payloads[] = {{"default", ISM_ATTR_DEFAULT}, {"all", ISM_ATTR_ALL}};
    static const struct {
        const char *name;
        ism_draco_tools t;
    } tools[] = {
        {"speed4", {4, ISM_DRACO_CONN_BY_SPEED, ISM_DRACO_PRED_BY_SPEED}},
        {"speed5", {5, ISM_DRACO_CONN_BY_SPEED, ISM_DRACO_PRED_BY_SPEED}},
        {"speed4+standard", {4, ISM_DRACO_CONN_STANDARD, ISM_DRACO_PRED_BY_SPEED}},
        {"speed5+valence", {5, ISM_DRACO_CONN_VALENCE, ISM_DRACO_PRED_BY_SPEED}},
        {"speed8", {8, ISM_DRACO_CONN_BY_SPEED, ISM_DRACO_PRED_BY_SPEED}},
        {"speed8+parallelogram", {8, ISM_DRACO_CONN_BY_SPEED, ISM_DRACO_PRED_PARALLELOGRAM}},
        {"speed8+valence", {8, ISM_DRACO_CONN_VALENCE, ISM_DRACO_PRED_BY_SPEED}},
        {"speed9", {9, ISM_DRACO_CONN_BY_SPEED, ISM_DRACO_PRED_BY_SPEED}},
        {"speed9+valence", {9, ISM_DRACO_CONN_VALENCE, ISM_DRACO_PRED_BY_SPEED}},
        {"speed10", {10, ISM_DRACO_CONN_BY_SPEED, ISM_DRACO_PRED_BY_SPEED}},
    };
    for (size_t p = 0; p < sizeof payloads / sizeof payloads[0]; p++) {
        for (size_t i = 0; i < sizeof tools / sizeof tools[0]; i++) {
            ism_draco_input in = input_of(w, payloads[p].attrs, 14, ISM_REQ_DEFAULT_CURVATURE_BITS,
                                          &tools[i].t);
            size_t bytes;
            double ms;
            if (!measure(&in, c->repeats, &bytes, &ms))
                return false;
            const ism_draco_tools *t = &tools[i].t, *d = &ism_draco_default_tools;
            bool is_default = t->speed == d->speed && t->connectivity == d->connectivity &&
                              t->position_prediction == d->position_prediction;
            printf("{\"case\":\"%s\",\"kind\":\"tools\",\"payload\":\"%s\",\"tools\":\"%s\","
                   "\"bytes\":%zu,\"ms\":%.3f,\"default\":%s}\n",
                   c->name, payloads[p].name, tools[i].name, bytes, ms,
                   is_default ? "true" : "false");
            fflush(stdout);
        }
    }
    return true;
}

static bool run_case(const bench_case *c, const char *out_dir, bool tools_only)
{
    ism_request req;
    ism_req_error rerr;
    if (!ism_request_decode(c->request, strlen(c->request), NULL, &req, &rerr)) {
        fprintf(stderr, "bench_wire: %s: %s\n", c->name, rerr.message);
        return false;
    }
    ism_tape *tape = ism_request_compile(&req, &rerr);
    ism_poly_options o;
    ism_request_poly_options(&req, &o);
    ism_mesh m;
    ism_mesh_init(&m);
    ism_poly_stats ps;
    ism_error err;
    double t0 = ism_now_ms();
    if (!tape || ism_polygonise(tape, &o, &m, &ps, &err) != ISM_POLY_OK) {
        fprintf(stderr, "bench_wire: %s: %s\n", c->name, tape ? err.message : rerr.message);
        return false;
    }
    double poly_ms = ism_now_ms() - t0;
    ism_analysis a;
    if (!ism_analyse(&m, tape, NULL, &a, &err)) {
        fprintf(stderr, "bench_wire: %s: %s\n", c->name, err.message);
        return false;
    }
    double side = 0;
    for (int k = 0; k < 3; k++)
        side = fmax(side, req.poly.box[k + 3] - req.poly.box[k]);
    ism_wire_mesh w;
    ism_features f;
    if (!ism_wire_mesh_build(&m, &a, ISM_ATTR_ALL, ldexp(1, req.poly.max_depth) / side, &w) ||
        !ism_features_build(&a, &f)) {
        fprintf(stderr, "bench_wire: out of memory\n");
        return false;
    }
    size_t flen = 0;
    free(ism_features_json(&m, &f, &flen));
    if (tools_only)
        out_dir = NULL;

    if (out_dir) {
        char path[512];
        snprintf(path, sizeof path, "%s/%s.ply", out_dir, c->name);
        FILE *fp = fopen(path, "wb");
        if (!fp || !ism_write_ply(&m, file_write, fp)) {
            fprintf(stderr, "bench_wire: cannot write %s\n", path);
            return false;
        }
        fclose(fp);
    }

    printf("{\"case\":\"%s\",\"kind\":\"mesh\",\"triangles\":%zu,\"vertices\":%zu,"
           "\"raw_bytes\":%zu,\"ply_bytes\":%zu,\"polygonise_ms\":%.1f,"
           "\"nonmanifold_edges\":%zu,\"nonmanifold_points\":%zu,\"boundary_edges\":%zu,"
           "\"features_json_bytes\":%zu,\"glb_side_bytes\":%zu}\n",
           c->name, m.ntris, m.nverts, m.nverts * 12 + m.ntris * 12, ism_ply_size(&m), poly_ms,
           a.nonmanifold_edges, a.npoints, a.boundary_edges, flen, glb_side_bytes(&f));

    if (tools_only) {
        bool ok = run_tools(c, &w);
        ism_features_free(&f);
        ism_wire_mesh_free(&w);
        ism_analysis_free(&a);
        ism_mesh_free(&m);
        ism_tape_free(tape);
        ism_request_free(&req);
        return ok;
    }
    static const struct {
        const char *name;
        unsigned attrs;
    } variants[] = {{"positions", 0},
                    {"normals", ISM_ATTR_DEFAULT},
                    {"all", ISM_ATTR_ALL}};
    static const int bits[] = {11, 14, 16};
    for (size_t b = 0; b < 3; b++)
        for (size_t v = 0; v < 3; v++) {
            ism_draco_input in = input_of(&w, variants[v].attrs, bits[b],
                                          ISM_REQ_DEFAULT_CURVATURE_BITS, NULL);
            size_t bytes;
            double ms;
            if (!measure(&in, c->repeats, &bytes, &ms))
                return false;
            printf("{\"case\":\"%s\",\"kind\":\"bits\",\"bits\":%d,\"attributes\":\"%s\","
                   "\"bytes\":%zu,\"ms\":%.3f}\n",
                   c->name, bits[b], variants[v].name, bytes, ms);
        }
    static const int speeds[] = {0, 2, 4, 5, 6, 7, 8, 10};
    for (size_t s = 0; s < sizeof speeds / sizeof speeds[0]; s++)
        for (size_t v = 0; v < 2; v++) {
            ism_draco_tools t = {speeds[s], ISM_DRACO_CONN_BY_SPEED, ISM_DRACO_PRED_BY_SPEED};
            ism_draco_input in = input_of(&w, variants[v].attrs, 14, 0, &t);
            size_t bytes;
            double ms;
            if (!measure(&in, c->repeats, &bytes, &ms))
                return false;
            printf("{\"case\":\"%s\",\"kind\":\"speed\",\"speed\":%d,\"attributes\":\"%s\","
                   "\"bytes\":%zu,\"ms\":%.3f}\n",
                   c->name, speeds[s], variants[v].name, bytes, ms);
        }
    if (!run_tools(c, &w))
        return false;
    static const int cbits[] = {0, 10, 12, 14, 16};
    for (size_t k = 0; k < sizeof cbits / sizeof cbits[0]; k++) {
        ism_draco_input in = input_of(&w, ISM_ATTR_ALL, 14, cbits[k], NULL);
        size_t bytes;
        double ms;
        if (!measure(&in, 1, &bytes, &ms))
            return false;
        printf("{\"case\":\"%s\",\"kind\":\"curvature\",\"curvature_bits\":%d,\"bytes\":%zu}\n",
               c->name, cbits[k], bytes);
    }
    fflush(stdout);
    ism_features_free(&f);
    ism_wire_mesh_free(&w);
    ism_analysis_free(&a);
    ism_mesh_free(&m);
    ism_tape_free(tape);
    ism_request_free(&req);
    return true;
}

int main(int argc, char **argv)
{
    const char *out_dir = NULL;
    bool quick = false, tools_only = false;
    for (int i = 1; i < argc; i++) {
        if (strcmp(argv[i], "--out") == 0 && i + 1 < argc)
            out_dir = argv[++i];
        else if (strcmp(argv[i], "--quick") == 0)
            quick = true;
        else if (strcmp(argv[i], "--tools") == 0)
            tools_only = true;
        else {
            fprintf(stderr, "usage: bench_wire [--out DIR] [--quick] [--tools]\n");
            return 2;
        }
    }
    if (tools_only) {
        for (size_t i = 0; i < sizeof tool_cases / sizeof tool_cases[0]; i++)
            if ((!quick || !strstr(tool_cases[i].name, "d9")) &&
                !run_case(&tool_cases[i], out_dir, true))
                return 1;
        return 0;
    }
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
        if (quick && strstr(cases[i].name, "1M"))
            continue;
        if (!run_case(&cases[i], out_dir, false))
            return 1;
    }
    return 0;
}
