/* level_build.c — a task's subtree decided a level at a time, its nodes' corners and edge
 * roots fetched ahead in wide batches, then laid out in the depth-first order (see below and
 * build_state.h). */
#include "core/octree/build_state.h"
#include "core/octree/level_prefetch.h"
#include "core/util/grow.h"

#include <assert.h>
#include <stdlib.h>
#include <string.h>

/* A task's subtree grown level by level (ism_grow_levels): where each node's decision depends
 * on nothing but the node, its range and its limit — a build that shortens no tape (every
 * node evaluates f itself) and takes nothing over from a last round — the nodes of one level
 * are decided together, so the pure values their tests read (corners, edge roots) are
 * computed ahead in wide batches (level_prefetch.h), then laid out in grow's depth-first
 * order (lay_out): the tree, every node's verdict and the counters but the evaluation counts
 * are grow's (the memos end holding other entries, of the same pure values). Klein bottle at
 * E 3.27e-3 (callgrind, one thread, ism_mesh_surface; main 5757910): 3,486.0M -> 3,447.0M,
 * the roots' f 31 points a batch (was 1), the corners' 40 (was 1 to 27); the 87,166 tests
 * themselves unchanged. Not yet for tapes that shorten (each node of a level would need its
 * own shortened tape: gyroid-ball, Barth's sextic) nor for later rounds (take_over). */
/* A level's nodes (decided in place; a split node's child: its first child in the next
 * level) and, until the level is decided, what deciding each asks besides the node: its range
 * and limit (side, freed then). The level build keeps every level's nodes until lay_out has
 * copied them: at its peak, while lay_out writes the task's array, 2 ism_node a node (40
 * bytes), and while a level is decided its nodes and the next level's with their sides (24
 * bytes each) beside the levels above — at most ~2.2 times the depth-first build's one
 * ism_node a node under the same max_nodes (the levels kept their 48-byte level_node whole
 * until lay_out before: ~3.4 times, revH 5). */
typedef struct level_side {
    ism_interval range; /* f's interval over the node */
    int limit;          /* the level its children may be split down to */
} level_side;

typedef struct level_vec {
    ism_node *v;
    level_side *side;
    size_t n, cap, side_cap;
} level_vec;

/* Nodes of a level decided together: their corners and roots fit the memos (2^16 corner
 * and 2^13 root entries a thread) with room to spare, and the batches are hundreds wide.
 * Klein bottle at E 3.27e-3 (292a171's trial, callgrind, one thread, ism_mesh_surface): a
 * chunk of 64 gave 3,458.3M instructions, 512 gave 3,456.4M; 128 kept (the chunk size moves
 * the total by under 0.1%). */
#define LEVEL_CHUNK 128

/* Does ism_grow_levels decide as grow would (see above)? */
bool ism_levels_apply(const build *b, const thread_state *th)
{
    return !b->shortening && !b->previous && !b->p->scalar_eval && th->memo.roots;
}

/* Nodes [from, to) of level lv: ranges and force checks, the tested nodes' corners (into
 * corners: room for LEVEL_CHUNK) and roots prefetched, then each decided as grow decides it
 * (its children appended to next). */
static bool decide_chunk(build *b, thread_state *th, level_vec *lv, size_t from, size_t to,
                         level_vec *next, ism_corners *corners)
{
    const ism_node *tested[LEVEL_CHUNK];
    bool have[LEVEL_CHUNK], asks[LEVEL_CHUNK]; /* asks[j - from]: node j asks the test */
    size_t nt = 0;
    for (size_t j = from; j < to; j++) {
        ism_node *nd = &lv->v[j];
        const level_side *sd = &lv->side[j];
        th->visited++;
        bool forced = ism_build_forced_split(b, nd);
        asks[j - from] = false;
        if (!(sd->range.lo <= 0 && sd->range.hi >= 0)) {
            nd->state = ISM_NODE_EMPTY;
            th->excluded++;
            continue;
        }
        asks[j - from] = nd->level >= b->p->min_depth && !forced;
        if (asks[j - from])
            tested[nt++] = nd;
    }
    const ism_tape *saved = th->s.tape;
    th->s.tape = b->p->tape; /* the tape the nodes are tested on (ism_levels_apply: f's own) */
    ism_prefetch_nodes(&th->memo, th->corners, ISM_CORNER_MEMO_BITS, b->grid, tested, nt,
                       &th->s, corners, have);
    th->s.tape = saved;
    for (size_t j = from, t = 0; j < to; j++) {
        if (atomic_load(&b->failed) != ISM_BUILD_OK)
            return false;
        if (b->p->cancel && *b->p->cancel)
            return ism_build_fail(b, ISM_BUILD_CANCELLED);
        if (lv->v[j].state == ISM_NODE_EMPTY)
            continue;
        ism_node nd = lv->v[j];
        int limit = lv->side[j].limit;
        bool ask = asks[j - from];
        const ism_corners *known = ask && have[t] ? &corners[t] : NULL;
        t += ask;
        if (ask && ism_build_test_node(b, th, &nd, b->p->tape, known, &lv->v[j], &limit))
            continue; /* a leaf (state LEAF already: no tape number, f itself) */
        if ((th->new_nodes += 8) >= NODE_BATCH && !ism_build_count_nodes(b, th))
            return false;
        if (!ism_grow((void **)&next->v, &next->cap, next->n + 8, sizeof *next->v, 256) ||
            !ism_grow((void **)&next->side, &next->side_cap, next->n + 8, sizeof *next->side,
                      256))
            return ism_build_fail(b, ISM_BUILD_NO_MEMORY);
        ism_interval ranges[8];
        ism_build_children_ranges(b, th, &nd, b->p->tape, ranges);
        lv->v[j].state = ISM_NODE_SPLIT;
        lv->v[j].child = (int32_t)next->n;
        for (int k = 0; k < 8; k++) {
            next->side[next->n] = (level_side){ranges[k], limit};
            next->v[next->n++] = ism_build_child(b, &nd, k);
        }
    }
    return true;
}

/* Node j of level l laid out at v->v[i], its children appended and laid out in turn, as
 * grow appends and grows them. */
static bool lay_out(build *b, node_vec *v, size_t i, const level_vec *lv, int l, size_t j)
{
    const ism_node *nd = &lv[l].v[j];
    v->v[i] = *nd;
    if (nd->state != ISM_NODE_SPLIT)
        return true;
    size_t first = v->n;
    if (!ism_build_vec_reserve(b, v, 8))
        return ism_build_fail(b, ISM_BUILD_NO_MEMORY);
    for (int k = 0; k < 8; k++)
        ism_build_vec_put(v, &lv[l + 1].v[nd->child + k], 0);
    v->v[i].child = (int32_t)first;
    for (int k = 0; k < 8; k++)
        if (!lay_out(b, v, first + k, lv, l + 1, (size_t)nd->child + k))
            return false;
    return true;
}

/* The task's node v->v[0] and its subtree, decided level by level (ism_levels_apply). */
bool ism_grow_levels(build *b, thread_state *th, node_vec *v, int limit)
{
    level_vec lv[ISM_GRID_MAX_DEPTH + 2];
    memset(lv, 0, sizeof lv);
    int top = v->v[0].level, l = top;
    bool ok = true;
    ism_interval range;
    ism_build_node_range(b, th, &v->v[0], b->p->tape, &range);
    lv[top].v = malloc(sizeof *lv[top].v);
    lv[top].side = malloc(sizeof *lv[top].side);
    ism_corners *k = malloc(LEVEL_CHUNK * sizeof *k); /* the chunk's tested nodes' */
    if (!lv[top].v || !lv[top].side || !k) {
        free(lv[top].v);
        free(lv[top].side);
        free(k);
        return ism_build_fail(b, ISM_BUILD_NO_MEMORY);
    }
    lv[top].v[0] = v->v[0];
    lv[top].side[0] = (level_side){range, limit};
    lv[top].n = lv[top].cap = lv[top].side_cap = 1;
    for (; ok && l <= ISM_GRID_MAX_DEPTH && lv[l].n; l++) {
        for (size_t from = 0; ok && from < lv[l].n; from += LEVEL_CHUNK) {
            size_t to = lv[l].n - from < LEVEL_CHUNK ? lv[l].n : from + LEVEL_CHUNK;
            ok = decide_chunk(b, th, &lv[l], from, to, &lv[l + 1], k);
        }
        free(lv[l].side); /* the level is decided */
        lv[l].side = NULL;
    }
    /* No node past the finest lattice level is split: every split path stops at limit or
     * thin_depth, both at most ISM_GRID_MAX_DEPTH. A child appended there would be laid out
     * as an untested leaf, so say so loudly rather than mesh it. */
    assert(!ok || lv[ISM_GRID_MAX_DEPTH + 1].n == 0);
    ok = ok && lay_out(b, v, 0, lv, top, 0);
    for (int j = top; j <= ISM_GRID_MAX_DEPTH + 1; j++) {
        free(lv[j].v);
        free(lv[j].side);
    }
    free(k);
    return ok;
}

