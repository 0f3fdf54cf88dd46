/* weld.c — exact-position welding of node outputs with an open-addressing hash table, and
 * the vertex normals: ∇f normalised, or the mean of the adjacent triangles' normals where
 * the gradient vanishes (singular points). */
#include "core/octree/weld.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

typedef struct slot {
    uint32_t vertex; /* UINT32_MAX: empty */
} slot;

/* g scaled to unit length, or 0 0 0 when g is zero or not finite. Dividing by the largest
 * component first keeps the squared length from underflowing (∇f ~ 1e-160 where f = g^64
 * nears its zero gave normals of length 1.015) or overflowing. */
static void unit_normal(const double g[3], float n[3])
{
    double big = fmax(fabs(g[0]), fmax(fabs(g[1]), fabs(g[2]))), s[3] = {0, 0, 0}, len = 0;
    if (big > 0 && isfinite(big)) {
        for (int k = 0; k < 3; k++)
            s[k] = g[k] / big;
        len = sqrt(s[0] * s[0] + s[1] * s[1] + s[2] * s[2]);
    }
    for (int k = 0; k < 3; k++)
        n[k] = len > 0 ? (float)(s[k] / len) : 0.0f; /* NaN len: no normal */
}

static uint64_t hash_point(const double p[3])
{
    uint64_t h = 0x9e3779b97f4a7c15ull;
    for (int k = 0; k < 3; k++) {
        uint64_t b;
        double v = p[k] == 0 ? 0.0 : p[k]; /* -0.0 and 0.0 are one point */
        memcpy(&b, &v, sizeof b);
        h ^= b + 0x9e3779b97f4a7c15ull + (h << 6) + (h >> 2);
        h *= 0xff51afd7ed558ccdull;
    }
    return h ^ (h >> 33);
}

static bool same_point(const double a[3], const double b[3])
{
    return a[0] == b[0] && a[1] == b[1] && a[2] == b[2];
}

typedef struct table {
    slot *s;
    size_t mask;
} table;

static uint32_t find_or_add(table *t, ism_mesh *m, const ism_fpoint *p, bool *added)
{
    size_t i = hash_point(p->p) & t->mask;
    for (;;) {
        uint32_t v = t->s[i].vertex;
        if (v == UINT32_MAX)
            break;
        if (same_point(m->pos + 3 * v, p->p)) {
            *added = false;
            return v;
        }
        i = (i + 1) & t->mask;
    }
    float n[3];
    unit_normal(p->g, n);
    uint32_t v = ism_mesh_add_vertex(m, p->p, n);
    if (v != UINT32_MAX)
        t->s[i].vertex = v;
    *added = true;
    return v;
}

static void count_kind(ism_weld_stats *st, uint8_t flags)
{
    st->zero_vertices += (flags & ISM_FP_ZERO) != 0;
    st->touch_vertices += (flags & ISM_FP_TOUCH) != 0;
    st->pair_vertices += (flags & ISM_FP_PAIR) != 0;
    st->many_vertices += (flags & ISM_FP_MANY) != 0;
}

/* Normals where ∇f vanished: the mean of the adjacent triangles' normals. */
static void fill_missing_normals(ism_mesh *m)
{
    double *acc = calloc(m->nverts * 3, sizeof *acc);
    if (!acc)
        return;
    for (size_t t = 0; t < m->ntris; t++) {
        const uint32_t *tri = m->tri + 3 * t;
        const double *a = m->pos + 3 * tri[0], *b = m->pos + 3 * tri[1], *c = m->pos + 3 * tri[2];
        double u[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]};
        double v[3] = {c[0] - a[0], c[1] - a[1], c[2] - a[2]};
        double n[3] = {u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2],
                       u[0] * v[1] - u[1] * v[0]};
        for (int k = 0; k < 3; k++)
            for (int j = 0; j < 3; j++)
                acc[3 * tri[k] + j] += n[j];
    }
    for (size_t i = 0; i < m->nverts; i++) {
        float *vn = m->normal + 3 * i;
        if (vn[0] != 0 || vn[1] != 0 || vn[2] != 0)
            continue;
        unit_normal(acc + 3 * i, vn);
    }
    free(acc);
}

bool ism_weld(const ism_cell_out *pieces, size_t npieces, ism_mesh *mesh, ism_weld_stats *st)
{
    memset(st, 0, sizeof *st);
    size_t total = 0, tris = 0;
    for (size_t k = 0; k < npieces; k++) {
        total += pieces[k].nverts;
        tris += pieces[k].ntris;
    }
    size_t cap = 16;
    while (cap < 2 * total + 16)
        cap *= 2;
    table t = {malloc(cap * sizeof(slot)), cap - 1};
    uint32_t *map = NULL;
    size_t map_cap = 0;
    bool ok = t.s != NULL && ism_mesh_reserve(mesh, total / 3 + 16, tris);
    if (ok)
        memset(t.s, 0xff, cap * sizeof(slot));
    for (size_t k = 0; k < npieces && ok; k++) {
        const ism_cell_out *o = &pieces[k];
        if (o->nverts > map_cap) {
            uint32_t *nm = realloc(map, o->nverts * sizeof *nm);
            if (!nm) {
                ok = false;
                break;
            }
            map = nm;
            map_cap = o->nverts;
        }
        for (size_t i = 0; i < o->nverts && ok; i++) {
            bool added;
            map[i] = find_or_add(&t, mesh, &o->verts[i], &added);
            ok = map[i] != UINT32_MAX;
            if (added)
                count_kind(st, o->verts[i].flags);
        }
        for (size_t i = 0; i < o->ntris && ok; i++) {
            uint32_t a = map[o->tris[3 * i]], b = map[o->tris[3 * i + 1]], c = map[o->tris[3 * i + 2]];
            if (a == b || b == c || a == c) {
                st->dropped_triangles++;
                continue;
            }
            ok = ism_mesh_add_triangle(mesh, a, b, c);
        }
        for (size_t i = 0; i < o->nsegs && ok; i++) {
            uint32_t a = map[o->segs[2 * i]], b = map[o->segs[2 * i + 1]];
            if (a != b)
                ok = ism_mesh_add_segment(mesh, a, b);
        }
    }
    free(t.s);
    free(map);
    if (ok)
        fill_missing_normals(mesh);
    return ok;
}
