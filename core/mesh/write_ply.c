/* write_ply.c — binary little-endian PLY with per-vertex normals: the header, then every
 * vertex as six float32 (position, normal), then every face as a uchar 3 and three int32. */
#include "core/mesh/write_mesh.h"
#include "core/mesh/write_sink.h"

#include <stdio.h>
#include <stdlib.h>

static int ply_header(const ism_mesh *m, char *buf, size_t n)
{
    return snprintf(buf, n,
                    "ply\n"
                    "format binary_little_endian 1.0\n"
                    "comment isomesh\n"
                    "element vertex %zu\n"
                    "property float x\nproperty float y\nproperty float z\n"
                    "property float nx\nproperty float ny\nproperty float nz\n"
                    "element face %zu\n"
                    "property list uchar int vertex_indices\n"
                    "end_header\n",
                    m->nverts, m->ntris);
}

size_t ism_ply_size(const ism_mesh *m)
{
    char head[512];
    int h = ply_header(m, head, sizeof head);
    return (size_t)h + m->nverts * 24 + m->ntris * 13;
}

void ism_ply_put_faces(ism_sink *s, const ism_mesh *m)
{
    for (size_t t = 0; t < m->ntris; t++) {
        ism_sink_u8(s, 3);
        for (int k = 0; k < 3; k++)
            ism_sink_u32le(s, m->tri[3 * t + k]);
    }
}

bool ism_write_ply(const ism_mesh *m, ism_write_fn write, void *ctx)
{
    if (m->nverts > INT32_MAX)
        return false; /* PLY's int indices could not address every vertex */
    ism_sink *s = malloc(sizeof *s);
    if (!s)
        return false;
    ism_sink_init(s, write, ctx);

    char head[512];
    int h = ply_header(m, head, sizeof head);
    ism_sink_put(s, head, (size_t)h);
    for (size_t i = 0; i < m->nverts; i++) {
        for (int k = 0; k < 3; k++)
            ism_sink_f32le(s, (float)m->pos[3 * i + k]);
        for (int k = 0; k < 3; k++)
            ism_sink_f32le(s, m->normal ? m->normal[3 * i + k] : 0.0f);
    }
    ism_ply_put_faces(s, m);
    bool ok = ism_sink_finish(s);
    free(s);
    return ok;
}
