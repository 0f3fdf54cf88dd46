/* fuzz_polygonise.c — libFuzzer target for the polygoniser on small random surfaces. The
 * input is 8 option bytes followed by an expression in the fuzz_text.h layout (so mutations
 * stay valid-ish expressions, parameters and lets):
 *
 *   byte 0  min depth 0..3            byte 4  gradient test
 *   byte 1  max depth (min..4)        byte 5  flatness (normal cosine, plane distance)
 *   byte 2  box size and shape        byte 6  stitch tolerance, double-root iterations
 *   byte 3  box centre                byte 7  double-root eps, triangle budget; bits 6-7:
 *                                             cancel at the first progress report / run
 *                                             again on 2 threads and compare
 *
 * Each run stays small: depth <= 4 (depth 5 costs ~0.4 s under the sanitizers), at most 300
 * expression nodes, one thread, a budget of at most 20000 triangles. Checks: the status is
 * one the options allow; a finished mesh has every index below nverts, finite positions
 * inside the box, unit or zero normals, at most max_triangles triangles, statistics that
 * count what the mesh holds, progress within [0, 1]; and the same mesh from 2 threads as
 * from 1 (the header promises determinism).
 *
 * The regression tests include this file with ISM_FUZZ_NO_ENTRY defined and call
 * ism_fuzz_polygonise on every committed input. */
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "core/expr/expr.h"
#include "core/mesh/mesh.h"
#include "core/octree/polygonise.h"
#include "tests/fuzz/fuzz_check.h"
#include "tests/fuzz/fuzz_text.h"

#define POLY_OPTION_BYTES 8

typedef struct poly_watch {
    volatile int cancel;
    int cancel_at_first;   /* set cancel when the first progress report arrives */
    size_t reports;
    double bad_fraction;   /* a reported fraction outside [0, 1], or 0 */
    int bad;
} poly_watch;

static void poly_progress(void *ctx, double fraction)
{
    poly_watch *w = ctx;
    w->reports++;
    if (!(fraction >= 0 && fraction <= 1)) {
        w->bad = 1;
        w->bad_fraction = fraction;
    }
    if (w->cancel_at_first)
        w->cancel = 1;
}

/* The tolerances stay inside the ranges of core/octree/tolerances.h (its edges included). */
static void poly_options_from(const uint8_t *b, ism_poly_options *o)
{
    static const double size[8] = {1e-3, 0.1, 0.5, 1, 1.5, 2, 3, 10};
    static const double stretch[4] = {1, 0.5, 2, 0.01};
    static const double centre[8] = {0, 0.1, -0.3, 0.5, 1, 1e-7, -2, 0.123456};
    static const double gradient[8] = {0.9, -1, 1, 0, 0.5, 0.99, -0.5, 0.95};
    static const double fnormal[8] = {0.9, 0.8, -1, 1, 0, 0.5, 0.99, 0.999};
    static const double fplane[8] = {0.05, 0.1, 1e-6, 1, 0.7, 0.01, 0.5, 0.2};
    static const double stitch[8] = {1e-3, 2e-9, 0.25, 1e-6, 0.01, 0.1, 1e-9, 0.05};
    static const int iters[8] = {25, 1, 59, 5, 60, 10, 2, 40};
    static const double eps[8] = {1e-9, 0, 1, 1e-3, 1e-15, 1e-6, 0.5, 0.9};
    static const size_t budget[8] = {20000, 1, 10, 100, 1000, 5000, 20000, 20000};

    ism_poly_options_default(o);
    o->min_depth = b[0] % 4;
    o->max_depth = o->min_depth + b[1] % (5 - o->min_depth);
    double s = size[b[2] & 7], c = centre[b[3] & 7];
    double half[3] = {s, s * stretch[(b[2] >> 3) & 3], s * stretch[(b[2] >> 5) & 3]};
    double mid[3] = {c, -0.5 * c, c * ((b[3] >> 3) & 3)};
    for (int k = 0; k < 3; k++) {
        o->box[k] = mid[k] - half[k];
        o->box[3 + k] = mid[k] + half[k];
    }
    o->gradient_test = gradient[b[4] & 7];
    o->flat_normal = fnormal[b[5] & 7];
    o->flat_plane = fplane[(b[5] >> 3) & 7];
    o->stitch_tol = stitch[b[6] & 7];
    o->double_root_iters = iters[(b[6] >> 3) & 7];
    o->double_root_eps = eps[b[7] & 7];
    o->max_triangles = budget[(b[7] >> 3) & 7];
    o->max_memory = (size_t)256 << 20;
    o->threads = 1;
}

static void poly_check_mesh(const ism_mesh *m, const ism_poly_options *o,
                            const ism_poly_stats *st)
{
    FUZZ_CHECK(m->ntris <= o->max_triangles, "%zu triangles over the budget %zu", m->ntris,
               o->max_triangles);
    FUZZ_CHECK(st->triangles == m->ntris && st->vertices == m->nverts,
               "stats say %llu triangles, %llu vertices; the mesh has %zu, %zu",
               (unsigned long long)st->triangles, (unsigned long long)st->vertices, m->ntris,
               m->nverts);
    for (size_t i = 0; i < 3 * m->ntris; i++)
        FUZZ_CHECK(m->tri[i] < m->nverts, "triangle %zu uses vertex %u of %zu", i / 3,
                   (unsigned)m->tri[i], m->nverts);
    for (size_t i = 0; i < 2 * m->nsegs; i++)
        FUZZ_CHECK(m->seg[i] < m->nverts, "segment %zu uses vertex %u of %zu", i / 2,
                   (unsigned)m->seg[i], m->nverts);
    for (size_t v = 0; v < m->nverts; v++) {
        const double *p = m->pos + 3 * v;
        for (int k = 0; k < 3; k++) {
            double side = o->box[3 + k] - o->box[k], slack = 1e-9 * side;
            FUZZ_CHECK(isfinite(p[k]), "vertex %zu has coordinate %g", v, p[k]);
            FUZZ_CHECK(p[k] >= o->box[k] - slack && p[k] <= o->box[3 + k] + slack,
                       "vertex %zu at %.17g is outside the box [%.17g, %.17g] on axis %c", v,
                       p[k], o->box[k], o->box[3 + k], "xyz"[k]);
        }
        const float *n = m->normal + 3 * v;
        double len = sqrt((double)n[0] * n[0] + (double)n[1] * n[1] + (double)n[2] * n[2]);
        FUZZ_CHECK(len == 0 || fabs(len - 1) < 1e-4, "vertex %zu has a normal of length %.9g",
                   v, len);
    }
}

static int poly_same_bytes(const void *a, const void *b, size_t n)
{
    return n == 0 || memcmp(a, b, n) == 0; /* empty arrays may be NULL */
}

static int poly_same_mesh(const ism_mesh *a, const ism_mesh *b)
{
    return a->nverts == b->nverts && a->ntris == b->ntris && a->nsegs == b->nsegs &&
           poly_same_bytes(a->pos, b->pos, 3 * a->nverts * sizeof *a->pos) &&
           poly_same_bytes(a->normal, b->normal, 3 * a->nverts * sizeof *a->normal) &&
           poly_same_bytes(a->tri, b->tri, 3 * a->ntris * sizeof *a->tri) &&
           poly_same_bytes(a->seg, b->seg, 2 * a->nsegs * sizeof *a->seg);
}

int ism_fuzz_polygonise(const uint8_t *data, size_t size)
{
    if (size < POLY_OPTION_BYTES)
        return 0;
    ism_poly_options o;
    poly_options_from(data, &o);
    fuzz_text in;
    if (!fuzz_text_parse(&in, data + POLY_OPTION_BYTES, size - POLY_OPTION_BYTES))
        return 0;
    ism_expr_limits lim;
    ism_expr_limits_default(&lim);
    lim.max_source = 1000;
    lim.max_nodes = 300;
    ism_error err;
    memset(&err, 0, sizeof err);
    ism_tape *t = ism_tape_compile(in.expr, in.params, in.nparams, in.lets, in.nlets, &lim,
                                   &err);
    fuzz_text_free(&in);
    if (!t)
        return 0;

    poly_watch w = {0};
    w.cancel_at_first = data[7] >> 6 == 1;
    o.progress = poly_progress;
    o.progress_ctx = &w;
    o.cancel = &w.cancel;
    ism_mesh m;
    ism_mesh_init(&m);
    ism_poly_stats st;
    memset(&st, 0, sizeof st);
    enum ism_poly_status status = ism_polygonise(t, &o, &m, &st, &err);
    FUZZ_CHECK(!w.bad, "progress reported %g", w.bad_fraction);
    switch (status) {
    case ISM_POLY_OK:
        poly_check_mesh(&m, &o, &st);
        break;
    case ISM_POLY_TOO_BIG:
        FUZZ_CHECK(err.message[0], "too big without a message");
        break;
    case ISM_POLY_CANCELLED:
        FUZZ_CHECK(w.cancel, "cancelled without being asked");
        break;
    default:
        FUZZ_CHECK(0, "status %d: %s", (int)status, err.message);
    }

    if (status == ISM_POLY_OK && data[7] >> 6 == 2) {
        ism_poly_options o2 = o;
        o2.threads = 2;
        o2.progress = NULL;
        o2.cancel = NULL;
        ism_mesh m2;
        ism_mesh_init(&m2);
        ism_poly_stats st2;
        enum ism_poly_status status2 = ism_polygonise(t, &o2, &m2, &st2, &err);
        FUZZ_CHECK(status2 == ISM_POLY_OK, "2 threads: status %d: %s", (int)status2,
                   err.message);
        FUZZ_CHECK(poly_same_mesh(&m, &m2), "2 threads give another mesh (%zu/%zu vs %zu/%zu "
                   "vertices/triangles)", m.nverts, m.ntris, m2.nverts, m2.ntris);
        ism_mesh_free(&m2);
    }
    ism_mesh_free(&m);
    ism_tape_free(t);
    return 0;
}

#ifndef ISM_FUZZ_NO_ENTRY
int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);
int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    return ism_fuzz_polygonise(data, size);
}
#endif
