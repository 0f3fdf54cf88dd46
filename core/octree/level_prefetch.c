/* level_prefetch.c — node corners and edge roots of many nodes of one octree level computed
 * in wide batches into the build's memos (see level_prefetch.h). */
#include "core/octree/level_prefetch.h"
#include "core/octree/corners.h"
#include "core/octree/edge_roots.h"
#include "core/octree/root_table.h"

#include <math.h>
#include <string.h>

/* Nodes whose corners are prefetched together: up to 256 points, siblings share most, and
 * the memo holds most from the level above (Klein bottle at E 3.27e-3: ~40 evaluated a
 * batch), in one gradient batch; the batched gradient costs about the same per point from 16
 * points on (evb26). Their new roots are gathered across such groups (PREFETCH_EDGES). */
#define PREFETCH_NODES 32
#define PREFETCH_POINTS (8 * PREFETCH_NODES)
/* Edges searched in one set of lanes (ism_regula_falsi_lanes keeps up to 64 running, a
 * finished search's lane taken by the next): four sets of lanes, so that most steps run with
 * every lane full and only the last searches' tail runs part-empty. Not measured against
 * other sizes (292a171 measured the lanes at this size: ~31 points a step on the Klein
 * bottle at E 3.27e-3); the batch is ~23 KB of stack. */
#define PREFETCH_EDGES 256

/* Node nd's corners as node_corners finds them (corner c at org + (c >> a & 1) steps): their
 * world positions and lattice keys (ism_lattice_key) into k, their memo slots into slot. */
static void corners_of(ism_point_entry *table, int bits, const ism_grid *g,
                       const ism_node *nd, ism_corners *k, ism_point_entry *slot[8])
{
    int32_t s = ism_grid_cell_steps(g, nd->level);
    double w[2][3];
    for (int a = 0; a < 3; a++) {
        w[0][a] = ism_grid_coord(g, a, nd->org[a]);
        w[1][a] = ism_grid_coord(g, a, nd->org[a] + s);
    }
    uint64_t mask = ((uint64_t)1 << bits) - 1;
    for (int c = 0; c < 8; c++) {
        int32_t ip[3];
        for (int a = 0; a < 3; a++) {
            int on = (c >> a) & 1;
            ip[a] = nd->org[a] + on * s;
            k->p[c][a] = w[on][a];
        }
        k->key[c] = ism_lattice_key(ip);
        slot[c] = &table[ism_cache_mix(k->key[c]) & mask];
    }
}

/* The points of corners k[0..n) (slots slot[i]) the memo lacks, evaluated together and stored
 * where their slot still holds them. */
static void fill_corners(const ism_corners *k, ism_point_entry *const (*slot)[8], size_t n,
                         ism_sampler *s)
{
    ism_point_entry *at[PREFETCH_POINTS];
    uint64_t key[PREFETCH_POINTS];
    double p[PREFETCH_POINTS][3], f[PREFETCH_POINTS], g[PREFETCH_POINTS][3];
    size_t m = 0;
    for (size_t i = 0; i < n; i++)
        for (int c = 0; c < 8; c++) {
            ism_point_entry *e = slot[i][c];
            if (e->key == k[i].key[c])
                continue; /* held, or gathered already (filled below) */
            e->key = k[i].key[c];
            at[m] = e;
            key[m] = e->key;
            memcpy(p[m++], k[i].p[c], sizeof p[0]);
        }
    if (!m)
        return;
    ism_sample_grad_batch(s, (const double (*)[3])p, f, g, m);
    for (size_t j = 0; j < m; j++)
        if (at[j]->key == key[j]) {
            at[j]->f = f[j];
            memcpy(at[j]->g, g[j], sizeof g[j]);
        }
}

/* Edges gathered for one set of lanes: their memo slots and the keys they were claimed with,
 * their ends and the values there. */
typedef struct root_batch {
    ism_root_entry *slot[PREFETCH_EDGES];
    uint64_t ka[PREFETCH_EDGES], kb[PREFETCH_EDGES];
    double pa[PREFETCH_EDGES][3], pb[PREFETCH_EDGES][3], fa[PREFETCH_EDGES], fb[PREFETCH_EDGES];
    size_t m;
} root_batch;

/* The gathered edges' roots searched in lanes, stored where their slot still holds them and
 * logged, as edge_roots in cell_error.c stores and logs what it searches. */
static void flush_roots(const ism_node_memo *memo, root_batch *rb, ism_sampler *s)
{
    double t[PREFETCH_EDGES];
    ism_regula_falsi_lanes(s, (const double (*)[3])rb->pa, (const double (*)[3])rb->pb, rb->fa,
                           rb->fb, t, rb->m);
    for (size_t k = 0; k < rb->m; k++) {
        if (rb->slot[k]->a == rb->ka[k] && rb->slot[k]->b == rb->kb[k]) /* not taken since */
            rb->slot[k]->t = t[k];
        if (memo->log)
            ism_root_log_push(memo->log, rb->ka[k], rb->kb[k], t[k]);
    }
    rb->m = 0;
}

/* Corners k of a node whose f is finite at all 8: the single roots on its edges the root
 * memo lacks, gathered into rb (searched when it fills). */
static void gather_roots(const ism_node_memo *memo, const ism_corners *k, root_batch *rb,
                         ism_sampler *s)
{
    unsigned neg = 0, zero = 0;
    for (int c = 0; c < 8; c++) {
        neg |= (unsigned)(k->f[c] < 0) << c;
        zero |= (unsigned)(k->f[c] == 0) << c;
    }
    if ((neg == 0 || neg == 0xff) && !zero)
        return; /* one sign: no edge crosses */
    for (int e = 0; e < 12; e++) {
        int c0 = ism_cube_edges[e][0], c1 = ism_cube_edges[e][1];
        if (!(((neg >> c0) ^ (neg >> c1)) & 1) || ((zero >> c0) | (zero >> c1)) & 1)
            continue; /* no single root (edge_roots in cell_error.c) */
        uint64_t a = k->key[c0], b = k->key[c1];
        ism_root_entry *r = ism_root_slot(memo->roots, a, b);
        if (r->a == a && r->b == b)
            continue; /* held, or gathered already */
        *r = (ism_root_entry){a, b, 0};
        size_t m = rb->m++;
        rb->slot[m] = r;
        rb->ka[m] = a;
        rb->kb[m] = b;
        memcpy(rb->pa[m], k->p[c0], sizeof rb->pa[0]);
        memcpy(rb->pb[m], k->p[c1], sizeof rb->pb[0]);
        rb->fa[m] = k->f[c0];
        rb->fb[m] = k->f[c1];
        if (rb->m == PREFETCH_EDGES)
            flush_roots(memo, rb, s);
    }
}

/* Corners k's values from their memo slots, just filled, as node_corners hands them to the
 * flatness test; false when a slot was taken over since. */
static bool corners_from_memo(const ism_node_memo *memo, ism_point_entry *const slot[8],
                              ism_corners *k)
{
    for (int c = 0; c < 8; c++) {
        const ism_point_entry *e = slot[c];
        if (e->key != k->key[c])
            return false;
        k->f[c] = e->f;
        memcpy(k->g[c], e->g, sizeof k->g[c]);
    }
    k->memo = memo;
    return true;
}

static bool all_finite(const double f[8])
{
    for (int c = 0; c < 8; c++)
        if (!isfinite(f[c]))
            return false;
    return true;
}

void ism_prefetch_nodes(const ism_node_memo *memo, ism_point_entry *table, int bits,
                        const ism_grid *g, const ism_node *const *nd, size_t n,
                        ism_sampler *s, ism_corners *k, bool *have)
{
    ism_point_entry *slot[PREFETCH_NODES][8];
    root_batch rb;
    rb.m = 0;
    for (size_t done = 0; done < n; done += PREFETCH_NODES) {
        size_t m = n - done < PREFETCH_NODES ? n - done : PREFETCH_NODES;
        for (size_t i = 0; i < m; i++)
            corners_of(table, bits, g, nd[done + i], &k[done + i], slot[i]);
        fill_corners(k + done, (ism_point_entry *const (*)[8])slot, m, s);
        for (size_t i = 0; i < m; i++) {
            have[done + i] = corners_from_memo(memo, slot[i], &k[done + i]);
            if (have[done + i] && all_finite(k[done + i].f))
                gather_roots(memo, &k[done + i], &rb, s);
        }
    }
    if (rb.m)
        flush_roots(memo, &rb, s);
}
