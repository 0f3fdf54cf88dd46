/* mesh.c — storage of the indexed triangle mesh: growth of the vertex, normal and triangle
 * arrays (doubling, so appends are amortised O(1)), and small queries over them. */
#include "core/mesh/mesh.h"
#include "core/util/grow.h"

#include <stdlib.h>
#include <string.h>

void ism_mesh_init(ism_mesh *m) { memset(m, 0, sizeof *m); }

void ism_mesh_free(ism_mesh *m)
{
    free(m->pos);
    free(m->normal);
    free(m->tri);
    free(m->seg);
    ism_mesh_init(m);
}

static size_t grown(size_t cap, size_t need)
{
    size_t c = cap ? cap : 64;
    while (c < need)
        c *= 2;
    return c;
}

bool ism_mesh_reserve(ism_mesh *m, size_t nverts, size_t ntris)
{
    if (nverts > m->cap_verts) {
        size_t c = grown(m->cap_verts, nverts);
        double *p = realloc(m->pos, c * 3 * sizeof *p);
        if (!p)
            return false;
        m->pos = p;
        float *n = realloc(m->normal, c * 3 * sizeof *n);
        if (!n)
            return false;
        m->normal = n;
        m->cap_verts = c;
    }
    if (ntris > m->cap_tris) {
        size_t c = grown(m->cap_tris, ntris);
        uint32_t *t = realloc(m->tri, c * 3 * sizeof *t);
        if (!t)
            return false;
        m->tri = t;
        m->cap_tris = c;
    }
    return true;
}

uint32_t ism_mesh_add_vertex(ism_mesh *m, const double p[3], const float *normal)
{
    if (m->nverts >= UINT32_MAX - 1 || !ism_mesh_reserve(m, m->nverts + 1, 0))
        return UINT32_MAX;
    size_t i = m->nverts++;
    memcpy(m->pos + 3 * i, p, 3 * sizeof *p);
    if (normal)
        memcpy(m->normal + 3 * i, normal, 3 * sizeof *normal);
    else
        memset(m->normal + 3 * i, 0, 3 * sizeof *m->normal);
    return (uint32_t)i;
}

bool ism_mesh_add_triangle(ism_mesh *m, uint32_t a, uint32_t b, uint32_t c)
{
    if (!ism_mesh_reserve(m, 0, m->ntris + 1))
        return false;
    uint32_t *t = m->tri + 3 * m->ntris++;
    t[0] = a;
    t[1] = b;
    t[2] = c;
    return true;
}

bool ism_mesh_add_segment(ism_mesh *m, uint32_t a, uint32_t b)
{
    if (!ism_grow((void **)&m->seg, &m->cap_segs, m->nsegs + 1, 2 * sizeof *m->seg, 16))
        return false;
    m->seg[2 * m->nsegs] = a;
    m->seg[2 * m->nsegs + 1] = b;
    m->nsegs++;
    return true;
}

size_t ism_mesh_bytes(const ism_mesh *m)
{
    return m->cap_verts * (3 * sizeof(double) + 3 * sizeof(float)) +
           m->cap_tris * 3 * sizeof(uint32_t) + m->cap_segs * 2 * sizeof(uint32_t);
}

bool ism_mesh_bounds(const ism_mesh *m, double lo[3], double hi[3])
{
    if (m->nverts == 0)
        return false;
    for (int k = 0; k < 3; k++)
        lo[k] = hi[k] = m->pos[k];
    for (size_t i = 1; i < m->nverts; i++)
        for (int k = 0; k < 3; k++) {
            double v = m->pos[3 * i + k];
            if (v < lo[k])
                lo[k] = v;
            if (v > hi[k])
                hi[k] = v;
        }
    return true;
}

void ism_mesh_compact(ism_mesh *m, uint32_t *used)
{
    for (size_t i = 0; i < 3 * m->ntris; i++)
        used[m->tri[i]] = 1;
    for (size_t i = 0; i < 2 * m->nsegs; i++)
        used[m->seg[i]] = 1;
    size_t nv = 0;
    for (size_t v = 0; v < m->nverts; v++) {
        if (!used[v]) {
            used[v] = UINT32_MAX;
            continue;
        }
        used[v] = (uint32_t)nv;
        memmove(m->pos + 3 * nv, m->pos + 3 * v, 3 * sizeof *m->pos);
        if (m->normal)
            memmove(m->normal + 3 * nv, m->normal + 3 * v, 3 * sizeof *m->normal);
        nv++;
    }
    m->nverts = nv;
    for (size_t i = 0; i < 3 * m->ntris; i++)
        m->tri[i] = used[m->tri[i]];
    for (size_t i = 0; i < 2 * m->nsegs; i++)
        m->seg[i] = used[m->seg[i]];
}

bool ism_mesh_drop_loose(ism_mesh *m)
{
    uint32_t *used = calloc(m->nverts ? m->nverts : 1, sizeof *used);
    if (!used)
        return false;
    m->nsegs = 0;
    ism_mesh_compact(m, used);
    free(used);
    return true;
}
