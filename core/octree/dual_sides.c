/* dual_sides.c — a round's misses mended without a split leaf (dual_sides.h): when every miss
 * is a side between two leaves' vertices a few E off, each side's two triangles are cut in
 * two at a vertex on the side's midpoint's foot, the halves measured, and the cut kept or
 * rolled back. Finding the missed sides, placing the side vertices (kept by pair key for a
 * retry), halving the triangles and the roll-back live here; measuring is dual_measure.c's. */
#include "core/octree/dual_sides.h"
#include "core/octree/dual_measure.h"
#include "core/util/vec3.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

/* A side is cut (ism_dual_split_sides) only while its midpoint lies within this many E of f = 0.
 * Its halves sag a quarter as far (a chord's sag grows with its length squared): under the
 * straddle move (ends 0.9 E outside) a side 3 E off sags 3.9 E, its halves 0.98 E, their
 * midpoints back within 0.1 E of f = 0; the halves are measured all the same, and the cut
 * kept only when every one meets E. A side farther off is an early round's, and its halves'
 * triangles could be worse than the round's finer leaves. Measured (bench_error mesh S E 10,
 * one thread, callgrind on ism_mesh_surface): the sphere at E 0.0141 (the bench's 1e-2
 * setting) missed on nothing but twelve sides between level-3 leaves at 1.023 E (the radial
 * foot of a centre 0.82 from the origin spreads the leaves' spacing 0.375 by 1 / 0.82), a
 * whole second round for twelve edges: cut, 456 -> 384 triangles, 4.83M -> 2.89M
 * instructions; the torus at 0.0141 missed on twelve sides at 1.55-1.59 E: 1,144 -> 1,008
 * triangles and no round (from 1.75 up). At 2 the sphere at 1.3e-3 (the bench's 1e-3
 * setting) still ran a round for 24 sides between level-4 leaves at 2.55 E beside 48 at
 * 1.19 E (one more level of 48 leaves, the walk and the measure again: 38.1M, 4,284
 * triangles); at 3 they are cut: 33.2M (-12.9%), 4,524 triangles, the same max centroid
 * distance 8.4e-4. Every preset at its default bound in the three placements: 121 of 126
 * meshes the same, ellipsoid 836 / 832 / 846 -> 756 / 752 / 754 and blob-pair own / 1e-3
 * 1,984 / 2,024 -> 1,776 / 1,786 triangles, within E as before. */
#define SIDE_SPLIT_MAX 3.0

/* Task k (job: in the pair keys, out the points, n how many): the midpoints of the pairs at
 * in[MEASURE_LANES k ..] as vertices (ism_dual_vertices_onto, each within its pair's
 * length), as dual_measure.c's fan_task makes fans' centres. */
static void side_task(void *ctx, size_t k, int thread)
{
    task_ctx *job = ctx;
    dual *d = job->d;
    worker *w = &d->w[thread];
    size_t lo, n = chunk_of(k, job->n, &lo);
    /* size zeroed: n >= 1 of it set, which gcc cannot see (maybe-uninitialized) */
    double m[MEASURE_LANES][3], size[MEASURE_LANES] = {0}, *out = (double *)job->out;
    for (size_t j = 0; j < n; j++) {
        uint64_t key = ((const uint64_t *)job->in)[lo + j];
        uint32_t a = (uint32_t)((key - 1) >> 32), b = (uint32_t)(key - 1);
        pair_mid(d, key, m[j]);
        size[j] = ism_dist3(&d->pos[3 * (size_t)a], &d->pos[3 * (size_t)b]);
    }
    ism_dual_vertices_onto(d, w, m, size, n, (double (*)[3])(out + 3 * lo));
}

/* The misses of a round (miss[t], ism_dual_measure_triangles') as missed sides into *out (sorted by
 * key, two triangles each), when every missed triangle missed on one edge alone, an edge
 * between two leaves' vertices (no fan's centre) within SIDE_SPLIT_MAX E whose other
 * triangle missed on it too; how many (0: not so, or out of memory). edge_misses marks the
 * two ends of each edge beyond E and a centroid's miss marks all three, so a mask of two
 * bits is one edge's miss: 3 edge 0, 6 edge 1, 5 edge 2. */
static size_t missed_sides(dual *d, const uint8_t *miss, ism_edge_ref **out)
{
    static const int8_t EDGE_OF[8] = {-1, -1, -1, 0, -1, 2, 1, -1};
    ism_edge_ref *s = NULL;
    size_t n = 0, cap = 0;
    double e = d->o->max_error;
    bool ok = true;
    *out = NULL;
    for (size_t t = 0; ok && t < d->nt; t++) {
        if (!miss[t])
            continue;
        int k = EDGE_OF[miss[t] & 7];
        uint32_t a = k < 0 ? 0 : d->tri[3 * t + k], b = k < 0 ? 0 : d->tri[3 * t + (k + 1) % 3];
        ok = k >= 0 && d->vleaf[a] >= 0 && d->vleaf[b] >= 0 &&
             ism_dual_mid_dist(d, a, b) <= SIDE_SPLIT_MAX * e &&
             grow((void **)&s, &cap, n + 1, sizeof *s);
        if (ok)
            s[n++] = (ism_edge_ref){ism_edge_key(a, b), (uint32_t)(3 * t + (size_t)k)};
    }
    ok = ok && n && n % 2 == 0;
    if (ok)
        qsort(s, n, sizeof *s, ism_edge_ref_order);
    for (size_t j = 0; ok && j < n; j += 2)
        ok = ism_edge_run_end(s, n, j) == j + 2;
    if (!ok) {
        free(s);
        return 0;
    }
    *out = s;
    return n;
}

/* The round's triangles into tri, each one cut[t] names (a side s[cut[t]], its vertex
 * vid[cut[t] / 2]) as the two halves of that side, each with the third corner, in place;
 * the halves' indices into list. Returns how many halves. */
static size_t halve_triangles(const dual *d, const ism_edge_ref *s, const uint32_t *cut,
                              const uint32_t *vid, uint32_t *tri, uint32_t *list)
{
    size_t m = 0, nl = 0;
    for (size_t t = 0; t < d->nt; t++) {
        const uint32_t *u = &d->tri[3 * t];
        if (cut[t] == UINT32_MAX) {
            memcpy(&tri[3 * m++], u, 3 * sizeof *u);
            continue;
        }
        int k = (int)(s[cut[t]].tri % 3);
        uint32_t c = vid[cut[t] / 2], a = u[k], b = u[(k + 1) % 3], o = u[(k + 2) % 3];
        uint32_t two[6] = {a, c, o, c, b, o};
        memcpy(&tri[3 * m], two, sizeof two);
        list[nl++] = (uint32_t)m;
        list[nl++] = (uint32_t)m + 1;
        m += 2;
    }
    return nl;
}

/* The vertex of each of the ns sides s[0], s[2], .. into vid: the one an earlier try made
 * for the side's pair key (d->sides; a pure function of the side's ends, like the
 * vertices), else one placed now on the pool (side_task) and kept. A try whose halves miss
 * leaves its vertices unused; its round then splits a leaf at one end of each side, or, both
 * ends at depth.max, the third corners' leaves, and the next round may try that same side
 * again: it reuses the vertex rather than adding another (d->nv only grows, and tri_key's
 * memo stops at 2^21 vertices).
 * False when a vertex cannot be placed (Newton) or out of memory. */
static bool side_vertices(dual *d, const ism_edge_ref *s, size_t ns, uint32_t *vid)
{
    uint64_t *keys = malloc(ns * sizeof *keys);
    uint32_t *which = malloc(ns * sizeof *which);
    double *at = malloc(3 * ns * sizeof *at);
    size_t nk = 0;
    bool ok = keys && which && at && keyed_reserve(&d->sides, ns) &&
              ism_dual_reserve_vertices(d, ns);
    for (size_t j = 0; ok && j < ns; j++) {
        uint64_t key = s[2 * j].key + 1; /* pair_key */
        const double *known = keyed_get(&d->sides, key);
        if (known) {
            vid[j] = (uint32_t)*known;
            continue;
        }
        which[nk] = (uint32_t)j;
        keys[nk++] = key;
    }
    if (ok && nk) {
        task_ctx job = {d, keys, at, nk};
        ism_pool_for(d->pool, chunks(nk), side_task, &job, NULL);
    }
    for (size_t k = 0; ok && k < nk; k++)
        ok = !isnan(at[3 * k]);
    for (size_t k = 0; ok && k < nk; k++) {
        memcpy(&d->pos[3 * d->nv], &at[3 * k], 3 * sizeof *at);
        d->vleaf[d->nv] = -1; /* like a fan's centre: no leaf of its own */
        d->vtwin[d->nv] = -1;
        keyed_put(&d->sides, keys[k], (double)d->nv); /* reserved: cannot fail */
        vid[which[k]] = (uint32_t)d->nv++;
    }
    free(keys);
    free(which);
    free(at);
    return ok;
}

/* Why and when: dual_sides.h. */
bool ism_dual_split_sides(dual *d, const uint8_t *miss)
{
    if (d->crease || d->inner || d->nballs)
        return false;
    ism_edge_ref *s;
    size_t n = missed_sides(d, miss, &s), ns = n / 2, nt = d->nt, nn = nt + n, cap = nn;
    if (n && nn > d->o->max_triangles) { /* the halves would pass the bound mesh_rounds
                                            checked on the round's triangles */
        free(s);
        return false;
    }
    if (!n)
        return false;
    uint32_t *vid = malloc(ns * sizeof *vid);
    /* list zeroed: GCC cannot see that halve_triangles fills what measure_triangles reads */
    uint32_t *tri = malloc(3 * nn * sizeof *tri), *list = calloc(2 * n, sizeof *list);
    uint32_t *cut = malloc(nt * sizeof *cut); /* triangle t's side (s's index), or none */
    uint8_t *nmiss = malloc(2 * n);
    bool ok = vid && tri && list && cut && nmiss && side_vertices(d, s, ns, vid);
    if (ok)
        memset(cut, 0xff, nt * sizeof *cut);
    for (size_t j = 0; ok && j < n; j++)
        cut[s[j].tri / 3] = (uint32_t)j;
    size_t nl = ok ? halve_triangles(d, s, cut, vid, tri, list) : 0;
    uint32_t *old = d->tri;
    size_t oldcap = d->capt;
    if (ok) {
        d->tri = tri;
        d->nt = nn;
        d->capt = cap;
        ism_dual_measure_triangles(d, list, nl, nmiss);
        for (size_t j = 0; j < nl; j++)
            ok &= !nmiss[j];
        ok &= !d->nomem;
        if (!ok) { /* as they were */
            d->tri = old;
            d->nt = nt;
            d->capt = oldcap;
        }
    }
    free(ok ? old : tri);
    free(s);
    free(vid);
    free(list);
    free(cut);
    free(nmiss);
    return ok;
}
