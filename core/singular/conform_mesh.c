/* conform_mesh.c — the mesh bookkeeping of the conformance pass: per-triangle dead marks,
 * the vertex→live-triangle incidence rebuilt before each surgery, appending vertices and
 * triangles, and the final compaction (dead triangles and orphaned vertices dropped, normals
 * of the vertices where ∇f vanishes taken from their triangles as the welder does). */
#include "core/singular/conform_internal.h"
#include "core/util/grow.h"
#include "core/util/clock.h"
#include "core/util/sort_u64.h"
#include "core/util/vec3.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

bool cf_grow_room(void **v, size_t *cap, size_t need, size_t sz)
{
    size_t c = *cap ? *cap : 64;
    while (c < need)
        c *= 2;
    /* fresh: calloc's pages come zeroed from the system for large sizes, where the memset
     * wrote every byte (callgrind counts a byte an instruction: 12 MB of new room on the
     * Klein bottle at E 0.00327, 13.8M of its conformance's 400M). The gain is mostly in
     * counted instructions, not time: below glibc's mmap threshold calloc clears the bytes
     * itself, and above it the kernel zeroes the pages, work callgrind does not count.
     * calloc also checks c * sz for overflow, which realloc's product does not. */
    void *p = *cap ? realloc(*v, c * sz) : calloc(c, sz);
    if (!p)
        return false;
    if (*cap)
        memset((char *)p + *cap * sz, 0, (c - *cap) * sz);
    else
        free(*v);
    *v = p;
    *cap = c;
    return true;
}

/* Below this many keys an insertion sort beats the radix passes' counting. */
#define SORT_SMALL 32

/* Shell sort with gaps first_gap, first_gap / 2, ..., 1 (first_gap 1: an insertion sort). */
static void shell_u32(uint32_t *a, size_t n, size_t first_gap)
{
    for (size_t gap = first_gap; gap > 0; gap /= 2)
        for (size_t i = gap; i < n; i++) {
            uint32_t x = a[i];
            size_t j = i;
            for (; j >= gap && a[j - gap] > x; j -= gap)
                a[j] = a[j - gap];
            a[j] = x;
        }
}

void cf_sort_u32(uint32_t *a, size_t n)
{
    /* equal keys are indistinguishable: any correct sort gives qsort's array */
    if (n < SORT_SMALL) {
        shell_u32(a, n, 1);
        return;
    }
    uint64_t *w = malloc(n * sizeof *w);
    if (!w) { /* out of memory: sorted in place all the same (shell sort: no extra memory) */
        shell_u32(a, n, n / 2);
        return;
    }
    /* the radix sort of 64-bit keys (digits every key shares, the high half here, are no
       pass) */
    for (size_t i = 0; i < n; i++)
        w[i] = a[i];
    ism_sort_u64(w, n);
    for (size_t i = 0; i < n; i++)
        a[i] = (uint32_t)w[i];
    free(w);
}

/* The CSR incidence of the triangles present now (dead ones left out). */
static bool build_incidence(cf_ctx *c)
{
    const ism_mesh *m = c->m;
    c->inc_start = calloc(m->nverts + 1, sizeof *c->inc_start);
    c->inc_tri = malloc((3 * m->ntris + 1) * sizeof *c->inc_tri);
    if (!c->inc_start || !c->inc_tri)
        return false;
    /* the corners written out, not looped (as cf_compact's: the counters cost as much) */
    uint32_t *st = c->inc_start;
    for (size_t t = 0; t < m->ntris; t++)
        if (!c->dead[t]) {
            const uint32_t *v = m->tri + 3 * t;
            st[v[0] + 1]++;
            st[v[1] + 1]++;
            st[v[2] + 1]++;
        }
    for (size_t v = 0; v < m->nverts; v++)
        st[v + 1] += st[v];
    for (size_t t = 0; t < m->ntris; t++)
        if (!c->dead[t]) {
            const uint32_t *v = m->tri + 3 * t;
            c->inc_tri[st[v[0]]++] = (uint32_t)t;
            c->inc_tri[st[v[1]]++] = (uint32_t)t;
            c->inc_tri[st[v[2]]++] = (uint32_t)t;
        }
    for (size_t v = m->nverts; v > 0; v--)
        st[v] = st[v - 1];
    st[0] = 0;
    c->inc_nverts = m->nverts;
    c->inc_ntris = m->ntris;
    return true;
}

bool cf_ctx_prepare(cf_ctx *c)
{
    const ism_mesh *m = c->m;
    if (!cf_grow((void **)&c->dead, &c->cap_dead, m->ntris, 1) ||
        !cf_grow((void **)&c->singular, &c->cap_singular, m->nverts, 1))
        return false;
    if (c->indexed)
        return true;
    if (!build_incidence(c) ||
        !cf_tgrid_init(&c->grid, c->origin, c->extent, c->cell, m->ntris))
        return false;
    c->grid.threads = c->threads;
    c->indexed = true;
    return true;
}

void cf_ctx_free(cf_ctx *c)
{
    free(c->dead);
    free(c->singular);
    free(c->inc_start);
    free(c->inc_tri);
    free(c->x_head);
    free(c->x_next);
    free(c->memo_d);
    free(c->memo_i);
    free(c->memo_gen);
    cf_tgrid_free(&c->grid);
}

bool cf_poll_clock(cf_ctx *c)
{
    c->since_poll = 0;
    c->st->polls++;
    if ((c->cancel && *c->cancel) || (c->deadline_ms > 0 && ism_now_ms() > c->deadline_ms))
        c->stopped = true;
    return c->stopped;
}

bool cf_memo_reset(cf_ctx *c)
{
    size_t n = c->m->nverts + 1;
    /* the answers' room not zeroed (ism_grow): they are read only where memo_gen says one
     * was written (a generation at least the first, gen_base); memo_gen's is (cf_grow) */
    if (!ism_grow((void **)&c->memo_d, &c->cap_memo_d, n, sizeof *c->memo_d, n) ||
        !ism_grow((void **)&c->memo_i, &c->cap_memo_i, n, sizeof *c->memo_i, n) ||
        !cf_grow((void **)&c->memo_gen, &c->cap_memo_gen, n, sizeof *c->memo_gen))
        return false; /* grow zeroes new room: generation 0, never current */
    if (++c->gen == 0) {
        memset(c->memo_gen, 0, c->cap_memo_gen * sizeof *c->memo_gen);
        c->gen = 1;
    }
    return true;
}

/* Files the mesh's last triangle in the incidence and the grid. */
static bool index_last(cf_ctx *c)
{
    ism_mesh *m = c->m;
    size_t t = m->ntris - 1, node = 3 * (t - c->inc_ntris);
    size_t had = c->cap_x_head;
    if (!cf_grow((void **)&c->x_head, &c->cap_x_head, m->nverts, sizeof *c->x_head) ||
        !cf_grow((void **)&c->x_next, &c->cap_x_next, node + 3, sizeof *c->x_next))
        return false;
    if (c->cap_x_head > had) /* new vertices have no appended triangle yet */
        memset(c->x_head + had, 0xff, (c->cap_x_head - had) * sizeof *c->x_head);
    if (!cf_tgrid_add(&c->grid, m, (uint32_t)t))
        return false;
    for (int k = 0; k < 3; k++) {
        uint32_t v = m->tri[3 * t + (size_t)k];
        c->x_next[node + (size_t)k] = c->x_head[v];
        c->x_head[v] = (uint32_t)(node + (size_t)k);
    }
    return true;
}

bool cf_add_triangle(cf_ctx *c, uint32_t a, uint32_t b, uint32_t d)
{
    if (a == b || b == d || a == d)
        return true; /* a ring that collapsed onto its neighbour: nothing to fill */
    cf_poll(c, 1); /* the refill ends at its next ring once this says stop */
    /* the new mark is written below: its room needs no zeroing (ism_grow) */
    if (!ism_grow((void **)&c->dead, &c->cap_dead, c->m->ntris + 1, 1, c->m->ntris + 1) ||
        !ism_mesh_add_triangle(c->m, a, b, d))
        return false;
    c->dead[c->m->ntris - 1] = 0;
    if (c->indexed && !index_last(c)) {
        c->m->ntris--;
        cf_tgrid_truncate(&c->grid, c->m->ntris);
        return false;
    }
    return true;
}

void cf_truncate(cf_ctx *c, size_t ntris, size_t nverts)
{
    ism_mesh *m = c->m;
    if (c->indexed) {
        for (size_t t = m->ntris; t > ntris && t > c->inc_ntris; t--) /* last pushed first */
            for (int k = 2; k >= 0; k--)
                c->x_head[m->tri[3 * (t - 1) + (size_t)k]] =
                    c->x_next[3 * (t - 1 - c->inc_ntris) + (size_t)k];
        cf_tgrid_truncate(&c->grid, ntris);
    }
    m->ntris = ntris;
    m->nverts = nverts;
}

void cf_inc_begin(const cf_ctx *c, uint32_t v, cf_inc *it)
{
    bool base = v < c->inc_nverts;
    it->i = base ? c->inc_start[v] : 0;
    it->end = base ? c->inc_start[v + 1] : 0;
    it->node = v < c->cap_x_head ? c->x_head[v] : CF_NONE;
}

bool cf_inc_next(const cf_ctx *c, cf_inc *it, uint32_t *t)
{
    while (it->i < it->end) {
        *t = c->inc_tri[it->i++];
        if (!c->dead[*t])
            return true;
    }
    while (it->node != CF_NONE) {
        *t = (uint32_t)(c->inc_ntris + it->node / 3);
        it->node = c->x_next[it->node];
        if (!c->dead[*t])
            return true;
    }
    return false;
}

/* The unit normal g / |g| into n; false (n left as it was) where |g| is 0 or not finite. */
static inline __attribute__((always_inline)) bool normal_of(const double g[3], float n[3])
{
    double len = sqrt(g[0] * g[0] + g[1] * g[1] + g[2] * g[2]);
    if (!(len > 0 && isfinite(len)))
        return false;
    for (int k = 0; k < 3; k++)
        n[k] = (float)(g[k] / len);
    return true;
}

/* The unit normal ∇f / |∇f| at p into n; false (n left as it was) where |∇f| is 0 or not
 * finite. Inlined into both callers: cf_add_vertex as cheap as when it held these lines. */
static inline __attribute__((always_inline)) bool normal_at(cf_ctx *c, const double p[3],
                                                       float n[3])
{
    double g[3];
    ism_eval_gradient(c->f, c->ws, p[0], p[1], p[2], g);
    return normal_of(g, n);
}

void cf_set_normal(cf_ctx *c, uint32_t v)
{
    float n[3] = {0, 0, 0};
    normal_at(c, c->m->pos + 3 * (size_t)v, n);
    for (int k = 0; k < 3; k++)
        c->m->normal[3 * (size_t)v + k] = n[k];
}

uint32_t cf_add_vertex_kept(cf_ctx *c, const double p[3], uint8_t flags, const cf_grad *kept)
{
    if (!cf_grow((void **)&c->singular, &c->cap_singular, c->m->nverts + 1, 1))
        return CF_NONE;
    float n[3] = {0, 0, 0};
    if (!(flags & CF_VERTEX_SINGULAR) &&
        !(kept && kept->at ? normal_of(kept->g, n) : normal_at(c, p, n)))
        flags |= CF_VERTEX_SINGULAR;
    uint32_t v = ism_mesh_add_vertex(c->m, p, n);
    if (v != CF_NONE)
        c->singular[v] = flags;
    return v;
}

uint32_t cf_add_vertex(cf_ctx *c, const double p[3], uint8_t flags)
{
    return cf_add_vertex_kept(c, p, flags, NULL);
}

double cf_triangle_longest_edge2(const ism_mesh *m, uint32_t tri)
{
    const uint32_t *t = m->tri + 3 * (size_t)tri;
    double best = 0;
    for (int k = 0; k < 3; k++) {
        double e = ism_sqdist3(m->pos + 3 * (size_t)t[k], m->pos + 3 * (size_t)t[(k + 1) % 3]);
        if (e > best)
            best = e;
    }
    return best;
}

double cf_vertex_longest_edge(const cf_ctx *c, uint32_t v)
{
    double best = 0;
    cf_inc it;
    uint32_t t;
    for (cf_inc_begin(c, v, &it); cf_inc_next(c, &it, &t);)
        best = fmax(best, cf_triangle_longest_edge2(c->m, t));
    return sqrt(best);
}

bool cf_longest_edge_near(cf_ctx *c, const double p[3], double r, double *out)
{
    /* the live triangles with a corner within r of p: their boxes meet p's cube */
    double lo[3], hi[3];
    cf_query_box(p, p, r, lo, hi);
    if (!cf_tgrid_cover(&c->grid, c->m, lo, hi, r)) /* and the first widenings' */
        return false;
    cf_tris cand = {0};
    cf_tgrid_begin(&c->grid);
    if (!cf_tgrid_gather(&c->grid, c->m, lo, hi, c->dead, &cand)) {
        free(cand.t);
        return false;
    }
    double best = 0;
    for (size_t i = 0; i < cand.n && !cf_poll(c, 1); i++) {
        const uint32_t *v = c->m->tri + 3 * (size_t)cand.t[i];
        for (int k = 0; k < 3; k++)
            if (ism_sqdist3(c->m->pos + 3 * (size_t)v[k], p) <= r * r) {
                best = fmax(best, cf_triangle_longest_edge2(c->m, cand.t[i]));
                break;
            }
    }
    free(cand.t);
    *out = sqrt(best);
    return true;
}

/* Normal of a vertex where ∇f vanishes: the area-weighted mean of its triangles' normals. */
static void singular_normals(cf_ctx *c)
{
    ism_mesh *m = c->m;
    double *acc = calloc(m->nverts ? 3 * m->nverts : 1, sizeof *acc);
    if (!acc)
        return; /* normals stay 0: "no normal known" */
    for (size_t t = 0; t < m->ntris; t++) {
        const uint32_t *v = m->tri + 3 * t;
        if (!((c->singular[v[0]] | c->singular[v[1]] | c->singular[v[2]]) &
              CF_VERTEX_SINGULAR))
            continue;
        double n[3];
        ism_tri_cross3(m->pos + 3 * (size_t)v[0], m->pos + 3 * (size_t)v[1],
                       m->pos + 3 * (size_t)v[2], n);
        for (int k = 0; k < 3; k++)
            if (c->singular[v[k]] & CF_VERTEX_SINGULAR)
                for (int j = 0; j < 3; j++)
                    acc[3 * (size_t)v[k] + j] += n[j];
    }
    for (size_t v = 0; v < m->nverts; v++) {
        if (!(c->singular[v] & CF_VERTEX_SINGULAR))
            continue;
        double len = sqrt(ism_sqdist3(acc + 3 * v, (const double[3]){0, 0, 0}));
        for (int j = 0; j < 3; j++)
            m->normal[3 * v + j] = len > 0 ? (float)(acc[3 * v + j] / len) : 0.0f;
    }
    free(acc);
}

bool cf_compact(cf_ctx *c)
{
    ism_mesh *m = c->m;
    /* a vertex is kept when a live triangle or a segment uses it, or when no triangle
     * used it before the pass either (the polygoniser's own isolated vertices) */
    uint8_t *use = calloc(m->nverts ? m->nverts : 1, 1);
    uint32_t *map = malloc((m->nverts ? m->nverts : 1) * sizeof *map);
    if (!use || !map) {
        free(use);
        free(map);
        return false;
    }
    /* the corners written out, not looped: the loops' counters cost the Klein bottle at
     * E 0.00327 as much as their bodies (callgrind) */
    for (size_t t = 0; t < m->ntris; t++) {
        const uint32_t *v = m->tri + 3 * t;
        uint8_t mark = c->dead[t] ? 1 : 2;
        use[v[0]] |= mark;
        use[v[1]] |= mark;
        use[v[2]] |= mark;
    }
    for (size_t s = 0; s < 2 * m->nsegs; s++)
        use[m->seg[s]] |= 2;
    /* the copies move down by whole elements (nt <= t, nv <= v): a source is read before
     * any later destination overwrites it, and element by element costs no libc call; the
     * elements before the first removed stay where they are */
    size_t nt = 0;
    while (nt < m->ntris && !c->dead[nt])
        nt++;
    for (size_t t = nt; t < m->ntris; t++)
        if (!c->dead[t]) {
            uint32_t *to = m->tri + 3 * nt;
            const uint32_t *from = m->tri + 3 * t;
            to[0] = from[0];
            to[1] = from[1];
            to[2] = from[2];
            nt++;
        }
    m->ntris = nt;
    memset(c->dead, 0, nt);
    size_t nv = 0;
    for (size_t v = 0; v < m->nverts; v++) {
        if (use[v] == 1) {
            map[v] = CF_NONE;
            continue;
        }
        map[v] = (uint32_t)nv;
        if (nv < v) {
            double *p = m->pos + 3 * nv;
            float *n = m->normal + 3 * nv;
            const double *pf = m->pos + 3 * v;
            const float *nf = m->normal + 3 * v;
            p[0] = pf[0], p[1] = pf[1], p[2] = pf[2];
            n[0] = nf[0], n[1] = nf[1], n[2] = nf[2];
            c->singular[nv] = c->singular[v];
        }
        nv++;
    }
    c->st->vertices_removed += m->nverts - nv;
    m->nverts = nv;
    for (size_t i = 0; i < 3 * m->ntris; i++)
        m->tri[i] = map[m->tri[i]];
    for (size_t i = 0; i < 2 * m->nsegs; i++)
        m->seg[i] = map[m->seg[i]];
    free(use);
    free(map);
    singular_normals(c);
    return true;
}
