/* octree_build.c — the subdivision of the search box: the top two levels on the calling
 * thread, then one task per level-2 node on the worker threads, each growing its subtree
 * in its own node array, depth first (grow) or a level at a time (level_build.c, where a
 * node's decision is its own); the arrays are joined in task order afterwards (each copied
 * to its place, known from a prefix sum, on the threads). The state both ways share:
 * build_state.h. */
#include "core/octree/octree_build.h"
#include "core/octree/build_state.h"
#include "core/octree/sampler.h"
#include "core/octree/cell_cache.h"
#include "core/octree/crease_memo.h"
#include "core/octree/crease_split.h"
#include "core/octree/edge_roots.h"
#include "core/octree/face_memo.h"
#include "core/octree/leaf_tapes.h"
#include "core/octree/node_balls.h"
#include "core/octree/quiet.h"
#include "core/octree/root_table.h"
#include "core/octree/thin_search.h"
#include "core/octree/turned.h"
#include "core/octree/zero_free.h"
#include "core/eval/shorten.h"
#include "core/util/parallel.h"
#include "core/util/grow.h"
#include "core/util/zeroed.h"

#include <assert.h>
#include <pthread.h>
#include <stdalign.h>
#include <stdatomic.h>
#include <stdlib.h>
#include <string.h>

#define TOP_LEVEL 2
/* The nodes of one top level left for tasks (grow's defer). */
typedef struct defer_list {
    int level;
    deferral *v;
    size_t n;
} defer_list;

bool ism_build_vec_reserve(const build *b, node_vec *v, size_t extra)
{
    return ism_grow((void **)&v->v, &v->cap, v->n + extra, sizeof *v->v, 256) &&
           (!b->shortening ||
            ism_grow((void **)&v->tape, &v->tape_cap, v->n + extra, sizeof *v->tape, 256));
}

static bool vec_push(const build *b, node_vec *v, const ism_node *nd, uint16_t tape)
{
    if (!ism_build_vec_reserve(b, v, 1))
        return false;
    ism_build_vec_put(v, nd, tape);
    return true;
}

/* The tape number node i of the last round's tree kept. */
static uint16_t previous_tape(const build *b, int32_t i)
{
    return b->previous->tape_of ? b->previous->tape_of[i] : 0;
}

static void node_box(const ism_grid *g, const ism_node *nd, double lo[3], double hi[3])
{
    int32_t s = ism_grid_cell_steps(g, nd->level);
    for (int a = 0; a < 3; a++) {
        lo[a] = ism_grid_coord(g, a, nd->org[a]);
        hi[a] = ism_grid_coord(g, a, nd->org[a] + s);
    }
}

/* Interval of f over the node; writes a shortened tape into th->tapes[level] when the box
 * proves min/max branches dominated, and returns the tape to use below this node. */
const ism_tape *ism_build_node_range(build *b, thread_state *th, const ism_node *nd,
                                     const ism_tape *tape, ism_interval *range)
{
    double lo[3], hi[3];
    node_box(b->grid, nd, lo, hi);
    ism_interval x = {lo[0], hi[0]}, y = {lo[1], hi[1]}, z = {lo[2], hi[2]};
    th->s.n_interval++;
    if (b->shortening && th->tapes[nd->level]) { /* fills *range whether or not it shortens */
        if (!ism_tape_shorten(tape, th->s.ws, x, y, z, th->tapes[nd->level], range))
            return tape;
        th->written[nd->level]++;
        return th->tapes[nd->level];
    }
    *range = ism_eval_interval(tape, th->s.ws, x, y, z);
    return tape;
}

ism_tape *ism_build_shorten_into(const build *b, thread_state *th, const ism_node *nd,
                                 const ism_tape *tape)
{
    ism_tape *out = b->shortening ? th->tapes[nd->level] : NULL;
    if (!out || out == tape || out->cap < tape->len || out->nregs < tape->nregs)
        return NULL;
    return out;
}

bool ism_build_node_choices(build *b, thread_state *th, const ism_node *nd,
                            const ism_tape *tape, ism_interval *range)
{
    double lo[3], hi[3];
    node_box(b->grid, nd, lo, hi);
    th->s.n_interval++;
    return ism_tape_shorten_pass(tape, th->s.ws, (ism_interval){lo[0], hi[0]},
                                 (ism_interval){lo[1], hi[1]}, (ism_interval){lo[2], hi[2]},
                                 range);
}

/* f and ∇f at the node's corners, through the thread's memo (neighbours share corners;
 * ism_point_memo_many: the memo ends as one corner at a time leaves it, every value f's and
 * ∇f's at the point bit for bit). */
static void node_corners(const ism_grid *g, thread_state *th, const ism_tape *tape,
                         const ism_node *nd, ism_corners *k)
{
    int32_t s = ism_grid_cell_steps(g, nd->level);
    const ism_tape *saved = th->s.tape;
    th->s.tape = tape; /* the full tape and a shortened one agree inside the node */
    int32_t ip[8][3], ia[3][2];
    double w[3][2]; /* each axis's two lattice and world coordinates, once (as level_prefetch.c's
                       corners_of: the corner loop with the axis loop inside cost ~220
                       instructions a node, Barth's sextic at E 0.0259) */
    for (int a = 0; a < 3; a++) {
        ia[a][0] = nd->org[a];
        ia[a][1] = nd->org[a] + s;
        w[a][0] = ism_grid_coord(g, a, ia[a][0]);
        w[a][1] = ism_grid_coord(g, a, ia[a][1]);
    }
    for (int c = 0; c < 8; c++) {
        int x = c & 1, y = c >> 1 & 1, z = c >> 2 & 1;
        ip[c][0] = ia[0][x], ip[c][1] = ia[1][y], ip[c][2] = ia[2][z];
        k->p[c][0] = w[0][x], k->p[c][1] = w[1][y], k->p[c][2] = w[2][z];
    }
    ism_point_memo_many(th->corners, ISM_CORNER_MEMO_BITS, (const int32_t (*)[3])ip,
                        (const double (*)[3])k->p, 8, &th->s, k->f, k->g, k->key);
    k->memo = th->memo.roots ? &th->memo : NULL; /* none on the reference path */
    th->s.tape = saved;
}

bool ism_build_fail(build *b, enum ism_build_status st)
{
    int expected = ISM_BUILD_OK;
    atomic_compare_exchange_strong(&b->failed, &expected, (int)st);
    return false;
}

/* Whether the whole tree fits does not depend on the batching: every node is counted by the
 * end of its task. */
bool ism_build_count_nodes(build *b, thread_state *th)
{
    size_t n = th->new_nodes;
    th->new_nodes = 0;
    if (atomic_fetch_add(&b->nodes_total, n) + n > b->p->max_nodes)
        return ism_build_fail(b, ISM_BUILD_TOO_BIG);
    return true;
}

/* The one sign of the corners of node face (2 × axis + side), 0 when they differ or one
 * is 0. */
static int face_sign(const ism_corners *k, int face)
{
    int axis = face / 2, side = face % 2, sign = 2;
    for (int c = 0; c < 8; c++) {
        if (((c >> axis) & 1) != side)
            continue;
        int s = ism_sign(k->f[c]);
        if (sign != 2 && s != sign)
            return 0;
        sign = s;
    }
    return sign;
}

/* Is nd in a ball round a certified node that asks for smaller nodes (node_balls.h)?
 * Never at the lattice's last level. */
static bool near_node(const build *b, const ism_node *nd)
{
    if (b->p->nnode_balls == 0 || nd->level >= b->p->thin_depth)
        return false;
    double lo[3], hi[3];
    node_box(b->grid, nd, lo, hi);
    return ism_node_balls_split(&b->node_balls, lo, hi);
}

/* Is fresh node nd split whatever its test says: a force_split key (its emitted triangles
 * missed max_error last round) above depth.max, or in a node ball (near_node)? */
bool ism_build_forced_split(const build *b, const ism_node *nd)
{
    return (nd->level < b->p->max_depth &&
            ism_split_set_has(b->p->force_split, ism_node_key(nd))) ||
           near_node(b, nd);
}

/* A search's verdict, with the counts ism_node.thin keeps (searches, undecided: searches
 * with interval proofs that could neither find a piece nor exclude one; a Newton probe
 * proves nothing where it finds nothing, so an empty probe is a search, not an undecided one
 * — counted, it made thin_undecided the blind leaves' count: the horn cyclide at E = 0.016,
 * depth 9, its own box, 8 undecided with the proofs and 6,364 with empty probes). */
typedef struct thin_tally {
    int searches, undecided;
} thin_tally;

/* One more search of verdict v; probe: by Newton probes only, whose UNDECIDED is no proof. */
static void tally_add(thin_tally *t, enum ism_thin_verdict v, bool probe)
{
    t->searches++;
    t->undecided += v == ISM_THIN_UNDECIDED && !probe;
}

/* probe: Newton probes only (ism_thin_probe), as the preview's coarse search everywhere. */
static enum ism_thin_verdict search(const build *b, thread_state *th, const ism_tape *sub,
                                    const double lo[3], const double hi[3], int sign, bool probe,
                                    thin_tally *tally)
{
    const ism_tape *saved = th->s.tape;
    th->s.tape = sub;
    probe = probe || b->p->thin_coarse;
    enum ism_thin_verdict v = probe ? ism_thin_probe(&th->s, lo, hi, sign, NULL)
                                    : ism_thin_search(&th->s, &th->thin, lo, hi, sign, NULL);
    th->s.tape = saved;
    tally_add(tally, v, probe);
    return v;
}

/* The counters move by a node's hidden-piece verdict, searched now or taken over. */
static void count_thin(thread_state *th, uint8_t thin)
{
    th->thin_searched += ISM_NODE_THIN_SEARCHES(thin);
    th->thin_undecided += ISM_NODE_THIN_UNDECIDED(thin);
    th->thin_found += (thin & ISM_NODE_THIN_FOUND) != 0;
}

/* Points along the straight path between two root pairs' middles (edges_see): the
 * other-sign region joins them when f has the other sign at all of them. A bar between two
 * pairs 0.08 apart leaves a gap of 0.05 (cube minus ball r = 1.41, below): 8 points are
 * 0.009 apart. */
#define JOIN_SAMPLES 8

/* Do f's values at JOIN_SAMPLES points strictly between p and q all have the sign opposite
 * to `sign`? The same points, bit for bit, for (q, p): the two nodes beside a face ask
 * about its edges in orders of their own (face_memo.h keeps one answer for both). */
static bool joined(ism_sampler *s, const double *p, const double *q, int sign)
{
    if (p[0] > q[0] || (p[0] == q[0] && (p[1] > q[1] || (p[1] == q[1] && p[2] > q[2])))) {
        const double *r = p;
        p = q;
        q = r;
    }
    for (int i = 1; i <= JOIN_SAMPLES; i++) {
        double t = (double)i / (JOIN_SAMPLES + 1), x[3];
        for (int j = 0; j < 3; j++)
            x[j] = p[j] + t * (q[j] - p[j]);
        double f = ism_sample_f(s, x);
        if (!(sign > 0 ? f < 0 : f > 0))
            return false;
    }
    return true;
}

static int root_of(int *up, int i)
{
    while (up[i] != i)
        i = up[i];
    return i;
}

/* Does the polygoniser's edge search (edge_roots.h, as the cells will run it) see the piece
 * found at a kink on the node's edges: on face `face`'s four, or on all twelve when face < 0?
 * It does when some edge holds a root pair and the other-sign region joins the pairs' middles
 * pairwise along straight paths (one sliver, one loop of the cells). Pairs that the region
 * does not join there may be two ends of one bar that passes between them unseen: cube minus
 * ball r = 1.41 (bars 1/13 of a depth-5 cell), box ±1.3 moved by 0.37 cell, has a lattice
 * plane 0.0063 inside a cube face, past the bars' middle section (0.006) but not their ends,
 * so the plane met each bar only near the node's two ends and the cells capped the ends
 * apart (χ −2, three bars cut). A crease's wedge crossing the node leaves a strip on a face
 * that joins its pairs. */
static bool edges_see(const build *b, thread_state *th, const ism_tape *sub,
                      const ism_corners *k, int face)
{
    const ism_flatness *fl = &b->p->flatness;
    ism_root_params prm = {fl->gradient_test, fl->double_root_eps, fl->double_root_iters,
                           true}; /* asked only where f has a kink */
    const ism_tape *saved = th->s.tape;
    th->s.tape = sub;
    double mid[12][3];
    int up[12], n = 0, sign = 0;
    for (int e = 0; e < 12; e++) {
        int c0, c1, faces[2];
        ism_cube_edge(e, &c0, &c1, faces);
        if (face >= 0 && faces[0] != face && faces[1] != face)
            continue;
        /* ism_segment_roots's path to its first pair (the box's corners share a sign: only
         * the double-root search can find one); t: a point between the two roots */
        const double *a = k->p[c0], *z = k->p[c1];
        double t = 0;
        int found = 0;
        if (!ism_segment_rootless(&prm, a, z, k->f[c0], k->f[c1], k->g[c0], k->g[c1]) &&
            ism_segment_may_reach(&th->s, a, z, 0)) {
            /* no memo on the scalar reference path (poly_options.h) */
            ism_pair_entry none = {0}, /* keys are + 1: never a hit */
                *m = th->memo.pairs ? ism_pair_slot(th->memo.pairs, k->key[c0] + 1,
                                                    k->key[c1] + 1)
                                    : &none;
            if (m->a == k->key[c0] + 1 && m->b == k->key[c1] + 1) {
                found = m->found;
                t = m->t;
            } else {
                found = ism_double_root_search(&th->s, &prm, a, z, k->f[c0], k->f[c1], &t);
                *m = (ism_pair_entry){k->key[c0] + 1, k->key[c1] + 1, t, found};
            }
        }
        if (found == 0)
            continue;
        sign = k->f[c0] < 0 ? -1 : 1;
        for (int j = 0; j < 3; j++)
            mid[n][j] = a[j] + t * (z[j] - a[j]);
        up[n] = n;
        /* a tangent point (1) joins nothing: the cells see a touching point there */
        for (int i = 0; i < n && found == 2; i++)
            if (root_of(up, i) != root_of(up, n) && joined(&th->s, mid[i], mid[n], sign))
                up[root_of(up, i)] = root_of(up, n);
        n++;
    }
    int groups = 0;
    for (int i = 0; i < n; i++)
        groups += root_of(up, i) == i;
    th->s.tape = saved;
    return groups == 1;
}

/* The verdict as ism_node.thin keeps it. */
static uint8_t thin_bits(const thin_tally *tally, enum ism_thin_verdict v)
{
    bool found = v == ISM_THIN_FOUND || v == ISM_THIN_FOUND_KINKED;
    return ISM_NODE_THIN_PACK(tally->searches, tally->undecided, found) |
           (v == ISM_THIN_FOUND_KINKED ? ISM_NODE_THIN_AT_KINK : 0);
}

/* The hidden-piece search of the node (face < 0) or of one face (lo..hi): a piece found at
 * a kink counts only when the box's edges see no root (see hides_piece); ISM_THIN_KINKED
 * when they do. */
static enum ism_thin_verdict search_box(const build *b, thread_state *th, const ism_tape *sub,
                                        const ism_corners *k, const double lo[3],
                                        const double hi[3], int sign, int face, bool probe,
                                        thin_tally *tally)
{
    enum ism_thin_verdict v = search(b, th, sub, lo, hi, sign, probe, tally);
    if (v == ISM_THIN_FOUND_KINKED && edges_see(b, th, sub, k, face))
        return ISM_THIN_KINKED; /* a sliver of the solid's wedge (or more), seen there */
    return v;
}

/* The number of sub (a shortened tape: th->tapes[l] for some l <= level) in the build's
 * table, 0 when it finds no room there. */
static uint16_t tape_number_of(build *b, thread_state *th, const ism_tape *sub, int level)
{
    int l = level;
    while (l >= 0 && th->tapes[l] != sub)
        l--;
    uint16_t k;
    if (l >= 0 && th->numbered[l] == th->written[l]) {
        k = th->number[l];
    } else {
        k = (uint16_t)ism_leaf_tapes_number(&b->leaf_tapes, &th->tape_cache, sub);
        if (l >= 0) {
            th->number[l] = k;
            th->numbered[l] = th->written[l];
        }
    }
    return k;
}

/* The same for a leaf's tape, counting the misses. */
static uint16_t tape_number(build *b, thread_state *th, const ism_tape *sub, int level)
{
    uint16_t k = tape_number_of(b, th, sub, level);
    th->tape_misses += k == 0;
    return k;
}

/* face_memo.h's verdict for a face where f keeps its sign by the face's interval (no
 * search ran), beside enum ism_thin_verdict's. */
#define FACE_CLEAR 0xff

/* A would-be leaf may hold a piece of the surface that no edge crosses (thin_search.h):
 * with all corners of one sign, anywhere in it; with both signs, behind a face whose four
 * corners share a sign — a nappe or a thin tube piercing the face in a closed curve that
 * crosses none of its edges (an island), which neither this node nor its neighbour across
 * the face would see. Returns the verdict as ism_node.thin keeps it: when it holds
 * ISM_NODE_THIN_FOUND the node is split, below depth.max too, down to b->p->thin_depth at
 * most. probe: Newton probes only (ism_thin_probe), no interval proof.
 *
 * Where f has a kink (a CSG crease) a search finds the solid's wedge poking past the corners
 * at every depth. Such a sliver is no piece of its own: a wedge W (two planes) meeting the
 * box but none of its corners has its vertices where W's planes cut the box's edges, or
 * where its edge leaves through a face (two points at most), so it reaches an edge of the
 * box, and of each face it cuts (a straight 2-D wedge in the face), and the cells see it
 * there. What the edges do not see is a piece of its own: a bar thinner than the node
 * passing through it (its section an island on two faces), a lens where two balls overlap
 * (the wedge's planes curved), a piece inside it. So a piece found where f has a kink
 * counts when the node's edges see no root (or see pairs that the piece does not join:
 * edges_see), or, in a face whose four corners share a sign (all six of a node whose edges
 * see the sliver), when the face's four edges see none:
 *
 *        sliver: its wedge crosses an edge      bar: an island in the face
 *        +─────────────────+                    +─────────────────+
 *        │        ╱╲       │                    │                 │
 *        │       ╱  ╲      │                    │      ╱╲         │
 *        │      ╱    ╲     │                    │     ╱  ╲        │
 *        +─────×──────×────+                    │    ╱____╲       │
 *             two roots on the edge             +─────────────────+
 *
 * The preview's coarse search (b->p->thin_coarse) probes whole nodes, and the faces of
 * nodes with both signs only where f has a kink (without them a bar found in a split node
 * met its unsplit neighbour's face in an island: cracks).
 *
 * Cost (own boxes, depth 7, one thread: `isomesh --surface S --threads 1`), where nothing is
 * hidden: the gyroid ball searches 4,425 boxes, most at its crease; skipping every node whose
 * tape keeps a min/max would cost 1,850M instructions, the search there 2,048M (+10.7%),
 * two thirds of it on faces (searches 5.1% of the run, their intervals 1.7%); cube minus ball
 * (r = 1.3) 1,397M -> 1,537M (+10.0%). A face's verdict is kept for the node across it
 * (face_memo.h): 2,027M and 1,514M, meshes the same; only 7.5% / 4% of the faces looked up
 * are found there (the node across is mostly a leaf of another size, or flat). An edge's
 * root pair is kept for the nodes beside it too (cell_cache.h ism_pair_entry; after the build's own edge
 * memos, cell_cache.h: 1,990M -> 1,983M and 1,478M -> 1,459M). The search at kinks is one
 * level deep (thin_search.c). */
static uint8_t hides_piece(build *b, thread_state *th, const ism_node *nd, const ism_tape *sub,
                           const ism_corners *k, bool probe)
{
    if (nd->level >= b->p->thin_depth)
        return 0;
    double lo[3], hi[3];
    node_box(b->grid, nd, lo, hi);
    if (ism_quiet_holds(&b->quiet, lo, hi))
        return 0;
    thin_tally tally = {0, 0};
    enum ism_thin_verdict v = ISM_THIN_EXCLUDED;
    int sign = face_sign(k, 0);
    bool one_sign = sign != 0 && sign == face_sign(k, 1);
    if (one_sign) {
        v = search_box(b, th, sub, k, lo, hi, sign, -1, probe, &tally);
        if (v != ISM_THIN_KINKED)
            return thin_bits(&tally, v); /* else islands in its faces still count */
    }
    if (b->p->thin_coarse && !ism_tape_has_min_max(sub))
        return thin_bits(&tally, v);
    /* the faces' verdicts are kept for the node across, under sub's number in the leaf
     * tapes' table (0: the build's own tape), the number this leaf takes anyway; none when
     * the table has no room, when leaves keep the full tape (the table stays empty), nor
     * on the scalar reference path */
    bool own = sub == b->p->tape;
    unsigned number = own || b->p->full_tape ? 0 : tape_number_of(b, th, sub, nd->level);
    bool memo = !b->p->scalar_eval && (own || number != 0) && !probe; /* probes prove less */
    uint32_t what = ism_face_memo_what(nd->level, 0, number);
    int32_t steps = ism_grid_cell_steps(b->grid, nd->level);
    for (int face = 0; face < 6 && v != ISM_THIN_FOUND && v != ISM_THIN_FOUND_KINKED; face++) {
        int s = face_sign(k, face);
        if (s == 0)
            continue;
        int axis = face / 2;
        uint64_t where =
            ism_face_memo_where(nd->org, axis, nd->org[axis] + (face % 2 ? steps : 0));
        uint32_t face_what = what | ism_face_memo_what(0, axis, 0);
        uint8_t kept;
        if (memo && ism_face_memo_get(&th->faces, where, face_what, &kept)) {
            if (kept != FACE_CLEAR) { /* counted as the search it stands for */
                v = (enum ism_thin_verdict)kept;
                tally_add(&tally, v, probe || b->p->thin_coarse);
            }
            continue;
        }
        double flo[3], fhi[3];
        memcpy(flo, lo, sizeof flo);
        memcpy(fhi, hi, sizeof fhi);
        if (face % 2)
            flo[axis] = hi[axis];
        else
            fhi[axis] = lo[axis];
        th->s.n_interval++;
        ism_interval r = ism_eval_interval(sub, th->s.ws, (ism_interval){flo[0], fhi[0]},
                                           (ism_interval){flo[1], fhi[1]},
                                           (ism_interval){flo[2], fhi[2]});
        if (!(r.lo <= 0 && r.hi >= 0)) { /* f keeps a sign on the whole face */
            if (memo)
                ism_face_memo_put(&th->faces, where, face_what, FACE_CLEAR);
            continue;
        }
        v = search_box(b, th, sub, k, flo, fhi, s, face, probe, &tally);
        if (memo)
            ism_face_memo_put(&th->faces, where, face_what, (uint8_t)v);
    }
    return thin_bits(&tally, v);
}

/* The level down to which nodes failing the flatness test split below a node where a
 * hidden piece was found. */
static int resolve_limit(const build *b, int limit)
{
    int resolve = b->p->max_depth + (b->p->thin_coarse ? 0 : ISM_THIN_RESOLVE_LEVELS);
    resolve = resolve < b->p->thin_depth ? resolve : b->p->thin_depth;
    return limit > resolve ? limit : resolve;
}

/* The last round's node pi taken over for node i when its decision still holds: an empty
 * node stays empty, a leaf not forced to split now stays a leaf (with its flags). The
 * counters move as the evaluation would have moved them. */
static bool take_over(build *b, thread_state *th, node_vec *v, size_t i, int32_t pi,
                      bool forced)
{
    const ism_node *pv = &b->previous->nodes[pi];
    if (pv->state == ISM_NODE_EMPTY) {
        v->v[i].state = ISM_NODE_EMPTY;
        th->excluded++;
        return true;
    }
    if (pv->state != ISM_NODE_LEAF || forced)
        return false;
    v->v[i].state = ISM_NODE_LEAF;
    v->v[i].flags = pv->flags;
    v->v[i].thin = pv->thin;
    if (v->tape)
        v->tape[i] = previous_tape(b, pi);
    count_thin(th, pv->thin);
    th->unresolved += (pv->flags & ISM_NODE_UNRESOLVED) != 0;
    th->deep_leaves += pv->level > b->p->max_depth;
    return true;
}

/* The intervals of node nd's 8 children over tape, in one batched call (the same bounds
 * ism_build_node_range finds child by child when it does not shorten). */
void ism_build_children_ranges(build *b, thread_state *th, const ism_node *nd,
                               const ism_tape *tape, ism_interval range[8])
{
    ism_interval box[3][8];
    for (int k = 0; k < 8; k++) {
        ism_node c = ism_build_child(b, nd, k);
        double lo[3], hi[3];
        node_box(b->grid, &c, lo, hi);
        for (int a = 0; a < 3; a++)
            box[a][k] = (ism_interval){lo[a], hi[a]};
    }
    ism_eval_interval_batch(tape, th->s.ws, box[0], box[1], box[2], range, 8);
    th->s.n_interval += 8;
}

/* Without max_error, is an unresolved leaf (lo..hi, tape sub) one a larger depth.max could
 * improve? Not on a crease (sub keeps a min/max: a C0 kink fails the corner gradients at
 * every level) nor where the singular locus is (a quiet ball meets it: two sheets or a cone
 * fail them at every level, and the conformance pass rebuilds the mesh there) or beside it:
 * a cone bends across its rulings with radius r tan α at distance r from its apex (α its
 * half-opening), so a cell of size h there holds a polygon (face diagonal √2 h) that leaves
 * its plane by h² / (4 r tan α) — beyond the flatness tolerance flat_plane h for
 * r < h / (4 flat_plane tan α), 5 cells on a right cone (tan α = 1) at the default 0.05, at
 * every depth (the cone is self-similar: the double cone in boxes moved off the lattice by
 * 1e-3 and by irrational fractions warned for 4 / 6 / 6 and 13 / 13 / 13 cells at depth.max
 * 6 / 7 / 8, 2.8-3.7 cells from its node, their worst distance halving with each level as
 * the locus's own cells do).
 * Narrower cones than right ones still warn there. Here only the balls that meet the leaf
 * are asked (reach 0: the grid cells round it); its emitted triangles are then measured
 * (polygonise.c), and only a leaf measured beyond the tolerance asks for the balls within
 * the cone's reach (measure_unflat): asked here of every unresolved leaf, that reach (5
 * leaf sizes: every grid cell within it, or every ball, read per leaf) cost Steiner's Roman
 * surface (43,364 such leaves round thousands of tube balls) ~1.2 s of a 2.3 s octree
 * stage. Under max_error the error rounds report. */
static bool unflat(const build *b, const ism_tape *sub, const double lo[3], const double hi[3])
{
    return b->p->flatness.max_error <= 0 && !ism_tape_has_min_max(sub) &&
           !ism_quiet_near(&b->quiet, lo, hi, 0);
}

/* Under max_error, may a node that failed the plot test stay whole because the conformance
 * pass meshes its box again? Its box lies in a quiet ball: inside the tube (or ball) of
 * CF_RHO_CELLS cells of the singular stage's depth that the pass cuts out round a double
 * curve or singular point (surface.c quiet_balls: 0.8 of its radius; the pass widens the cut,
 * never narrows it), so none of its triangles is kept. Along a double curve or at a cone the
 * plot test fails at every level (two sheets, a zero gradient on the locus), and the error
 * rounds split such leaves again (their polygons straddle the locus, a cell off it): they
 * went to depth.max, the safety depth 10 under the default bound, whatever E (crossing
 * planes: the tube's triangles removed 33,792 at depth 10 against 6,144 at depth 8, the
 * same 24,704-triangle mesh). A node as large as the ball stays out (its box is not held), so
 * the tube's rim still lies in cells the plot test and E decided. */
static bool conformed(const build *b, const double lo[3], const double hi[3])
{
    return b->p->flatness.max_error > 0 && ism_quiet_holds(&b->quiet, lo, hi);
}

/* Is a quiet ball's centre within ISM_TURNED_LOCUS_CELLS sizes of box lo..hi? Beside the
 * singular locus the corner gradients turn apart at every depth (they vanish on it). Asked
 * only of turned leaves at depth.max, last (the wide query: Steiner d8 +53M instructions
 * when asked first). */
static bool beside_locus(const build *b, const double lo[3], const double hi[3])
{
    return ism_quiet_near(&b->quiet, lo, hi, ISM_TURNED_LOCUS_CELLS * (hi[0] - lo[0]));
}

/* Is a crossed leaf at depth.max that failed the flatness test, on the depth path (unflat:
 * no max_error, no min/max, no quiet ball meeting it; the caller asks that first, as it
 * needs it anyway), a feature about a cell across that its corners see (turned.h), to be
 * resolved as deep as a hidden one? Its corner gradients turn over; no kink in its tape
 * (min, max and abs: an abs crease turns the gradients at every depth —
 * crease/narrow_bump_under_a_plane lost a piece, 1 instead of 2); f's nearby critical point
 * stands for a feature wider than ISM_TURNED_MIN_RADIUS (not a crossing of two sheets); no
 * singular locus near. Cheapest first. */
static bool visible_feature(const build *b, thread_state *th, const ism_tape *sub,
                            const ism_corners *k, const double lo[3], const double hi[3])
{
    return ism_corners_turned(k->g, ISM_TURNED_COS) && !ism_tape_has_kink(sub) &&
           ism_critical_radius(sub, th->s.ws, k, hi[0] - lo[0], ISM_TURNED_NEWTON_STEPS,
                               ISM_TURNED_PINV_REL, ISM_TURNED_NEWTON_REACH) >
               ISM_TURNED_MIN_RADIUS &&
           !beside_locus(b, lo, hi);
}

/* The nodes of the last round's tree that a subtree copy must not skip (copy_subtree): 1 on
 * the descent to each key of force_split (a superset of the ancestors of the leaves forced
 * now). None is computed, and no subtree copied, when node balls may force a leaf
 * (near_node). */
static uint8_t *mark_forced(const ism_octree *t, const ism_split_set *set)
{
    uint8_t *mark = calloc(t->n, 1);
    for (size_t k = 0; mark && set && k < set->n; k++) {
        int32_t o[3], path[ISM_GRID_MAX_DEPTH + 1];
        int level = ism_node_key_decode(set->keys[k], o);
        for (int n = ism_octree_path(t, o, level, path), j = 0; j < n; j++)
            mark[path[j]] = 1;
    }
    return mark;
}

/* One past the last node of split node i's subtree in tree t: the children of its last split
 * node in grow's order (the last split child's, recursively) are appended last. Relies on
 * the subtree being one run (copy_subtree's comment). */
static size_t subtree_end(const ism_octree *t, int32_t i)
{
    for (;;) {
        int32_t first = t->nodes[i].child, last = -1;
        for (int k = 7; k >= 0 && last < 0; k--)
            if (t->nodes[first + k].state == ISM_NODE_SPLIT)
                last = first + k;
        if (last < 0)
            return (size_t)first + 8;
        i = last;
    }
}

/* Node v->v[i], split in the last round as node pi with no forced leaf below, and its
 * subtree copied from the last round's tree: what grow makes of them node by node (split
 * nodes keep their verdicts, leaves their flags, verdicts and tapes: take_over), counted
 * as it counts them. Its root is visited already.
 * Why: later rounds re-grew the last round's tree node by node, though below such a node
 * nothing is decided afresh (take_over keeps every leaf and empty node, and split nodes
 * split again): Barth's sextic at E 0.0259 walked ~28M instructions of octree in each of
 * its 5 later rounds to change a few dozen nodes. A grown subtree lies in one run of nodes
 * after its root's children (grow appends a node's 8 children, then grows each in turn,
 * and join_tasks keeps each task's run in one piece), so the copy is a run with its child
 * indices moved. */
static bool copy_subtree(build *b, thread_state *th, node_vec *v, size_t i, int32_t pi)
{
    const ism_octree *t = b->previous;
    size_t from = (size_t)t->nodes[pi].child, end = subtree_end(t, pi), n = end - from;
    if ((th->new_nodes += n) >= NODE_BATCH && !ism_build_count_nodes(b, th))
        return false;
    if (!ism_build_vec_reserve(b, v, n))
        return ism_build_fail(b, ISM_BUILD_NO_MEMORY);
    int32_t shift = (int32_t)v->n - (int32_t)from;
    v->v[i].state = ISM_NODE_SPLIT;
    v->v[i].child = (int32_t)v->n;
    v->v[i].thin = t->nodes[pi].thin;
    count_thin(th, t->nodes[pi].thin);
    for (size_t j = from; j < end; j++) {
        const ism_node *q = &t->nodes[j];
        ism_node c = {{q->org[0], q->org[1], q->org[2]}, -1, q->level, q->state, 0, 0};
        uint16_t tape = 0;
        if (q->state == ISM_NODE_SPLIT) {
            c.child = q->child + shift;
            c.thin = q->thin;
            count_thin(th, q->thin);
        } else if (q->state == ISM_NODE_LEAF) {
            c.flags = q->flags;
            c.thin = q->thin;
            tape = previous_tape(b, (int32_t)j);
            count_thin(th, q->thin);
            th->unresolved += (q->flags & ISM_NODE_UNRESOLVED) != 0;
            th->deep_leaves += q->level > b->p->max_depth;
        } else {
            th->excluded++;
        }
        ism_build_vec_put(v, &c, tape);
    }
    th->visited += n;
    th->copied += n;
    return true;
}

/* The tape of a node split in the last round, asked for only when a node below it is decided
 * afresh: the walk reaches only the subtrees on a forced path (the others are copied whole,
 * copy_subtree), or all of them when there are node balls, and a reached subtree may still
 * be taken over node by node and evaluate nothing, yet its split nodes shortened their
 * tapes again (Barth's sextic at E 1e-2: 17M of each later round's ~65M octree). `tape` is the node's once resolved (NULL
 * before); its parent's is `above` when that is itself pending, else `parent`. ism_build_node_range
 * writes th->tapes[level] as it would have when the node was reached: the levels below a
 * pending node are written only inside its subtree, so a resolved tape stays valid for
 * the rest of it. */
typedef struct tape_link {
    struct tape_link *above;
    const ism_tape *parent, *tape;
    ism_node nd;
} tape_link;

static const ism_tape *resolve_tape(build *b, thread_state *th, tape_link *l)
{
    if (!l->tape) {
        ism_interval range;
        const ism_tape *parent = l->above ? resolve_tape(b, th, l->above) : l->parent;
        l->tape = ism_build_node_range(b, th, &l->nd, parent, &range);
    }
    return l->tape;
}

/* The flatness test of a fresh node nd (no previous round's verdict; at depth.min or below,
 * not forced) over tape sub, with the hidden-piece search and the resolve levels it may ask
 * for: true when it is a leaf. Its corners: known (node_corners' values, prefetched), or
 * NULL to read them here. Its flags and verdict go to *out, the level its children may be
 * split down to to *limit_io. */
bool ism_build_test_node(build *b, thread_state *th, const ism_node *nd, const ism_tape *sub,
                         const ism_corners *known, ism_node *out, int *limit_io)
{
    int limit = *limit_io;
    bool leaf;
    double lo[3], hi[3];
    node_box(b->grid, nd, lo, hi);
    ism_corners own;
    if (!known)
        node_corners(b->grid, th, b->p->tape, nd, &own);
    const ism_corners *k = known ? known : &own;
    const ism_tape *saved = th->s.tape;
    th->s.tape = sub;
    bool blind;
    bool flat = ism_plot_test(&th->s, th->thin.jet, &b->p->flatness, lo, hi, k, &blind);
    th->s.tape = saved;
    bool kept = !flat && nd->level < limit && conformed(b, lo, hi);
    leaf = flat || kept || nd->level >= limit;
    /* a leaf proven free of f = 0 emits nothing and hides no piece: skipped from here */
    if (leaf && !b->p->scalar_eval &&
        ism_box_zero_free(sub, th->s.ws, th->thin.jet, lo, hi, k,
                          b->p->flatness.double_root_eps, &th->s.n_interval))
        out->flags |= ISM_NODE_ZERO_FREE;
    else if (leaf && !kept && (!flat || blind)) {
        /* A leaf that passed the test blind (ism_plot_test: under max_error, at most 4 E
         * across, corners of one sign whose gradients disagree) is searched by Newton
         * probes alone, not with the interval proofs. The horn cyclide at E = 0.016,
         * depth 9 (callgrind, one thread): in the box moved by (0.37, −0.23, 0.41) of a
         * cell 1,473M instructions with the horns lost, 4,648M searching such leaves in
         * full, 2,776M probing them (both find the horns: χ 1); in its own box, where
         * nothing more is found (the same mesh), 2,074M, 3,298M and 2,395M. A kept
         * leaf (conformed) lies in a quiet ball, where hides_piece searches nothing. */
        out->thin = hides_piece(b, th, nd, sub, k, flat);
        count_thin(th, out->thin);
    }
    if (out->thin & ISM_NODE_THIN_FOUND) {
        leaf = false;
        /* below a piece found at a kink only the nodes that still hide it split: there
         * every node on a crease fails the flatness test (cube minus ball r = 1.4, d5:
         * 13,232 triangles with the resolve levels, 7,424 without; 5,456 losing the bars) */
        if (!(out->thin & ISM_NODE_THIN_AT_KINK))
            limit = resolve_limit(b, limit);
    }
    bool uf = leaf && !flat && unflat(b, sub, lo, hi); /* asked once per unflat leaf */
    if (uf && !kept && nd->level >= limit && limit < resolve_limit(b, limit) &&
        visible_feature(b, th, sub, k, lo, hi)) {
        leaf = false; /* resolved as deep as a hidden piece would be */
        limit = resolve_limit(b, limit);
    }
    if (leaf && !flat) {
        out->flags |= ISM_NODE_UNRESOLVED | (kept ? ISM_NODE_CONFORMED : 0);
        th->unresolved++;
        if (uf)
            out->flags |= ISM_NODE_UNFLAT;
    }
    th->deep_leaves += leaf && nd->level > b->p->max_depth;
    *limit_io = limit;
    return leaf;
}

/* Decides node v->v[i] and grows its subtree. Nodes that fail the flatness test are split
 * down to level `limit` (depth.max, or ISM_THIN_RESOLVE_LEVELS deeper below a hidden
 * piece or a visible feature about a cell across, visible_feature); a would-be leaf that
 * hides a piece is split in any case, down to thin_depth. When defer is not NULL, nodes at
 * its level are left for tasks (appended to it). pi: the same node in the last round's tree
 * (b->previous), or -1. */
static bool grow(build *b, thread_state *th, node_vec *v, size_t i, const ism_tape *tape,
                 tape_link *above, int limit, defer_list *defer, int32_t pi,
                 const ism_interval *known)
{
    if (atomic_load(&b->failed) != ISM_BUILD_OK)
        return false;
    if (b->p->cancel && *b->p->cancel)
        return ism_build_fail(b, ISM_BUILD_CANCELLED);
    ism_node nd = v->v[i];
    if (defer && nd.level == defer->level) {
        deferral *d = realloc(defer->v, (defer->n + 1) * sizeof *d);
        if (!d)
            return ism_build_fail(b, ISM_BUILD_NO_MEMORY);
        d[defer->n++] = (deferral){i, limit, pi};
        defer->v = d;
        return true;
    }
    th->visited++;
    const ism_node *pv = pi >= 0 ? &b->previous->nodes[pi] : NULL;
    if (pv && pv->state == ISM_NODE_SPLIT && !defer && b->forced_below &&
        !b->forced_below[pi])
        return copy_subtree(b, th, v, i, pi);
    /* asked only where it decides: a node the last round left empty stays empty and one it
     * split is split again, forced or not (take_over) */
    bool forced = (!pv || pv->state == ISM_NODE_LEAF) && ism_build_forced_split(b, &nd);
    if (pv && take_over(b, th, v, i, pi, forced))
        return true;
    bool was_split = pv && pv->state == ISM_NODE_SPLIT;
    /* a node split again: its tape only when a node below asks (tape_link) */
    tape_link link = {above, tape, NULL, nd};
    if (!was_split && above)
        tape = resolve_tape(b, th, above);
    ism_interval range = known ? *known : (ism_interval){0, 0};
    const ism_tape *sub =
        known || was_split ? tape : ism_build_node_range(b, th, &nd, tape, &range);
    if (!pv && !(range.lo <= 0 && range.hi >= 0)) {
        v->v[i].state = ISM_NODE_EMPTY;
        th->excluded++;
        return true;
    }
    bool leaf = false;
    /* a node split last round is split again (its range was computed for its tape), with
     * the hidden-piece verdict that split it */
    if (pv && pv->state == ISM_NODE_SPLIT) {
        v->v[i].thin = pv->thin;
        count_thin(th, pv->thin);
        if ((pv->thin & ISM_NODE_THIN_FOUND) && !(pv->thin & ISM_NODE_THIN_AT_KINK))
            limit = resolve_limit(b, limit); /* as below */
    }
    if (!pv && nd.level >= b->p->min_depth && !forced)
        leaf = ism_build_test_node(b, th, &nd, sub, NULL, &v->v[i], &limit);
    if (leaf) {
        v->v[i].state = ISM_NODE_LEAF;
        /* the tape its cell evaluates: sub, shortened over this box or an ancestor's */
        if (sub != b->p->tape && !(v->v[i].flags & ISM_NODE_ZERO_FREE) && !b->p->full_tape)
            v->tape[i] = tape_number(b, th, sub, nd.level);
        return true;
    }
    if ((th->new_nodes += 8) >= NODE_BATCH && !ism_build_count_nodes(b, th))
        return false;
    size_t first = v->n;
    if (!ism_build_vec_reserve(b, v, 8))
        return ism_build_fail(b, ISM_BUILD_NO_MEMORY);
    for (int k = 0; k < 8; k++) {
        ism_node c = ism_build_child(b, &nd, k);
        ism_build_vec_put(v, &c, 0);
    }
    v->v[i].state = ISM_NODE_SPLIT;
    v->v[i].child = (int32_t)first;
    /* the children's intervals at once, unless each child may shorten its own tape (sub
     * still holds a min/max), is taken over from the last round, or is left for a task */
    bool batch = !b->p->scalar_eval && !was_split && !(defer && nd.level + 1 == defer->level) &&
                 !(b->shortening && ism_tape_has_min_max(sub));
    ism_interval ranges[8];
    if (batch)
        ism_build_children_ranges(b, th, &nd, sub, ranges);
    for (int k = 0; k < 8; k++)
        if (!grow(b, th, v, first + k, was_split ? NULL : sub, was_split ? &link : NULL, limit,
                  defer, was_split ? pv->child + k : -1, batch ? &ranges[k] : NULL))
            return false;
    return true;
}

static void report_progress(build *b)
{
    if (!b->p->progress)
        return;
    size_t done = atomic_fetch_add(&b->tasks_done, 1) + 1;
    pthread_mutex_lock(&b->progress_lock);
    b->p->progress(b->p->progress_ctx, (double)done / (double)b->ntasks);
    pthread_mutex_unlock(&b->progress_lock);
}

static void run_task(void *ctx, size_t task, int thread)
{
    build *b = ctx;
    thread_state *th = &b->threads[thread];
    node_vec *out = &b->task_out[task];
    /* The task's tape: shorten from the full tape over the task's own box on the way. */
    enum ism_levels_result r = ism_levels_apply(b, th)
                                   ? ism_grow_levels(b, th, out, b->tasks[task].limit)
                                   : ISM_LEVELS_DECLINED;
    bool ok = r == ISM_LEVELS_DECLINED
                  ? grow(b, th, out, 0, b->p->tape, NULL, b->tasks[task].limit, NULL,
                         b->tasks[task].previous, NULL)
                  : r == ISM_LEVELS_GROWN;
    if (ok)
        ism_build_count_nodes(b, th);
    report_progress(b);
}

static bool init_threads(build *b, int nthreads)
{
    b->threads = aligned_alloc(ISM_CACHE_LINE, (size_t)nthreads * sizeof *b->threads);
    if (!b->threads)
        return false;
    memset(b->threads, 0, (size_t)nthreads * sizeof *b->threads);
    /* the caller's, or zeroed by writing (zeroed.h): a lookup reads its slot before it
     * fills it. 2^16 entries of 40 bytes: each thread's memo starts on a cache line of its
     * own. */
    size_t memo = (size_t)1 << ISM_CORNER_MEMO_BITS;
    b->corner_memos = b->p->corner_memos
                          ? b->p->corner_memos
                          : ism_zeroed_alloc(b->p->pool, (size_t)nthreads * memo,
                                             sizeof *b->corner_memos, b->p->cost);
    if (!b->corner_memos)
        return false;
    /* the node memos (none on the scalar reference path, poly_options.h) */
    size_t roots = (size_t)1 << ISM_ROOT_MEMO_BITS, labels = (size_t)1 << ISM_LABEL_MEMO_BITS;
    size_t pairs = (size_t)1 << ISM_PAIR_MEMO_BITS;
    if (!b->p->scalar_eval) {
        b->root_memos = ism_zeroed_alloc(b->p->pool, (size_t)nthreads * roots,
                                         sizeof *b->root_memos, b->p->cost);
        b->label_memos = ism_zeroed_alloc(b->p->pool, (size_t)nthreads * labels,
                                          sizeof *b->label_memos, b->p->cost);
        b->pair_memos = ism_zeroed_alloc(b->p->pool, (size_t)nthreads * pairs,
                                         sizeof *b->pair_memos, b->p->cost);
        if (!b->root_memos || !b->label_memos || !b->pair_memos)
            return false;
    }
    for (int t = 0; t < nthreads; t++) {
        thread_state *th = &b->threads[t];
        th->s.tape = b->p->tape;
        th->s.dist_above = b->p->flatness.max_error;
        th->s.rays_below = b->p->nquiet ? INFINITY : 0;
        th->s.batch = !b->p->scalar_eval;
        th->s.wedge_edges_below =
            ism_crease_wedge_edges(b->grid, b->p->max_depth, b->p->flatness.max_error);
        th->s.crease_pieces = ism_crease_pieces(b->p->tape);
        th->s.fold_below = ism_crease_fold_below(b->p->flatness.max_error);
        th->s.memo_tape = b->p->scalar_eval ? NULL : b->p->tape; /* poly_options.h */
        th->s.crease_memo = b->p->crease_memos ? &b->p->crease_memos[t] : NULL;
        th->s.ws = ism_eval_ws_new(b->p->tape);
        th->corners = b->corner_memos + (size_t)t * memo;
        if (b->root_memos) {
            th->memo.roots = b->root_memos + (size_t)t * roots;
            th->memo.labels = b->label_memos + (size_t)t * labels;
            th->memo.pairs = b->pair_memos + (size_t)t * pairs;
            th->memo.log = b->p->roots ? &th->roots : NULL;
            th->roots.limit = b->p->max_roots / (size_t)nthreads;
        }
        if (!th->s.ws || !ism_thin_ws_init(&th->thin, b->p->tape))
            return false;
        if (b->shortening)
            for (int l = 0; l <= b->p->thin_depth; l++)
                if (!(th->tapes[l] = ism_tape_new_like(b->p->tape)))
                    return false;
    }
    return true;
}

static void free_threads(build *b, int nthreads, ism_octree_build_stats *st)
{
    if (!b->threads)
        return;
    for (int t = 0; t < nthreads; t++) {
        thread_state *th = &b->threads[t];
        st->visited += th->visited;
        st->excluded += th->excluded;
        st->unresolved += th->unresolved;
        st->thin_searched += th->thin_searched;
        st->thin_found += th->thin_found;
        st->thin_undecided += th->thin_undecided;
        st->thin_boxes += th->thin.n_boxes;
        st->deep_leaves += th->deep_leaves;
        st->tape_misses += th->tape_misses;
        st->copied += th->copied;
        ism_thin_ws_free(&th->thin);
        st->n_point += th->s.n_point;
        st->n_gradient += th->s.n_gradient;
        st->n_interval += th->s.n_interval;
        if (th->s.ws)
            ism_eval_ws_free(th->s.ws);
        for (int l = 0; l <= ISM_GRID_MAX_DEPTH; l++)
            if (th->tapes[l])
                ism_tape_free(th->tapes[l]);
        ism_root_log_free(&th->roots);
    }
    free(b->threads);
    if (b->corner_memos != b->p->corner_memos)
        free(b->corner_memos);
    free(b->root_memos);
    free(b->label_memos);
    free(b->pair_memos);
}

/* The join: where each task's subtree lands in the top array (at[k]: its node 1's place). */
typedef struct joiner {
    build *b;
    node_vec *top;
    size_t *at;
} joiner;

/* Task k's subtree copied to its place, child indices moved by the same offset. */
static void join_task(void *ctx, size_t k, int thread)
{
    (void)thread;
    joiner *j = ctx;
    const node_vec *sub = &j->b->task_out[k];
    node_vec *top = j->top;
    size_t offset = j->at[k] - 1; /* local index i > 0 lands at offset + i */
    ism_node root = sub->v[0];
    if (root.child >= 0)
        root.child += (int32_t)offset;
    top->v[j->b->tasks[k].node] = root;
    if (top->tape)
        top->tape[j->b->tasks[k].node] = sub->tape[0];
    for (size_t i = 1; i < sub->n; i++) {
        ism_node nd = sub->v[i];
        if (nd.child >= 0)
            nd.child += (int32_t)offset;
        top->v[offset + i] = nd;
        if (top->tape)
            top->tape[offset + i] = sub->tape[i];
    }
}

/* Appends every task's subtree to the top array, in task order, fixing child indices: the
 * places from a prefix sum, the copies on the build's threads (one task per subtree). Each
 * task's run stays in one piece: the next round's subtree_end and copy_subtree rely on it. */
static bool join_tasks(build *b, node_vec *top, int nthreads)
{
    size_t *at = malloc((b->ntasks ? b->ntasks : 1) * sizeof *at), n = top->n;
    if (!at)
        return false;
    for (size_t k = 0; k < b->ntasks; k++) {
        at[k] = n;
        n += b->task_out[k].n - 1;
    }
    if (!ism_build_vec_reserve(b, top, n - top->n)) {
        free(at);
        return false;
    }
    joiner j = {b, top, at};
    if (b->p->pool)
        ism_pool_for(b->p->pool, b->ntasks, join_task, &j, b->p->cost);
    else
        ism_parallel_for_costed(nthreads, b->ntasks, join_task, &j, b->p->cost);
    top->n = n;
    free(at);
    return true;
}

/* The threads' logged roots into p->roots (empty when the build failed), each log freed as
 * soon as it is in. */
static void hand_roots(build *b, int nthreads, bool ok)
{
    size_t roots = 0;
    for (int t = 0; b->threads && t < nthreads; t++)
        roots += b->threads[t].roots.n;
    ism_root_table_init(b->p->roots, ok ? roots : 0);
    for (int t = 0; b->threads && t < nthreads; t++)
        ism_root_table_take(b->p->roots, &b->threads[t].roots);
}

enum ism_build_status ism_octree_build(ism_octree *t, const ism_octree_build_params *p,
                                       ism_octree_build_stats *stats)
{
    memset(stats, 0, sizeof *stats);
    build b;
    memset(&b, 0, sizeof b);
    b.p = p;
    b.grid = &t->grid;
    b.shortening = ism_tape_has_min_max(p->tape); /* nothing to drop without min/max */
    atomic_init(&b.failed, ISM_BUILD_OK);
    atomic_init(&b.nodes_total, 1);
    atomic_init(&b.tasks_done, 0);
    pthread_mutex_init(&b.progress_lock, NULL);
    int nthreads = p->pool ? ism_pool_threads(p->pool) : p->threads < 1 ? 1 : p->threads;
    node_vec top = {0};
    defer_list deferred = {0, NULL, 0};
    enum ism_build_status status = ISM_BUILD_OK;

    b.previous = p->previous && p->previous->n ? p->previous : NULL;
    if (!ism_quiet_init(&b.quiet, p->quiet, p->nquiet) ||
        !ism_node_balls_init(&b.node_balls, p->node_balls, p->nnode_balls) ||
        !init_threads(&b, nthreads) ||
        !ism_leaf_tapes_init(&b.leaf_tapes, b.previous)) {
        status = ISM_BUILD_NO_MEMORY;
        goto done;
    }
    /* none (every node grown) when node balls may force a leaf or out of memory */
    if (b.previous && p->nnode_balls == 0)
        b.forced_below = mark_forced(b.previous, p->force_split);
    ism_node root = {{0, 0, 0}, -1, 0, ISM_NODE_LEAF, 0, 0};
    if (!vec_push(&b, &top, &root, 0)) {
        status = ISM_BUILD_NO_MEMORY;
        goto done;
    }
    deferred.level = p->max_depth < TOP_LEVEL ? p->max_depth : TOP_LEVEL;
    if (grow(&b, &b.threads[0], &top, 0, p->tape, NULL, p->max_depth, &deferred,
             b.previous ? 0 : -1,
             NULL))
        ism_build_count_nodes(&b, &b.threads[0]);
    if ((status = atomic_load(&b.failed)) != ISM_BUILD_OK)
        goto done;

    b.ntasks = deferred.n;
    b.tasks = deferred.v;
    b.task_out = calloc(b.ntasks ? b.ntasks : 1, sizeof *b.task_out);
    if (!b.task_out) {
        status = ISM_BUILD_NO_MEMORY;
        goto done;
    }
    for (size_t k = 0; k < b.ntasks; k++)
        if (!vec_push(&b, &b.task_out[k], &top.v[b.tasks[k].node],
                      top.tape ? top.tape[b.tasks[k].node] : 0)) {
            status = ISM_BUILD_NO_MEMORY;
            goto done;
        }
    if (p->pool)
        ism_pool_for(p->pool, b.ntasks, run_task, &b, p->cost);
    else
        ism_parallel_for_costed(nthreads, b.ntasks, run_task, &b, p->cost);
    if ((status = atomic_load(&b.failed)) != ISM_BUILD_OK)
        goto done;
    if (!join_tasks(&b, &top, nthreads))
        status = ISM_BUILD_NO_MEMORY;

done:
    if (p->roots)
        hand_roots(&b, nthreads, status == ISM_BUILD_OK);
    free_threads(&b, nthreads, stats);
    ism_quiet_free(&b.quiet);
    ism_node_balls_free(&b.node_balls);
    if (b.task_out)
        for (size_t k = 0; k < b.ntasks; k++) {
            free(b.task_out[k].v);
            free(b.task_out[k].tape);
        }
    free(b.task_out);
    free(b.forced_below);
    free(deferred.v);
    pthread_mutex_destroy(&b.progress_lock);
    if (status != ISM_BUILD_OK) {
        ism_leaf_tapes_free(&b.leaf_tapes);
        free(top.v);
        free(top.tape);
        t->nodes = NULL;
        t->tape_of = NULL;
        t->tapes = NULL;
        t->n = t->cap = 0;
        t->ntapes = 0;
        return status;
    }
    t->nodes = top.v;
    t->n = top.n;
    t->cap = top.cap;
    t->tape_of = top.tape;
    ism_leaf_tapes_give(&b.leaf_tapes, t);
    ism_leaf_tapes_free(&b.leaf_tapes);
    return ISM_BUILD_OK;
}

void ism_octree_free(ism_octree *t)
{
    free(t->nodes);
    free(t->tape_of);
    t->nodes = NULL;
    t->tape_of = NULL;
    t->n = t->cap = 0;
    for (size_t k = 0; k < t->ntapes; k++)
        ism_tape_free(t->tapes[k]);
    free(t->tapes);
    t->tapes = NULL;
    t->ntapes = 0;
}
