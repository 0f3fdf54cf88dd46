/* write_obj.c — Wavefront OBJ text: a comment line, `v` and `vn` lines per vertex (9
 * significant digits, enough for float32 round trips), `f a//a b//b c//c` per triangle. */
#include "core/mesh/write_mesh.h"
#include "core/mesh/write_sink.h"

#include <stdlib.h>

bool ism_write_obj(const ism_mesh *m, ism_write_fn write, void *ctx)
{
    ism_sink *s = malloc(sizeof *s);
    if (!s)
        return false;
    ism_sink_init(s, write, ctx);

    ism_sink_printf(s, "# isomesh: %zu vertices, %zu triangles\n", m->nverts, m->ntris);
    for (size_t i = 0; i < m->nverts; i++) {
        const double *p = m->pos + 3 * i;
        ism_sink_printf(s, "v %.9g %.9g %.9g\n", p[0], p[1], p[2]);
    }
    for (size_t i = 0; i < m->nverts; i++) {
        const float *n = m->normal + 3 * i;
        ism_sink_printf(s, "vn %.6g %.6g %.6g\n", (double)n[0], (double)n[1], (double)n[2]);
    }
    for (size_t t = 0; t < m->ntris; t++) {
        const uint32_t *v = m->tri + 3 * t;
        unsigned long a = v[0] + 1UL, b = v[1] + 1UL, c = v[2] + 1UL;
        ism_sink_printf(s, "f %lu//%lu %lu//%lu %lu//%lu\n", a, a, b, b, c, c);
    }
    bool ok = ism_sink_finish(s);
    free(s);
    return ok;
}
