/* dual_measure.c — the dual mesher's round of triangles and their measure (dual_measure.h):
 * the round's quads cut into triangles (across the diagonal nearer f = 0, or four round a
 * centre), the distances of their centroids and edge midpoints to f = 0 measured in
 * batched lanes on the pool (memos by triangle and by vertex pair, kept across rounds), and
 * the leaves round every miss marked to split. */
#include "core/octree/dual_measure.h"
#include "core/octree/dual_box.h"
#include "core/octree/dual_crease.h"
#include "core/octree/sample_dist.h"
#include "core/octree/straddle.h"
#include "core/util/vec3.h"

#include <limits.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

/* Inline: emit_quads adds every triangle of a round, ~1,000 calls on the sphere at E 0.0141
 * (their calls ~9K instructions of 1.91M). */
static inline __attribute__((always_inline)) bool add_tri(dual *d, uint32_t a, uint32_t b,
                                                          uint32_t c)
{
    if (!grow((void **)&d->tri, &d->capt, d->nt + 1, 3 * sizeof *d->tri))
        return false;
    d->tri[3 * d->nt] = a;
    d->tri[3 * d->nt + 1] = b;
    d->tri[3 * d->nt + 2] = c;
    d->nt++;
    return true;
}

/* The distance to f = 0 (ism_dual_dist) of the midpoint of the pair key stands for. */
static double pair_dist(dual *d, worker *w, uint64_t key)
{
    double m[3];
    pair_mid(d, key, m);
    return ism_dual_dist(&w->s, m, d->o->max_error);
}

/* The midpoint distance of vertices a and b: from the memo, measured here (thread 0) only
 * when the memo could not keep it. A pair is measured once: a mesh edge is asked for by both
 * its triangles, a quad's diagonal when it is chosen, and vertices keep their positions from
 * round to round. */
double ism_dual_mid_dist(dual *d, uint32_t a, uint32_t b)
{
    uint64_t key = pair_key(a, b);
    const double *known = keyed_get(&d->mid, key);
    return known && !isnan(*known) ? *known : pair_dist(d, &d->w[0], key);
}

/* Task k (job: in the pair keys, out their distances, n how many): the midpoint distances
 * of keys[MEASURE_LANES k ..] (ism_dual_dist's, with the first gradients in one batch). */
static void pair_task(void *ctx, size_t k, int thread)
{
    task_ctx *job = ctx;
    dual *d = job->d;
    worker *w = &d->w[thread];
    const uint64_t *keys = job->in;
    double *dist = job->out;
    size_t lo, n = chunk_of(k, job->n, &lo);
    double m[MEASURE_LANES][3], f[MEASURE_LANES], g[MEASURE_LANES][3], e = d->o->max_error;
    double plain[MEASURE_LANES];
    for (size_t j = 0; j < n; j++)
        pair_mid(d, keys[lo + j], m[j]);
    ism_sample_grad_batch(&w->s, (const double (*)[3])m, f, g, n);
    ism_plain_dists(&w->s, (const double (*)[3])m, f, (const double (*)[3])g, e, plain, n);
    /* ism_dual_dist's, its first test once a task */
    ism_dual_kink_dists(&w->s, (const double (*)[3])m, plain, e, &dist[lo], n);
}

/* The midpoint distances of the n vertex pairs in pairs[0..2n) into the memo: those not
 * known yet, each once, measured on the pool; and every pair's into out[0..n) (out NULL:
 * none). False (nothing measured) when out of memory. */
_Static_assert(sizeof(size_t) == sizeof(uint64_t), "measure_pairs' block: 8-byte slots");

static bool measure_pairs(dual *d, const uint32_t *pairs, size_t n, double *out)
{
    size_t room = n ? n : 1; /* keys, slot, at and dist in one block (8 bytes each) */
    uint64_t *keys = malloc(4 * room * sizeof *keys);
    size_t *slot = (size_t *)(keys + room), *at = slot + room;
    double *dist = (double *)(at + room);
    if (!keys || !keyed_reserve(&d->mid, n)) {
        free(keys);
        return false; /* mid_dist measures them one by one */
    }
    size_t m = 0;
    keyed *k = &d->mid;
    for (size_t j = 0; j < n; j++) {
        uint64_t key = pair_key(pairs[2 * j], pairs[2 * j + 1]);
        size_t i = keyed_slot(k, key);
        at[j] = i; /* slots stay put till the end (reserved) */
        if (keyed_used(k, i))
            continue;
        keyed_claim(k, i, key); /* asked for: not again in this batch; no growth till the end */
        k->val[i] = NAN;
        k->n++;
        keys[m] = key;
        slot[m++] = i;
    }
    task_ctx job = {d, keys, dist, m};
    ism_pool_for(d->pool, chunks(m), pair_task, &job, NULL);
    for (size_t j = 0; j < m; j++)
        k->val[slot[j]] = dist[j];
    for (size_t j = 0; out && j < n; j++) /* mid_dist's answer, without its look-up */
        out[j] = k->val[at[j]];
    free(keys);
    return true;
}

/* Triangle t's corners (bit k: vertex k) whose leaves to split for its edges: the two ends
 * of each edge whose midpoint lies beyond E (splitting the third leaf would leave that edge
 * as it is). dist: the midpoints' distances (edge k from vertex k), or NULL: the memo's. */
static int edge_misses(dual *d, size_t t, const double *dist)
{
    int miss = 0;
    for (int k = 0; k < 3; k++) {
        double m = dist ? dist[k]
                        : ism_dual_mid_dist(d, d->tri[3 * t + k], d->tri[3 * t + (k + 1) % 3]);
        if (!(m <= d->o->max_error))
            miss |= 1 << k | 1 << (k + 1) % 3;
    }
    return miss;
}

/* Triangle t's corners into p. */
static void tri_corners(const dual *d, size_t t, const double *p[3])
{
    for (int k = 0; k < 3; k++)
        p[k] = &d->pos[3 * d->tri[3 * t + k]];
}

/* Task k (job: in the triangles, out their miss masks, n how many): for triangles tris[MEASURE_LANES k ..], 0 when the centroid is within E of f = 0
 * and the normal along ∇f there (ism_dual_centroid_within, the centroids' gradients in one
 * batch), else 7 (every leaf of the triangle to split). */
static void centroid_task(void *ctx, size_t k, int thread)
{
    task_ctx *job = ctx;
    dual *d = job->d;
    worker *w = &d->w[thread];
    const uint32_t *tris = job->in;
    uint8_t *miss = job->out;
    size_t lo, n = chunk_of(k, job->n, &lo);
    double c[MEASURE_LANES][3], f[MEASURE_LANES], g[MEASURE_LANES][3];
    const double *p[MEASURE_LANES][3]; /* the corners (d->pos), kept for the second pass */
    for (size_t j = 0; j < n; j++) {
        tri_corners(d, tris[lo + j], p[j]);
        ism_dual_centroid(p[j], c[j]);
    }
    double plain[MEASURE_LANES], e = d->o->max_error;
    ism_sample_grad_batch(&w->s, (const double (*)[3])c, f, g, n);
    ism_plain_dists(&w->s, (const double (*)[3])c, f, (const double (*)[3])g, e, plain, n);
    for (size_t j = 0; j < n; j++)
        miss[lo + j] = ism_dual_centroid_within_at(&w->s, p[j], c[j], f[j], g[j], plain[j], e)
                           ? 0
                           : 7;
}

/* Triangle t's vertices, sorted, in one word (+1: never 0); 0 when the vertices are too
 * many for 21 bits each (then nothing is remembered). A triangle keeps its vertices'
 * positions while they exist, so one that met E meets it again. */
static uint64_t tri_key(const dual *d, size_t t)
{
    uint64_t v[3] = {d->tri[3 * t], d->tri[3 * t + 1], d->tri[3 * t + 2]};
    if (d->nv >= (size_t)1 << 21)
        return 0;
    for (int i = 0; i < 2; i++)
        for (int j = 0; j < 2 - i; j++)
            if (v[j] > v[j + 1]) {
                uint64_t x = v[j];
                v[j] = v[j + 1];
                v[j + 1] = x;
            }
    return (v[0] | v[1] << 21 | v[2] << 42) + 1;
}

/* What the clip by the request's box (dual_box.h) does to triangle t: CLIP_DROPS it whole
 * (every corner beyond one plane by more than the snap: not measured here, the clip measures
 * every piece it makes), CLIP_TOUCHES it (a plane across it, or a corner within the snap of
 * one: the probe clips it, ism_dual_mark_cut_misses), or keeps it as it is (CLIP_KEEPS). */
enum { CLIP_KEEPS, CLIP_TOUCHES, CLIP_DROPS };

static int clip_of(const dual *d, size_t t)
{
    double snap = ISM_DUAL_BOX_SNAP * d->o->max_error;
    int touches = 0;
    for (int a = 0; a < 6; a++) {
        int beyond = 0, far = 0;
        for (int j = 0; j < 3; j++) {
            double x = d->pos[3 * (size_t)d->tri[3 * t + j] + a % 3], w = d->inner[a];
            beyond += a < 3 ? x < w : x > w;
            far += a < 3 ? x < w - snap : x > w + snap;
            touches |= fabs(x - w) < snap;
        }
        if (far == 3)
            return CLIP_DROPS;
        touches |= beyond && beyond < 3;
    }
    return touches ? CLIP_TOUCHES : CLIP_KEEPS;
}

/* The miss masks of triangles list[0..n) (list NULL: triangles 0..n) into miss[0..n)
 * (edge_misses, else centroid_task; 0: within E). Triangles that met E in an earlier round
 * (d->passed) read 0 unmeasured; the rest have their edges, then the centroids of those whose
 * edges pass, measured on the pool, and are remembered when they pass. */
/* Bytes a triangle of ism_dual_measure_triangles' one block takes, its arrays widest first
 * (each then starts aligned): at (size_t), tkey (the open triangles' tri_key) and pdist (3
 * doubles), open, pairs (6) and cen (uint32_t), emiss and cmiss (uint8_t). */
#define TRI_BLOCK_BYTES                                                                     \
    (sizeof(size_t) + sizeof(uint64_t) + 3 * sizeof(double) + 8 * sizeof(uint32_t) +       \
     2 * sizeof(uint8_t))

void ism_dual_measure_triangles(dual *d, const uint32_t *list, size_t n, uint8_t *miss)
{
    size_t np = 0, nc = 0, room = n ? n : 1;
    size_t *at = room <= SIZE_MAX / TRI_BLOCK_BYTES ? malloc(TRI_BLOCK_BYTES * room) : NULL;
    if (!at) {
        d->nomem = true;
        return;
    }
    uint64_t *tkey = (uint64_t *)(at + room);
    double *pdist = (double *)(tkey + room);
    uint32_t *open = (uint32_t *)(pdist + 3 * room), *pairs = open + room, *cen = pairs + 6 * room;
    uint8_t *emiss = (uint8_t *)(cen + room), *cmiss = emiss + room;
    pairs[0] = 0; /* GCC cannot see that measure_pairs reads only what the loop writes */
    for (size_t k = 0; k < n; k++) {
        uint32_t t = list ? list[k] : (uint32_t)k;
        uint64_t key = tri_key(d, t);
        miss[k] = 0;
        if ((key && keyed_get(&d->passed, key)) || (d->inner && clip_of(d, t) == CLIP_DROPS))
            continue;
        at[np] = k;
        tkey[np] = key;
        const uint32_t *v = &d->tri[3 * (size_t)t];
        uint32_t *e = &pairs[6 * np]; /* edges 0-1, 1-2, 2-0 */
        e[0] = v[0], e[1] = v[1], e[2] = v[1], e[3] = v[2], e[4] = v[2], e[5] = v[0];
        open[np++] = t;
    }
    bool known = measure_pairs(d, pairs, 3 * np, pdist);
    for (size_t k = 0; k < np; k++) {
        emiss[k] = (uint8_t)edge_misses(d, open[k], known ? &pdist[3 * k] : NULL);
        if (!emiss[k])
            cen[nc++] = open[k];
    }
    task_ctx job = {d, cen, cmiss, nc};
    ism_pool_for(d->pool, chunks(nc), centroid_task, &job, NULL);
    size_t pass = 0;
    for (size_t k = 0, c = 0; k < np; k++)
        pass += !emiss[k] && !cmiss[c++] && tkey[k];
    if (pass) /* one growth, not one a doubling (out of memory: keyed_put grows, or keeps
                 nothing) */
        keyed_reserve(&d->passed, pass);
    for (size_t k = 0, c = 0; k < np; k++) {
        int m = emiss[k] ? emiss[k] : cmiss[c++];
        miss[at[k]] = (uint8_t)m;
        if (!m && tkey[k])
            keyed_put(&d->passed, tkey[k], 0); /* out of memory: measured again, no more */
    }
    free(at);
}

/* Marks leaf (a leaf not yet split, above depth.max) to split; true when it can. */
static bool mark_leaf(dual *d, int32_t leaf, size_t *marked)
{
    dnode *n = leaf < 0 ? NULL : &d->n[leaf];
    if (!n || n->child >= 0 || n->level >= d->o->max_depth)
        return false;
    *marked += !n->split;
    n->split = 1;
    return true;
}

/* A fan's triangle t (ism_dual_emit_quads: the fan's centre c is corner 2 of each of its
 * four, which follow one another) whose own leaves are at depth.max: the leaves of the fan's
 * other corners are marked instead (the quad's far side). A quad between leaves two levels
 * apart is a sliver whose centre may fall beyond its near side: the spindle torus at E 1e-2
 * in the irrational box had a fan triangle turned over between two depth-9 leaves and two
 * depth-7 ones (where the quad's other diagonal met E) and declined (error_at_max_depth).
 * True when one can split. */
static bool mark_fan_leaves(dual *d, size_t t, size_t *marked)
{
    uint32_t c = d->tri[3 * t + 2];
    if (d->vleaf[c] >= 0)
        return false;
    bool any = false;
    size_t lo = t >= 3 ? t - 3 : 0, hi = t + 3 < d->nt ? t + 3 : d->nt - 1;
    for (size_t u = lo; u <= hi; u++)
        if (d->tri[3 * u + 2] == c)
            for (int j = 0; j < 2; j++)
                for (int32_t v = (int32_t)d->tri[3 * u + j]; v >= 0; v = d->vtwin[v])
                    any |= mark_leaf(d, d->vleaf[v], marked);
    return any;
}

/* The level of the coarsest leaf that can still split among those on triangle t's corners
 * in mask m (welded twins included); INT_MAX when none can. A missed triangle between leaves
 * of different levels splits only its coarsest: the finer ones wait for the next round's
 * measure, where the triangle's larger side is usually what missed. Splitting every leaf of
 * it drove the finer side a level deeper than E needs (torus r 0.3 at E 0.0119, 1e-3:
 * 1,856 / 17,312 triangles; minimum depth 4 instead of 3 gave 1,344 / 15,744). */
static int coarsest_open(const dual *d, size_t t, int m)
{
    int top = INT_MAX;
    for (int j = 0; j < 3; j++)
        for (int32_t v = (int32_t)d->tri[3 * t + j]; (m >> j & 1) && v >= 0; v = d->vtwin[v]) {
            const dnode *n = d->vleaf[v] < 0 ? NULL : &d->n[d->vleaf[v]];
            if (n && n->child < 0 && n->level < d->o->max_depth && n->level < top)
                top = n->level;
        }
    return top;
}

size_t ism_dual_mark_misses(dual *d, const uint8_t *miss, uint64_t *missed)
{
    size_t marked = 0;
    *missed = 0;
    for (size_t t = 0; t < d->nt && !d->nomem; t++) {
        int m = miss[t];
        if (!m)
            continue;
        bool any = false;
        for (int pass = 0; pass < 2 && !any; pass++, m = 7) { /* then every leaf of t */
            int top = coarsest_open(d, t, m);
            for (int j = 0; j < 3; j++)
                for (int32_t v = (int32_t)d->tri[3 * t + j]; v >= 0; v = d->vtwin[v])
                    /* every leaf on a welded vertex, the coarsest first */
                    any |= (m >> j & 1) && d->vleaf[v] >= 0 &&
                           d->n[d->vleaf[v]].level <= top &&
                           mark_leaf(d, d->vleaf[v], &marked);
        }
        if (!any) /* a fan's triangle: the quad's other leaves */
            any = mark_fan_leaves(d, t, &marked);
        *missed += !any;
    }
    return marked;
}

size_t ism_dual_mark_cut_misses(dual *d, uint64_t *missed)
{
    ism_mesh m;
    ism_mesh_init(&m);
    uint32_t *map = malloc((d->nv + 1) * sizeof *map), *from = malloc((d->nt + 1) * sizeof *from);
    uint8_t *miss = malloc(d->nt + 1);
    size_t marked = 0, n = 0;
    bool ok = map && from && miss;
    if (ok)
        memset(map, 0xff, (d->nv + 1) * sizeof *map);
    for (size_t t = 0; t < d->nt && ok; t++) {
        if (clip_of(d, t) != CLIP_TOUCHES)
            continue;
        uint32_t v[3];
        for (int j = 0; j < 3 && ok; j++) {
            uint32_t u = d->tri[3 * t + j];
            if (map[u] == UINT32_MAX)
                map[u] = ism_mesh_add_vertex(&m, &d->pos[3 * (size_t)u], NULL);
            v[j] = map[u];
            ok = v[j] != UINT32_MAX;
        }
        ok = ok && ism_mesh_add_triangle(&m, v[0], v[1], v[2]);
        from[n++] = (uint32_t)t;
    }
    ism_box_clip_stats cs;
    enum ism_box_clip_status c = ok ? ism_dual_box_clip(&m, &d->w[0].s, d->inner,
                                                        d->o->max_error, miss, &cs)
                                    : ISM_BOX_CLIP_NO_MEMORY;
    if (c == ISM_BOX_CLIP_NO_MEMORY)
        d->nomem = true;
    else if (c == ISM_BOX_CLIP_BAD)
        decline(d, ISM_DUAL_WHY_BOX_CUT);
    for (size_t k = 0; k < n && c == ISM_BOX_CLIP_MISS; k++) {
        if (!miss[k])
            continue;
        bool any = false;
        for (int j = 0; j < 3; j++) {
            int32_t leaf = d->vleaf[d->tri[3 * from[k] + j]];
            dnode *nd = leaf < 0 ? NULL : &d->n[leaf];
            /* a welded crease vertex's first leaf may have split (weld_crease) */
            if (nd && nd->child < 0 && nd->level < d->o->max_depth) {
                marked += !nd->split;
                nd->split = 1;
                any = true;
            }
        }
        *missed += !any;
    }
    ism_mesh_free(&m);
    free(map);
    free(from);
    free(miss);
    return marked;
}

size_t ism_dual_mark_not_manifold(dual *d)
{
    uint32_t *ends = malloc((d->nt ? 6 * d->nt : 1) * sizeof *ends);
    size_t n = ends ? ism_dual_not_manifold(d->tri, d->nt, d->nv, ends) : (size_t)-1;
    size_t marked = 0;
    if (n == (size_t)-1) {
        d->nomem = true;
        n = 0;
    }
    for (size_t k = 0; k < n; k++)
        for (int32_t v = (int32_t)ends[k]; v >= 0; v = d->vtwin[v]) {
            int32_t leaf = d->vleaf[v];
            dnode *nd = leaf < 0 ? NULL : &d->n[leaf];
            if (!nd || nd->child >= 0)
                continue;
            if (nd->level >= d->o->max_depth)
                decline(d, ISM_DUAL_WHY_MIN_MAX);
            marked += !nd->split;
            nd->split = 1;
        }
    free(ends);
    return marked;
}

/* Quad u's vertices in one key (+1: never 0) when every index fits 16 bits, else 0 (then
 * nothing is remembered). */
static uint64_t quad_key(const dual *d, const uint32_t *u)
{
    if (d->nv >= 0xffff)
        return 0;
    return ((uint64_t)u[0] << 48 | (uint64_t)u[1] << 32 | (uint64_t)u[2] << 16 | u[3]) + 1;
}

void ism_dual_vertices_onto(const dual *d, worker *w, double (*m)[3], const double *size,
                            size_t n, double (*out)[3])
{
    bool ok[MEASURE_LANES];
    ism_dual_newton_lanes(w, m, size, n, ok);
    if (d->shift > 0) { /* ism_straddle_balanced_point's move, from jets taken at once */
        double p[MEASURE_LANES][3], f[MEASURE_LANES], g[MEASURE_LANES][3], h[MEASURE_LANES][6];
        size_t at[MEASURE_LANES], na = 0;
        for (size_t j = 0; j < n; j++)
            if (ok[j]) {
                memcpy(p[na], m[j], sizeof p[na]);
                at[na++] = j;
            }
        if (na)
            ism_eval_hessian_batch(w->s.tape, w->s.ws, (const double (*)[3])p, f, g, h, na);
        for (size_t i = 0; i < na; i++) {
            ism_straddle_jet jet = {f[i], {g[i][0], g[i][1], g[i][2]},
                                    {h[i][0], h[i][1], h[i][2], h[i][3], h[i][4], h[i][5]}};
            double q[3];
            if (ism_straddle_balanced_point_at(&w->s, d->shift, d->o->box, m[at[i]], &jet, q,
                                               NULL))
                memcpy(m[at[i]], q, sizeof q);
        }
    }
    for (size_t j = 0; j < n; j++)
        for (int a = 0; a < 3; a++)
            out[j][a] = ok[j] ? m[j][a] : NAN;
}

/* Task k (job: in the quads, out the centres, n how many): the centres of the quads at
 * in[MEASURE_LANES k ..] into out (3 each): the mean of each quad's corners as a vertex,
 * within its longer diagonal, NaN when Newton cannot finish (ism_dual_vertices_onto: one
 * fan at a time cost the sphere at E 0.0141 ~2.5K instructions a fan, 54 fans). A pure
 * function of the corners, like the vertices. */
static void fan_task(void *ctx, size_t k, int thread)
{
    task_ctx *job = ctx;
    dual *d = job->d;
    worker *w = &d->w[thread];
    size_t lo, n = chunk_of(k, job->n, &lo);
    /* size zeroed: n >= 1 of it set, which gcc cannot see (maybe-uninitialized) */
    double m[MEASURE_LANES][3], size[MEASURE_LANES] = {0}, *out = (double *)job->out;
    for (size_t j = 0; j < n; j++) {
        const uint32_t *u = &d->q.q[4 * ((const uint32_t *)job->in)[lo + j]];
        m[j][0] = m[j][1] = m[j][2] = 0;
        size[j] = 0;
        for (int c = 0; c < 4; c++)
            for (int a = 0; a < 3; a++)
                m[j][a] += 0.25 * d->pos[3 * u[c] + a];
        for (int c = 0; c < 2; c++) {
            double l = 0;
            for (int a = 0; a < 3; a++) {
                double t = d->pos[3 * u[c + 2] + a] - d->pos[3 * u[c] + a];
                l += t * t;
            }
            size[j] = fmax(size[j], sqrt(l));
        }
    }
    ism_dual_vertices_onto(d, w, m, size, n, (double (*)[3])(out + 3 * lo));
}

/* Would four triangles round a centre do better than the two in tri[0..6) (a quad cut across
 * its diagonal tri[0]-tri[2], measured, one of them missing E)? Only when the diagonal's
 * midpoint or a centroid misses: where only the quad's sides do, the fan's triangles hold
 * those sides and split the same leaves (measured: torus 3e-3 the same 4,544 triangles for
 * 100.1M instructions with every missing quad fanned). */
static bool fan_helps(dual *d, const uint32_t *tri)
{
    double e = d->o->max_error;
    if (!(ism_dual_mid_dist(d, tri[0], tri[2]) <= e))
        return true;
    for (int t = 0; t < 2; t++) {
        const uint32_t *v = &tri[3 * t];
        bool sides = ism_dual_mid_dist(d, v[0], v[1]) <= e &&
                     ism_dual_mid_dist(d, v[1], v[2]) <= e &&
                     ism_dual_mid_dist(d, v[2], v[0]) <= e;
        if (sides)
            return true; /* its miss is the centroid's (or it faces against ∇f) */
    }
    return false;
}

/* Quads cut across the nearer diagonal or fanned: why, and the measured counts, in
 * dual_measure.h. */
void ism_dual_emit_quads(dual *d)
{
    size_t nq = d->q.n;
    d->ntmiss = 0; /* tmiss speaks of no triangles until this round's are made */
    uint32_t *diag = malloc((nq ? nq : 1) * 4 * sizeof *diag);
    uint32_t *first = malloc((nq ? nq : 1) * sizeof *first), *list = NULL, *fq = NULL;
    uint8_t *fan = calloc(nq ? nq : 1, 1), *miss = NULL;
    double *centre = NULL, *ddist = malloc((nq ? nq : 1) * 2 * sizeof *ddist);
    size_t nd = 0, nl = 0, nf = 0;
    bool ok = diag && first && fan;
    for (size_t q = 0; ok && q < nq; q++) {
        const uint32_t *u = &d->q.q[4 * q];
        if (u[3] == UINT32_MAX)
            continue;
        uint32_t pairs[4] = {u[0], u[2], u[1], u[3]};
        memcpy(&diag[4 * nd++], pairs, sizeof pairs);
    }
    /* the diagonals' distances as measured (NULL: mid_dist looks them up); the pair memo's
       room for them and for their triangles' 6 pairs a quad at once (one growth, not two:
       measure_pairs reserves for each call's pairs in turn) */
    if (!ok || !ddist || !keyed_reserve(&d->mid, 8 * nd) ||
        !measure_pairs(d, diag, 2 * nd, ddist)) {
        free(ddist);
        ddist = NULL;
    }
    d->nt = 0;
    /* two triangles a quad at most before the fans: room at once (add_tri growing one at a
       time copied the array through its doublings; out of memory here, add_tri grows) */
    grow((void **)&d->tri, &d->capt, 2 * nq, 3 * sizeof *d->tri);
    for (size_t q = 0, k = 0; q < nq && ok; q++) {
        const uint32_t *u = &d->q.q[4 * q];
        first[q] = (uint32_t)d->nt;
        if (u[3] == UINT32_MAX) {
            ok = add_tri(d, u[0], u[1], u[2]);
            continue;
        }
        uint64_t key = quad_key(d, u);
        const double *known = key ? keyed_get(&d->fans, key) : NULL;
        double d02 = ddist ? ddist[2 * k] : ism_dual_mid_dist(d, u[0], u[2]);
        double d13 = ddist ? ddist[2 * k + 1] : ism_dual_mid_dist(d, u[1], u[3]);
        k++;
        int a = d02 <= d13 ? 0 : 1;
        ok = add_tri(d, u[a], u[a + 1], u[a + 2]) && add_tri(d, u[a], u[a + 2], u[(a + 3) % 4]);
        if (known) { /* cut as a fan in an earlier round: its centre kept */
            fan[q] = 2;
            first[q] = (uint32_t)*known; /* the centre's index (its triangles not measured) */
        }
    }
    /* the diagonals' triangles measured (those of quads known as fans aside) */
    list = ok ? malloc((d->nt ? d->nt : 1) * sizeof *list) : NULL;
    miss = ok ? malloc(d->nt ? d->nt : 1) : NULL;
    ok = ok && list && miss;
    for (size_t q = 0; ok && q < nq; q++)
        if (d->q.q[4 * q + 3] != UINT32_MAX && !fan[q]) {
            list[nl++] = first[q];
            list[nl++] = first[q] + 1;
        }
    if (ok && nl) /* nl: list's entries written (none: nothing to measure) */
        ism_dual_measure_triangles(d, list, nl, miss);
    /* what was measured, for mark_round, by triangle; the fans below add 2 a quad at most */
    uint8_t *tm = ok ? calloc(d->nt + 2 * nq + 1, 1) : NULL;
    for (size_t k = 0; tm && k < nl; k++)
        tm[list[k]] = (uint8_t)(TMISS_KNOWN | miss[k]);
    for (size_t q = 0, k = 0; ok && q < nq; q++)
        if (d->q.q[4 * q + 3] != UINT32_MAX && !fan[q]) {
            fan[q] = (miss[k] || miss[k + 1]) && fan_helps(d, &d->tri[3 * first[q]]);
            k += 2;
        }
    /* the new fans' centres, on the pool; numbered in quad order */
    fq = ok ? malloc((nq ? nq : 1) * sizeof *fq) : NULL;
    ok = ok && fq;
    for (size_t q = 0; ok && q < nq; q++)
        if (fan[q] == 1)
            fq[nf++] = (uint32_t)q;
    centre = ok ? malloc((nf ? nf : 1) * 3 * sizeof *centre) : NULL;
    ok = ok && centre && ism_dual_reserve_vertices(d, nf);
    if (ok) {
        task_ctx job = {d, fq, centre, nf};
        ism_pool_for(d->pool, chunks(nf), fan_task, &job, NULL);
        ok = keyed_reserve(&d->fans, nf);
    }
    for (size_t k = 0; ok && k < nf; k++) {
        uint32_t q = fq[k];
        if (isnan(centre[3 * k])) {
            fan[q] = 0; /* no centre: the diagonal's triangles (split as they miss) */
            continue;
        }
        memcpy(&d->pos[3 * d->nv], &centre[3 * k], 3 * sizeof *centre);
        d->vleaf[d->nv] = -1; /* a fan's centre: no leaf of its own */
        d->vtwin[d->nv] = -1;
        uint64_t key = quad_key(d, &d->q.q[4 * q]);
        if (key)
            keyed_put(&d->fans, key, (double)d->nv);
        first[q] = (uint32_t)d->nv++; /* now the centre's index */
    }
    /* the triangles again, each fan's four in place of its quad's two */
    if (ok && (nf || d->fans.n)) {
        size_t nt = d->nt;
        uint32_t *kept = malloc((nt ? nt : 1) * 3 * sizeof *kept);
        uint8_t *kept_tm = tm ? malloc(nt ? nt : 1) : NULL;
        ok = kept != NULL;
        if (ok)
            memcpy(kept, d->tri, nt * 3 * sizeof *kept);
        if (kept_tm)
            memcpy(kept_tm, tm, nt);
        else {
            free(tm);
            tm = NULL;
        }
        d->nt = 0;
        for (size_t q = 0, t = 0; ok && q < nq; q++) {
            const uint32_t *u = &d->q.q[4 * q];
            size_t own = u[3] == UINT32_MAX ? 1 : 2;
            if (fan[q]) {
                for (int j = 0; ok && j < 4; j++) {
                    if (tm)
                        tm[d->nt] = 0; /* a fan's triangle: not measured yet */
                    ok = add_tri(d, u[j], u[(j + 1) % 4], first[q]);
                }
            } else
                for (size_t j = 0; ok && j < own; j++) {
                    if (tm)
                        tm[d->nt] = kept_tm[t + j];
                    ok = add_tri(d, kept[3 * (t + j)], kept[3 * (t + j) + 1],
                                 kept[3 * (t + j) + 2]);
                }
            t += own;
        }
        free(kept);
        free(kept_tm);
    }
    if (!ok)
        d->nomem = true;
    if (ok && tm) { /* mark_round's: this round's triangles as they now stand */
        free(d->tmiss);
        d->tmiss = tm;
        d->ntmiss = d->nt;
        tm = NULL;
    }
    free(tm);
    free(diag);
    free(ddist);
    free(first);
    free(list);
    free(fq);
    free(fan);
    free(miss);
    free(centre);
}
