/* rm_mesh.c — the quality pass's incidence (each vertex's triangles, updated by flips and
 * collapses), edge look-ups by scanning a vertex's few triangles, and the shared angle
 * geometry. */
#include "core/remesh/rm_mesh.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

bool rm_mesh_build(rm_mesh *r, ism_mesh *m, size_t extra)
{
    size_t nv = m->nverts, cv = nv + extra, ct = m->ntris + 2 * extra;
    r->m = m;
    r->cap_verts = cv;
    r->cap_tris = ct;
    r->start = calloc(cv ? cv : 1, sizeof *r->start);
    r->room = calloc(cv ? cv : 1, sizeof *r->room);
    r->count = calloc(cv ? cv : 1, sizeof *r->count);
    r->locked = calloc(cv ? cv : 1, 1);
    r->gone = calloc(cv ? cv : 1, 1);
    r->dead = calloc(ct ? ct : 1, 1);
    r->origin = malloc((ct ? ct : 1) * sizeof *r->origin);
    if (!r->start || !r->room || !r->count || !r->locked || !r->gone || !r->dead ||
        !r->origin || ct >= UINT32_MAX || !ism_mesh_reserve(m, cv, ct))
        return false;
    for (size_t t = 0; t < m->ntris; t++)
        r->origin[t] = (uint32_t)t;
    for (size_t i = 0; i < 3 * m->ntris; i++)
        r->count[m->tri[i]]++;
    size_t total = 0;
    for (size_t v = 0; v < nv; v++) {
        r->start[v] = (uint32_t)total;
        r->room[v] = r->count[v] + ISM_RM_SLACK;
        total += r->room[v];
        r->count[v] = 0;
    }
    r->nvt = r->cap_vt = total;
    if (total >= UINT32_MAX || !(r->vt = malloc((total ? total : 1) * sizeof *r->vt)))
        return false;
    for (size_t t = 0; t < m->ntris; t++)
        for (int k = 0; k < 3; k++) {
            uint32_t v = m->tri[3 * t + k];
            /* a collapsed triangle lists its vertex once */
            if (k > 0 && m->tri[3 * t] == v)
                continue;
            if (k > 1 && m->tri[3 * t + 1] == v)
                continue;
            r->vt[r->start[v] + r->count[v]++] = (uint32_t)t;
        }
    return true;
}

void rm_mesh_free(rm_mesh *r)
{
    free(r->start);
    free(r->room);
    free(r->count);
    free(r->gone);
    free(r->dead);
    free(r->origin);
    free(r->vt);
    free(r->locked);
    free(r->locked_edges);
    memset(r, 0, sizeof *r);
}

bool rm_keys_has(const uint64_t *keys, size_t n, uint64_t key)
{
    size_t lo = 0, hi = n;
    while (lo < hi) {
        size_t mid = lo + (hi - lo) / 2;
        if (keys[mid] < key)
            lo = mid + 1;
        else
            hi = mid;
    }
    return lo < n && keys[lo] == key;
}

bool rm_edge_locked(const rm_mesh *r, uint32_t a, uint32_t b)
{
    return rm_keys_has(r->locked_edges, r->nlocked_edges, rm_edge_key(a, b));
}

bool rm_edge_triangles(const rm_mesh *r, uint32_t a, uint32_t b, uint32_t t[2], int *n)
{
    const uint32_t *tri = r->m->tri;
    int forward = 0, backward = 0;
    *n = 0;
    const uint32_t *slot = r->vt + r->start[a];
    for (uint32_t i = 0; i < r->count[a]; i++) {
        uint32_t s = slot[i];
        const uint32_t *c = tri + 3 * (size_t)s;
        if (c[0] != b && c[1] != b && c[2] != b)
            continue; /* most of a's triangles */
        /* a's two neighbours in the winding, without a remainder by 3 (the pass's hottest
           loop: flips and the protection ask for every edge) */
        uint32_t next = c[0] == a ? c[1] : c[1] == a ? c[2] : c[0];
        uint32_t prev = c[0] == a ? c[2] : c[1] == a ? c[0] : c[1];
        if (next == b) {
            t[0] = s;
            forward++;
        } else if (prev == b) {
            t[1] = s;
            backward++;
        } else {
            continue;
        }
        (*n)++;
    }
    return *n == 2 && forward == 1 && backward == 1;
}

void rm_slot_remove(rm_mesh *r, uint32_t v, uint32_t t)
{
    uint32_t *s = r->vt + r->start[v];
    for (uint32_t i = 0; i < r->count[v]; i++)
        if (s[i] == t) {
            s[i] = s[--r->count[v]];
            return;
        }
}

bool rm_slot_room(const rm_mesh *r, uint32_t v)
{
    return r->count[v] < r->room[v];
}

bool rm_slot_reserve(rm_mesh *r, uint32_t v, uint32_t n)
{
    if (r->count[v] + (size_t)n <= r->room[v])
        return true;
    size_t room = 2 * ((size_t)r->count[v] + n);
    if (r->nvt + room >= UINT32_MAX)
        return false;
    if (r->nvt + room > r->cap_vt) {
        size_t cap = 2 * (r->nvt + room);
        uint32_t *vt = realloc(r->vt, cap * sizeof *vt);
        if (!vt)
            return false;
        r->vt = vt;
        r->cap_vt = cap;
    }
    memcpy(r->vt + r->nvt, r->vt + r->start[v], r->count[v] * sizeof *r->vt);
    r->start[v] = (uint32_t)r->nvt;
    r->room[v] = (uint32_t)room;
    r->nvt += room;
    return true;
}

bool rm_slot_add(rm_mesh *r, uint32_t v, uint32_t t)
{
    if (!rm_slot_room(r, v))
        return false;
    r->vt[r->start[v] + r->count[v]++] = t;
    return true;
}

double rm_angle(const double *p, const double *q, const double *s)
{
    double n[3], len = rm_cross(p, q, s, n);
    double dot = (q[0] - p[0]) * (s[0] - p[0]) + (q[1] - p[1]) * (s[1] - p[1]) +
                 (q[2] - p[2]) * (s[2] - p[2]);
    return len == 0 && dot == 0 ? 0 : atan2(len, dot);
}

double rm_min_angle(const double *a, const double *b, const double *c)
{
    /* the smallest angle lies opposite the shortest side */
    double ab = rm_dist(a, b), bc = rm_dist(b, c), ca = rm_dist(c, a);
    if (bc <= ab && bc <= ca)
        return rm_angle(a, b, c);
    return ca <= ab ? rm_angle(b, c, a) : rm_angle(c, a, b);
}

/* A corner whose cosine's square is under this is no cap (cos² 160° = 0.883): the arc
 * tangent is not asked. Far enough under it that rounding in the squares cannot matter
 * while they are normal numbers: sides over ~1e-77. Under that |u|²|w|² is subnormal, and so
 * is rm_angle's squared cross product: the arc tangent fails there too (test_rm_cap.c). */
#define ISM_RM_CAP_COS2_SCREEN 0.8

/* The angle at p of (p, q, s) is at least ISM_RM_CAP_DEG. An angle whose sides' dot
 * product is not negative is at most 90° (its cosine not negative), and one whose cosine's
 * square is under ISM_RM_CAP_COS2_SCREEN at most 153°: no cap there, and the arc tangent is
 * not asked (most corners; of the obtuse ones most too: the flips' caps test was 4.5M of
 * the cube's pass). */
static bool cap_at(const double *p, const double *q, const double *s)
{
    double u[3] = {q[0] - p[0], q[1] - p[1], q[2] - p[2]};
    double w[3] = {s[0] - p[0], s[1] - p[1], s[2] - p[2]};
    double dot = u[0] * w[0] + u[1] * w[1] + u[2] * w[2];
    if (!(dot < 0))
        return false;
    double uu = u[0] * u[0] + u[1] * u[1] + u[2] * u[2];
    double ww = w[0] * w[0] + w[1] * w[1] + w[2] * w[2];
    if (dot * dot < ISM_RM_CAP_COS2_SCREEN * uu * ww)
        return false;
    return cos(rm_angle(p, q, s)) < cos(ISM_RM_CAP_DEG * M_PI / 180);
}

bool rm_is_cap(const double *a, const double *b, const double *c)
{
    return cap_at(a, b, c) || cap_at(b, c, a) || cap_at(c, a, b);
}
