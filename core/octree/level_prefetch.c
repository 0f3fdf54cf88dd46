/* level_prefetch.c — node corners and edge roots of many nodes of one octree level computed
 * in wide batches into the build's memos (see level_prefetch.h). */
#include "core/octree/level_prefetch.h"
#include "core/octree/corners.h"
#include "core/octree/edge_roots.h"
#include "core/octree/root_table.h"

#include <assert.h>
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
 * world positions and lattice keys (ism_lattice_key) into k, their memo slots into slot. Each
 * axis's two lattice and world coordinates are computed once and the corners picked from them
 * (GCC at -O2 kept the per-axis loop inside the corner loop: ~57 instructions a corner for the
 * positions, Klein bottle at E 3.27e-3). */
static void corners_of(ism_point_entry *table, int bits, const ism_grid *g,
                       const ism_node *nd, ism_corners *k, ism_point_entry *slot[8])
{
    int32_t s = ism_grid_cell_steps(g, nd->level);
    int32_t ip[3][2];
    double w[3][2];
    for (int a = 0; a < 3; a++) {
        ip[a][0] = nd->org[a];
        ip[a][1] = nd->org[a] + s;
        w[a][0] = ism_grid_coord(g, a, ip[a][0]);
        w[a][1] = ism_grid_coord(g, a, ip[a][1]);
    }
    uint64_t mask = ((uint64_t)1 << bits) - 1;
    for (int c = 0; c < 8; c++) {
        int x = c & 1, y = c >> 1 & 1, z = c >> 2 & 1;
        const int32_t at[3] = {ip[0][x], ip[1][y], ip[2][z]};
        k->p[c][0] = w[0][x];
        k->p[c][1] = w[1][y];
        k->p[c][2] = w[2][z];
        k->key[c] = ism_lattice_key(at);
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
    const ism_tape *tape; /* the tape they are searched on */
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
    const ism_tape *saved = s->tape;
    s->tape = rb->tape;
    ism_regula_falsi_lanes(s, (const double (*)[3])rb->pa, (const double (*)[3])rb->pb, rb->fa,
                           rb->fb, t, rb->m);
    s->tape = saved;
    for (size_t k = 0; k < rb->m; k++)
        ism_root_store(rb->slot[k], memo->log, rb->ka[k], rb->kb[k], t[k]);
    rb->m = 0;
}

/* Corners k of a node whose f is finite at all 8: the single roots on its edges the root
 * memo lacks, gathered into rb (searched when it fills). Inlined in both its callers (called,
 * Barth's sextic at E 0.0259 took ~0.9M instructions more). */
static inline __attribute__((always_inline)) void
gather_roots(const ism_node_memo *memo, const ism_corners *k, root_batch *rb, ism_sampler *s)
{
    for (unsigned es = ism_single_root_edges(k->f); es; es &= es - 1) { /* in edge order */
        int e = __builtin_ctz(es);
        int c0 = ism_cube_edges[e][0], c1 = ism_cube_edges[e][1];
        uint64_t a = k->key[c0], b = k->key[c1];
        ism_root_entry *r = ism_root_slot(memo->roots, a, b);
        double held;
        if (ism_root_memo_find(r, a, b, &held))
            continue; /* held, or gathered already */
        ism_root_claim(r, a, b);
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
 * flatness test; false when a slot was taken over since. *finite: f is finite at all 8. */
static bool corners_from_memo(const ism_node_memo *memo, ism_point_entry *const slot[8],
                              ism_corners *k, bool *finite)
{
    bool fin = true;
    for (int c = 0; c < 8; c++) {
        const ism_point_entry *e = slot[c];
        if (e->key != k->key[c])
            return false;
        k->f[c] = e->f;
        fin &= isfinite(e->f) != 0;
        memcpy(k->g[c], e->g, sizeof k->g[c]);
    }
    k->memo = memo;
    *finite = fin;
    return true;
}

/* The roots of the nodes whose corners are all finite (finite[i]), searched on their tapes
 * (tape[i], NULL: s->tape) through rb: the nodes of one tape after another, in the order the
 * tapes first come, so that each set of lanes evaluates one tape. */
static void prefetch_roots(const ism_node_memo *memo, const ism_corners *k,
                           const bool *finite, const ism_tape *const *tape, size_t n,
                           ism_sampler *s, root_batch *rb)
{
    bool done[ISM_PREFETCH_MAX_NODES];
    memset(done, 0, n * sizeof *done);
    for (size_t first = 0; first < n; first++) {
        if (done[first])
            continue;
        const ism_tape *t = tape[first];
        rb->tape = t ? t : s->tape;
        rb->m = 0;
        for (size_t i = first; i < n; i++) {
            if (done[i] || tape[i] != t)
                continue;
            done[i] = true;
            if (finite[i])
                gather_roots(memo, &k[i], rb, s);
        }
        if (rb->m)
            flush_roots(memo, rb, s);
    }
}

/* Do all n nodes search their roots on one tape (into *one)? */
static bool one_tape(const ism_tape *const *tape, size_t n, ism_sampler *s,
                     const ism_tape **one)
{
    *one = tape && n && tape[0] ? tape[0] : s->tape;
    for (size_t i = 1; tape && i < n; i++)
        if (tape[i] != tape[0])
            return false;
    return true;
}

void ism_prefetch_nodes(const ism_node_memo *memo, ism_point_entry *table, int bits,
                        const ism_grid *g, const ism_node *const *nd,
                        const ism_tape *const *tape, size_t n, ism_sampler *s, ism_corners *k,
                        bool *have)
{
    assert(n <= ISM_PREFETCH_MAX_NODES);
    ism_point_entry *slot[PREFETCH_NODES][8];
    bool finite[ISM_PREFETCH_MAX_NODES];
    root_batch rb;
    /* one tape: the roots gathered as each group's corners come (one set of lanes after
     * another), else tape by tape once every corner is in */
    bool one = one_tape(tape, n, s, &rb.tape);
    rb.m = 0;
    for (size_t done = 0; done < n; done += PREFETCH_NODES) {
        size_t m = n - done < PREFETCH_NODES ? n - done : PREFETCH_NODES;
        for (size_t i = 0; i < m; i++)
            corners_of(table, bits, g, nd[done + i], &k[done + i], slot[i]);
        fill_corners(k + done, (ism_point_entry *const (*)[8])slot, m, s);
        for (size_t i = 0; i < m; i++) {
            bool fin = false;
            have[done + i] = corners_from_memo(memo, slot[i], &k[done + i], &fin);
            finite[done + i] = have[done + i] && fin;
            if (one && finite[done + i])
                gather_roots(memo, &k[done + i], &rb, s);
        }
    }
    if (!one)
        prefetch_roots(memo, k, finite, tape, n, s, &rb);
    else if (rb.m)
        flush_roots(memo, &rb, s);
}
