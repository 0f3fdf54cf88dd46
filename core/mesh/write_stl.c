/* write_stl.c — binary STL: an 80-byte header, the triangle count, and per triangle the unit
 * facet normal from the right-hand rule over its corners (zero for a zero-area triangle),
 * the three corners as float32, and a zero attribute byte count. */
#include "core/mesh/write_mesh.h"
#include "core/mesh/write_sink.h"
#include "core/util/vec3.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

size_t ism_stl_size(const ism_mesh *m) { return 84 + m->ntris * 50; }

static void facet_normal(const ism_mesh *m, const uint32_t *v, float out[3])
{
    double n[3];
    ism_tri_cross3(m->pos + 3 * v[0], m->pos + 3 * v[1], m->pos + 3 * v[2], n);
    double len = ism_norm3(n);
    for (int k = 0; k < 3; k++)
        out[k] = len > 0 ? (float)(n[k] / len) : 0.0f;
}

bool ism_write_stl(const ism_mesh *m, ism_write_fn write, void *ctx)
{
    if (m->ntris > UINT32_MAX)
        return false;
    ism_sink *s = malloc(sizeof *s);
    if (!s)
        return false;
    ism_sink_init(s, write, ctx);

    char header[80];
    memset(header, ' ', sizeof header);
    memcpy(header, "isomesh binary STL", 18);
    ism_sink_put(s, header, sizeof header);
    ism_sink_u32le(s, (uint32_t)m->ntris);
    for (size_t t = 0; t < m->ntris; t++) {
        const uint32_t *v = m->tri + 3 * t;
        float n[3];
        facet_normal(m, v, n);
        for (int k = 0; k < 3; k++)
            ism_sink_f32le(s, n[k]);
        for (int c = 0; c < 3; c++)
            for (int k = 0; k < 3; k++)
                ism_sink_f32le(s, (float)m->pos[3 * v[c] + k]);
        ism_sink_u16le(s, 0);
    }
    bool ok = ism_sink_finish(s);
    free(s);
    return ok;
}
