/* crease_micro.c — micro clusters beside the crease welded (crease_micro.h). The vertices'
 * stars as a CSR, micro edges joined in a union-find (its root is a set's lowest vertex),
 * then each set contracted on a copy of its triangles and kept only where the result is a
 * closed fan of distinct triangles each facing as it did. */
#include "core/curves/crease_micro.h"
#include "core/analysis/unionfind.h"
#include <stdlib.h>
#include <string.h>
#include "core/util/vec3.h"

#define NONE CUT_NONE
/* An edge this much shorter than its ends' longest edge is no feature of the surface: three
 * edge roots within a hair of a lattice corner (the gyroid ball's were 3.5e-5 apart in
 * cells of 0.023: 0.0015 of the edges round them). */
#define CREASE_MICRO_FRACTION 0.01
/* Triangles of a set's star handled at most (three vertices of 3–12 each); a larger set is
 * left as it is. */
#define CREASE_MICRO_STAR_MAX 48
/* A triangle of the welded star keeps this cosine with its own normal before (60°: not
 * turned over). */
#define CREASE_MICRO_TURN_COS 0.5

typedef struct micro_state {
    cut_state *s;
    const uint32_t *label;
    uint32_t *first, *star;  /* CSR: the triangles of vertex v are star[first[v] .. first[v+1]) */
    uint32_t *uf;            /* per vertex: union-find over micro edges */
    uint8_t *dead;           /* per triangle: dropped */
    uint32_t *stamp;         /* per triangle: the set that last gathered it + 1 */
} micro_state;

/* The CSR of the triangles round each vertex. False when out of memory. */
static bool build_stars(micro_state *ms)
{
    const ism_mesh *m = ms->s->m;
    size_t nv = m->nverts, nt = m->ntris;
    ms->first = calloc(nv + 2, sizeof *ms->first);
    ms->star = malloc((3 * nt + 1) * sizeof *ms->star);
    if (!ms->first || !ms->star)
        return false;
    for (size_t i = 0; i < 3 * nt; i++)
        ms->first[m->tri[i] + 2]++;
    for (size_t v = 0; v < nv; v++)
        ms->first[v + 2] += ms->first[v + 1];
    for (size_t i = 0; i < 3 * nt; i++)
        ms->star[ms->first[m->tri[i] + 1]++] = (uint32_t)(i / 3);
    return true;
}

/* Whether a neighbour of v takes another branch than v (v is beside the crease). */
static bool beside_crease(const micro_state *ms, uint32_t v)
{
    const uint32_t *tri = ms->s->m->tri;
    for (uint32_t i = ms->first[v]; i < ms->first[v + 1]; i++)
        for (int c = 0; c < 3; c++)
            if (ms->label[tri[3 * (size_t)ms->star[i] + c]] != ms->label[v])
                return true;
    return false;
}

/* Joins the ends of every micro edge beside the crease (both ends on one branch, on no curve
 * and no segment). */
static bool join_micro_edges(micro_state *ms)
{
    const ism_mesh *m = ms->s->m;
    size_t nv = m->nverts;
    double *longest = malloc((nv + 1) * sizeof *longest);
    uint8_t *free_v = malloc(nv + 1), *beside = malloc(nv + 1);
    bool ok = longest && free_v && beside;
    if (ok) {
        cut_longest_edges(m, longest);
        for (size_t v = 0; v < nv; v++) {
            ms->uf[v] = (uint32_t)v;
            free_v[v] = cut_vcurve_of(ms->s, (uint32_t)v) == NONE;
            beside[v] = beside_crease(ms, (uint32_t)v);
        }
        for (size_t i = 0; i < 2 * m->nsegs; i++)
            free_v[m->seg[i]] = 0;
    }
    for (size_t t = 0; ok && t < m->ntris; t++)
        for (int c = 0; c < 3; c++) {
            uint32_t a = m->tri[3 * t + c], b = m->tri[3 * t + (c + 1) % 3];
            double reach = CREASE_MICRO_FRACTION * (longest[a] > longest[b] ? longest[a]
                                                                            : longest[b]);
            if (free_v[a] && free_v[b] && (beside[a] || beside[b]) &&
                ms->label[a] == ms->label[b] &&
                ism_sqdist3(m->pos + 3 * (size_t)a, m->pos + 3 * (size_t)b) <= reach * reach)
                (void)ism_an_uf_union(ms->uf, a, b);
        }
    free(longest);
    free(free_v);
    free(beside);
    return ok;
}

/* Whether the triangles t (n of them, each with corner r) form a closed fan round r of
 * distinct triangles, each facing within CREASE_MICRO_TURN_COS of its normal before the weld
 * (was[i]: the set's star beside the crease holds both branches' triangles, whose normals
 * part by the crease's angle: their sum was no measure of a turn — the gyroid ball d7 in
 * the irrational box kept a cluster 1e-4 across that way, 75° from the sum, and the crease
 * cut through it left a 0.08° sliver, its edge 6.1° off the gradients' angle). */
static bool good_fan(const ism_mesh *m, uint32_t r, const uint32_t (*t)[3], size_t n,
                     const double (*was)[3])
{
    for (size_t i = 0; i < n; i++) {
        double q[3];
        cut_tri_normal(m, t[i], NONE, NULL, q); /* unnormalised */
        if (!(ism_dot3(q, was[i]) >= CREASE_MICRO_TURN_COS * ism_norm3(q) * ism_norm3(was[i])))
            return false;
        for (int c = 0; c < 3; c++) {
            uint32_t w = t[i][c];
            int seen = 0;
            for (size_t j = 0; w != r && j < n; j++)
                seen += t[j][0] == w || t[j][1] == w || t[j][2] == w;
            if (w != r && seen != 2)
                return false;
        }
        for (size_t j = 0; j < i; j++) {
            int same = 0;
            for (int c = 0; c < 3; c++)
                same += t[j][0] == t[i][c] || t[j][1] == t[i][c] || t[j][2] == t[i][c];
            if (same == 3)
                return false;
        }
    }
    return true;
}

/* Contracts the set whose root is r (its members: uf leads to r) when the result is good;
 * true when it was. */
static bool weld_set(micro_state *ms, uint32_t r, const uint32_t *members, size_t nm)
{
    ism_mesh *m = ms->s->m;
    uint32_t idx[CREASE_MICRO_STAR_MAX], t[CREASE_MICRO_STAR_MAX][3];
    size_t n = 0, live = 0;
    double was[CREASE_MICRO_STAR_MAX][3];
    for (size_t i = 0; i < nm; i++)
        for (uint32_t k = ms->first[members[i]]; k < ms->first[members[i] + 1]; k++) {
            uint32_t tr = ms->star[k];
            if (ms->dead[tr] || ms->stamp[tr] == r + 1)
                continue;
            if (n == CREASE_MICRO_STAR_MAX)
                return false;
            ms->stamp[tr] = r + 1;
            idx[n++] = tr;
        }
    uint32_t (*out)[3] = t;
    for (size_t i = 0; i < n; i++) {
        const uint32_t *tv = m->tri + 3 * (size_t)idx[i];
        uint32_t v[3];
        for (int c = 0; c < 3; c++)
            v[c] = ism_an_uf_find(ms->uf, tv[c]) == r ? r : tv[c];
        if (v[0] != v[1] && v[1] != v[2] && v[2] != v[0]) {
            cut_tri_normal(m, tv, NONE, NULL, was[live]);
            memcpy(out[live++], v, sizeof v);
        }
    }
    if (!live || !good_fan(m, r, (const uint32_t (*)[3])out, live, (const double (*)[3])was))
        return false;
    for (size_t i = 0; i < n; i++) { /* the same renaming, now in the mesh */
        uint32_t *tv = m->tri + 3 * (size_t)idx[i];
        for (int c = 0; c < 3; c++)
            tv[c] = ism_an_uf_find(ms->uf, tv[c]) == r ? r : tv[c];
        ms->dead[idx[i]] = tv[0] == tv[1] || tv[1] == tv[2] || tv[2] == tv[0];
    }
    return true;
}

/* Drops the dead triangles from the mesh and the parents. */
static void drop_dead(micro_state *ms)
{
    cut_state *s = ms->s;
    ism_mesh *m = s->m;
    size_t k = 0;
    for (size_t t = 0; t < m->ntris; t++) {
        if (ms->dead[t])
            continue;
        memmove(m->tri + 3 * k, m->tri + 3 * t, 3 * sizeof *m->tri);
        s->parent[k++] = s->parent[t];
    }
    m->ntris = k;
}

bool cut_crease_weld_micro(cut_state *s, const uint32_t *label, size_t *welded)
{
    ism_mesh *m = s->m;
    size_t nv = m->nverts, nt = m->ntris;
    micro_state ms = {.s = s, .label = label};
    ms.uf = malloc((nv + 1) * sizeof *ms.uf);
    ms.dead = calloc(nt + 1, 1);
    ms.stamp = calloc(nt + 1, sizeof *ms.stamp);
    uint32_t *members = malloc((nv + 1) * sizeof *members), *start = calloc(nv + 2, sizeof *start);
    *welded = 0;
    bool ok = ms.uf && ms.dead && ms.stamp && members && start && build_stars(&ms) &&
              join_micro_edges(&ms);
    for (size_t v = 0; ok && v < nv; v++) { /* the sets' members grouped by root (CSR) */
        ms.uf[v] = ism_an_uf_find(ms.uf, (uint32_t)v); /* (a root is its set's lowest) */
        start[ms.uf[v] + 2]++;
    }
    for (size_t v = 0; ok && v < nv; v++)
        start[v + 2] += start[v + 1];
    for (size_t v = 0; ok && v < nv; v++)
        members[start[ms.uf[v] + 1]++] = (uint32_t)v;
    for (size_t r = 0; ok && r < nv; r++) {
        size_t nm = start[r + 1] - start[r];
        if (nm > 1 && weld_set(&ms, (uint32_t)r, members + start[r], nm))
            *welded += nm - 1;
    }
    if (ok && *welded) /* some set welded: its dead triangles go */
        drop_dead(&ms);
    free(ms.first);
    free(ms.star);
    free(ms.uf);
    free(ms.dead);
    free(ms.stamp);
    free(members);
    free(start);
    return ok;
}
