/* write_obj.c — Wavefront OBJ text: a comment line, `v` and `vn` lines per vertex (9
 * significant digits, enough for float32 round trips), then one `vn` per normal of the
 * corners that have one of their own (a crease side, a half-sheet at the singular locus),
 * `f a//na b//nb c//nc` per triangle. */
#include "core/mesh/write_mesh.h"
#include "core/mesh/write_sink.h"

#include <stdlib.h>

static void put_normal(ism_sink *s, const float *n)
{
    ism_sink_printf(s, "vn %.6g %.6g %.6g\n", (double)n[0], (double)n[1], (double)n[2]);
}

bool ism_write_obj_corners(const ism_mesh *m, const ism_obj_corner_normals *cn,
                           ism_write_fn write, void *ctx)
{
    ism_sink *s = malloc(sizeof *s);
    if (!s)
        return false;
    ism_sink_init(s, write, ctx);
    size_t ncn = cn ? cn->n : 0, nn = ncn ? cn->nnormals : 0;

    ism_sink_printf(s, "# isomesh: %zu vertices, %zu triangles\n", m->nverts, m->ntris);
    for (size_t i = 0; i < m->nverts; i++) {
        const double *p = m->pos + 3 * i;
        ism_sink_printf(s, "v %.9g %.9g %.9g\n", p[0], p[1], p[2]);
    }
    for (size_t i = 0; i < m->nverts; i++)
        put_normal(s, m->normal + 3 * i);
    for (size_t j = 0; j < nn; j++)
        put_normal(s, cn->normal + 3 * j);
    size_t j = 0; /* the next corner with its own normal */
    for (size_t t = 0; t < m->ntris; t++) {
        ism_sink_printf(s, "f");
        for (size_t c = 3 * t; c < 3 * t + 3; c++) {
            unsigned long v = m->tri[c] + 1UL, n = v;
            if (j < ncn && cn->at[j] == c) {
                n = m->nverts + 1 + cn->which[j];
                j++;
            }
            ism_sink_printf(s, " %lu//%lu", v, n);
        }
        ism_sink_printf(s, "\n");
    }
    bool ok = ism_sink_finish(s);
    free(s);
    return ok;
}

bool ism_write_obj(const ism_mesh *m, ism_write_fn write, void *ctx)
{
    return ism_write_obj_corners(m, NULL, write, ctx);
}
