/* level_build.c — a task's subtree decided a level at a time, its nodes' corners and edge
 * roots fetched ahead in wide batches, then laid out in the depth-first order (see below and
 * build_state.h). */
#include "core/octree/build_state.h"
#include "core/octree/level_prefetch.h"
#include "core/octree/shorten_memo.h"
#include "core/eval/shorten.h"
#include "core/util/grow.h"

#include <assert.h>
#include <stddef.h>
#include <stdlib.h>
#include <string.h>

/* A task's subtree grown level by level (ism_grow_levels): where each node's decision depends
 * on nothing but the node, its range, its limit and the tape it is tested on — a build that
 * takes nothing over from a last round (take_over) — the nodes of one level are decided
 * together, so the pure values their tests read (corners, edge roots) are computed ahead in
 * wide batches (level_prefetch.h), then laid out in grow's depth-first order (lay_out): the
 * tree, every node's verdict and the counters but the evaluation counts are grow's (the memos
 * end holding other entries, of the same pure values; the leaf tapes' numbers follow the
 * order the tapes are met). Klein bottle at E 3.27e-3 (callgrind, one thread,
 * ism_mesh_surface; main 5757910): 3,486.0M -> 3,447.0M, the roots' f 31 points a batch (was
 * 1), the corners' 40 (was 1 to 27); the 87,166 tests themselves unchanged.
 * Tapes that shorten (a min/max the node intervals decide): each node keeps the tape grow
 * would test it on — its parent's, or the one ism_build_node_range shortened from it — in the
 * task's table of tapes (level_tapes); the prefetch evaluates f's own tape, which is the
 * shortened one's value inside the node (shorten.c drops only branches the interval proves
 * dead there), as node_corners already reads every corner on it. Barth's sextic at E 0.0259
 * (callgrind, one thread, ism_mesh_surface; main 2db83568): 1,222.4M -> 1,206.8M (the edge
 * roots in lanes: 59.0M of single searches -> 42.5M); the gyroid ball at E 1.09e-3
 * 2,251.9M -> 2,250.0M (its sin/cos cost about as much a point in lanes as alone). */
/* A level's nodes (decided in place; a split node's child: its first child in the next
 * level) and, until the level is decided, what deciding each asks besides the node: its
 * range, limit and tape (side, freed then). The level build keeps every level's nodes until
 * lay_out has copied them: at its peak, while lay_out writes the task's array, 2 ism_node a
 * node (40 bytes), and while a level is decided its nodes and the next level's with their
 * sides (24 bytes each) beside the levels above — at most ~2.2 times the depth-first build's
 * one ism_node a node under the same max_nodes (the levels kept their 48-byte level_node
 * whole until lay_out before: ~3.4 times, revH 5); a build that shortens keeps 2 bytes more a
 * node (number) and each distinct tape of the task once (level_tapes). */
typedef struct level_side {
    ism_interval range; /* f's interval over the node */
    int limit;          /* the level its children may be split down to */
    uint32_t tape;      /* the tape it is tested on (level_tapes: 0 f's own) */
} level_side;

typedef struct level_vec {
    ism_node *v;
    level_side *side;
    uint16_t *number; /* beside v when the build shortens: a leaf's number in the build's
                         leaf_tapes (octree.h's tape_of), else 0 */
    size_t n, cap, side_cap, number_cap;
} level_vec;

/* The shortened tapes a task's nodes are tested on, each distinct tape once: a level's nodes
 * are decided together, so each needs its own (grow keeps one a level, th->tapes, as it
 * decides one node at a time). Numbered from 1 in an ism_leaf_tapes table of the task's own
 * (0: f's own tape, b->p->tape), under the tree's limits (past them the task is given up to
 * grow, ism_grow_levels); what a number asks of its tape is kept beside it. */
typedef struct level_tapes {
    ism_leaf_tapes table;
    ism_leaf_tapes_cache cache;
    uint8_t *facts;    /* per number: FACT_* bits (0: not asked yet) */
    uint32_t *leaf;    /* per number: 1 + its number in b->leaf_tapes (0: not asked yet) */
    size_t cap;
    uint32_t last;     /* the number a shortening got last (0: none yet), compared first:
                          siblings mostly shorten alike, and a compare costs less than the
                          table's hash */
    bool full;         /* a tape found no room in table: the task is grown node by node */
    ism_shorten_memo met; /* the shortenings met, by number and choices (split_node) */
} level_tapes;

/* Nodes of a level decided together: their corners and roots fit the memos (2^16 corner
 * and 2^13 root entries a thread) with room to spare, and the batches are hundreds wide.
 * Klein bottle at E 3.27e-3 (292a171's trial, callgrind, one thread, ism_mesh_surface): a
 * chunk of 64 gave 3,458.3M instructions, 512 gave 3,456.4M; 128 kept (the chunk size moves
 * the total by under 0.1%). */
#define LEVEL_CHUNK 128
_Static_assert(LEVEL_CHUNK <= ISM_PREFETCH_MAX_NODES, "a chunk is one prefetch call");
/* A tested node's edge roots are searched on its own shortened tape when that tape is at most
 * this share of f's instructions, else on f's own (same roots: the prefetch's lanes run one
 * tape a set, so more tapes mean more, emptier sets). Callgrind, one thread, ism_mesh_surface:
 * the gyroid ball at E 1.09e-3 (its nodes inside the ball on 15 of 21 instructions)
 * 2,244.1M -> 2,229.5M on their own tapes; Barth's sextic at E 0.0259 (18 of 20 near its
 * surface) 1,183.6M -> 1,185.1M on theirs, 1,184.2M with this share (its ball's caps, on 7
 * instructions, on theirs: the +0.6M is the choice's own cost, ~20 instructions a tested
 * node; at E 3.89e-3 2,454.3M -> 2,455.8M). */
#define ROOTS_OWN_TAPE_SHARE 0.8

/* Does ism_grow_levels decide as grow would (see above)? */
bool ism_levels_apply(const build *b, const thread_state *th)
{
    return !b->previous && !b->p->scalar_eval && !b->p->depth_first && th->memo.roots;
}

static const ism_tape *tape_at(const build *b, const level_tapes *lt, uint32_t id)
{
    return id ? lt->table.v[id - 1] : b->p->tape;
}

/* The number of tape t, as ism_build_node_range returned it below a node tested on tape
 * `from` (number id): id when it did not shorten, else its copy's. False when out of memory,
 * or with lt->full when the table has no room for t (its limits, octree.h's, bound a task's
 * scratch: the task is then grown as grow grows it, ism_grow_levels). */
static bool tape_id(build *b, level_tapes *lt, const ism_tape *t, const ism_tape *from,
                    uint32_t id, uint32_t *out)
{
    if (t == from) {
        *out = id;
        return true;
    }
    if (lt->last && ism_leaf_tapes_same(lt->table.v[lt->last - 1], t)) {
        *out = lt->last;
        return true;
    }
    unsigned k = ism_leaf_tapes_number(&lt->table, &lt->cache, t);
    if (k && k > lt->cap) {
        size_t cap = lt->cap, c2 = lt->cap;
        if (!ism_grow((void **)&lt->facts, &cap, k, sizeof *lt->facts, 64) ||
            !ism_grow((void **)&lt->leaf, &c2, k, sizeof *lt->leaf, 64))
            return ism_build_fail(b, ISM_BUILD_NO_MEMORY);
        memset(lt->facts + lt->cap, 0, (cap - lt->cap) * sizeof *lt->facts);
        memset(lt->leaf + lt->cap, 0, (c2 - lt->cap) * sizeof *lt->leaf);
        lt->cap = cap < c2 ? cap : c2;
    }
    *out = lt->last = k;
    lt->full = k == 0;
    return k != 0;
}

/* What level_tapes.facts keeps of a tape number: asked; the tape keeps a min/max (then each
 * child shortens its own, as in grow); its nodes' roots are searched on it
 * (ROOTS_OWN_TAPE_SHARE). */
enum { FACT_KNOWN = 1, FACT_MIN_MAX = 2, FACT_ROOTS_OWN = 4 };

/* Tape number id's facts (id > 0). */
static unsigned facts_of(const build *b, level_tapes *lt, uint32_t id)
{
    uint8_t *f = &lt->facts[id - 1];
    if (!*f) {
        const ism_tape *t = lt->table.v[id - 1];
        bool own = (double)t->len <= ROOTS_OWN_TAPE_SHARE * (double)b->p->tape->len;
        *f = (uint8_t)(FACT_KNOWN | (ism_tape_has_min_max(t) ? FACT_MIN_MAX : 0) |
                       (own ? FACT_ROOTS_OWN : 0));
    }
    return *f;
}

static bool keeps_min_max(const build *b, level_tapes *lt, uint32_t id)
{
    return id ? (facts_of(b, lt, id) & FACT_MIN_MAX) != 0 : b->shortening != 0;
}

/* The tape the edge roots of a node tested on tape number id are searched on. */
static const ism_tape *roots_tape(const build *b, level_tapes *lt, uint32_t id)
{
    return id && (facts_of(b, lt, id) & FACT_ROOTS_OWN) ? tape_at(b, lt, id) : b->p->tape;
}

/* A leaf's number in the build's leaf_tapes (as grow's tape_number: 0 when it finds no
 * room there, counted as a miss), for a leaf tested on tape number id != 0. */
static uint16_t leaf_number(build *b, thread_state *th, level_tapes *lt, uint32_t id)
{
    if (!lt->leaf[id - 1])
        lt->leaf[id - 1] = 1 + ism_leaf_tapes_number(&b->leaf_tapes, &th->tape_cache,
                                                     lt->table.v[id - 1]);
    uint16_t k = (uint16_t)(lt->leaf[id - 1] - 1);
    th->tape_misses += k == 0;
    return k;
}

/* Room for 8 more nodes in level lv (and their numbers when the build shortens). */
static bool level_room(const build *b, level_vec *lv)
{
    return ism_grow((void **)&lv->v, &lv->cap, lv->n + 8, sizeof *lv->v, 256) &&
           ism_grow((void **)&lv->side, &lv->side_cap, lv->n + 8, sizeof *lv->side, 256) &&
           (!b->shortening || ism_grow((void **)&lv->number, &lv->number_cap, lv->n + 8,
                                       sizeof *lv->number, 256));
}

/* Child c's range and tape number below a node tested on tape number id (tape sub), as
 * ism_build_node_range and tape_id find them: a child whose pass records the choices at sub's
 * min/max that one before it recorded takes the number that one's shortening got
 * (shorten_memo.h) without shortening. Barth's sextic at E 0.0259 (callgrind, one thread,
 * ism_mesh_surface; main 9300ff0f): 30,448 of 30,592 such children met their tape and choices
 * before, 1,133.9M -> 1,109.8M (the backward pass, the copy and tape_id's lookup were ~24M);
 * at E 0.00389 2,353.1M -> 2,286.3M. */
static bool child_tape(build *b, thread_state *th, level_tapes *lt, const ism_node *c,
                       const ism_tape *sub, uint32_t id, level_side *sd)
{
    ism_tape *into = ism_build_shorten_into(b, th, c, sub);
    if (!into) {
        const ism_tape *t = ism_build_node_range(b, th, c, sub, &sd->range);
        return tape_id(b, lt, t, sub, id, &sd->tape);
    }
    if (!ism_build_node_choices(b, th, c, sub, &sd->range)) { /* ws does not fit sub */
        sd->tape = id;
        return true;
    }
    uint64_t key;
    enum ism_shorten_memo_found met = ism_shorten_memo_get(
        &lt->met, id, sub, ism_tape_shorten_choices(th->s.ws), &key, &sd->tape);
    if (met == ISM_SHORTEN_MEMO_HIT)
        return true;
    const ism_tape *t = sub;
    if (ism_tape_shorten_recorded(sub, th->s.ws, into)) {
        th->written[c->level]++;
        t = into;
    }
    if (!tape_id(b, lt, t, sub, id, &sd->tape))
        return false;
    /* unkept (out of memory): met again, it is shortened again */
    (void)(met == ISM_SHORTEN_MEMO_MISS && ism_shorten_memo_add(&lt->met, id, key, sd->tape));
    return true;
}

/* Split node nd (tested on tape number id, child limit `limit`): its 8 children appended to
 * next with their ranges and tapes, as grow finds them: in one batch over nd's tape, unless
 * that tape keeps a min/max the build may drop (each child then shortens its own). */
static bool split_node(build *b, thread_state *th, level_tapes *lt, const ism_node *nd,
                       uint32_t id, int limit, level_vec *next)
{
    if (!level_room(b, next))
        return ism_build_fail(b, ISM_BUILD_NO_MEMORY);
    const ism_tape *sub = tape_at(b, lt, id);
    ism_node *c = &next->v[next->n];
    level_side *sd = &next->side[next->n];
    ism_interval ranges[8];
    for (int k = 0; k < 8; k++)
        c[k] = ism_build_child(b, nd, k);
    if (!keeps_min_max(b, lt, id)) {
        ism_build_children_ranges(b, th, nd, sub, ranges);
        for (int k = 0; k < 8; k++)
            sd[k] = (level_side){ranges[k], limit, id};
    } else {
        for (int k = 0; k < 8; k++) {
            sd[k] = (level_side){{0, 0}, limit, id};
            if (!child_tape(b, th, lt, &c[k], sub, id, &sd[k]))
                return false;
        }
    }
    if (next->number)
        memset(&next->number[next->n], 0, 8 * sizeof *next->number);
    next->n += 8;
    return true;
}

/* Nodes [from, to) of level lv: ranges and force checks, the tested nodes' corners (into
 * corners: room for LEVEL_CHUNK) and roots prefetched, then each decided as grow decides it
 * (its children appended to next). */
static bool decide_chunk(build *b, thread_state *th, level_tapes *lt, level_vec *lv,
                         size_t from, size_t to, level_vec *next, ism_corners *corners)
{
    const ism_node *tested[LEVEL_CHUNK];
    const ism_tape *tapes[LEVEL_CHUNK]; /* tested[i]'s (its roots are searched on it) */
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
        if (asks[j - from]) {
            if (b->shortening)
                tapes[nt] = roots_tape(b, lt, sd->tape);
            tested[nt++] = nd;
        }
    }
    const ism_tape *saved = th->s.tape;
    th->s.tape = b->p->tape; /* corners on f's own tape, as node_corners reads them; the
                                roots on each node's, as cell_error.c searches them */
    ism_prefetch_nodes(&th->memo, th->corners, ISM_CORNER_MEMO_BITS, b->grid, tested,
                       b->shortening ? tapes : NULL, nt, &th->s, corners, have);
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
        uint32_t id = lv->side[j].tape;
        const ism_tape *sub = tape_at(b, lt, id);
        bool ask = asks[j - from];
        const ism_corners *known = ask && have[t] ? &corners[t] : NULL;
        t += ask;
        if (ask && ism_build_test_node(b, th, &nd, sub, known, &lv->v[j], &limit)) {
            /* a leaf (state LEAF already); the tape its cell evaluates, as grow numbers it */
            if (id && !(lv->v[j].flags & ISM_NODE_ZERO_FREE) && !b->p->full_tape)
                lv->number[j] = leaf_number(b, th, lt, id);
            continue;
        }
        lv->v[j].state = ISM_NODE_SPLIT;
        lv->v[j].child = (int32_t)next->n;
        if (!split_node(b, th, lt, &nd, id, limit, next))
            return false;
        /* counted once appended, so that the task's levels hold the nodes it counted */
        if ((th->new_nodes += 8) >= NODE_BATCH && !ism_build_count_nodes(b, th))
            return false;
    }
    return true;
}

/* Node j of level l laid out at v->v[i], its children appended and laid out in turn, as
 * grow appends and grows them. */
static bool lay_out(build *b, node_vec *v, size_t i, const level_vec *lv, int l, size_t j)
{
    const ism_node *nd = &lv[l].v[j];
    v->v[i] = *nd;
    if (v->tape)
        v->tape[i] = lv[l].number[j];
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

/* Level `top`, the task's node alone (range and tape from f's own tape, as grow finds
 * them), into lv[top]. */
static bool first_level(build *b, thread_state *th, level_tapes *lt, const ism_node *nd,
                        int limit, level_vec *lv)
{
    ism_interval range;
    uint32_t id;
    const ism_tape *t = ism_build_node_range(b, th, nd, b->p->tape, &range);
    if (!tape_id(b, lt, t, b->p->tape, 0, &id))
        return false;
    if (!level_room(b, lv))
        return ism_build_fail(b, ISM_BUILD_NO_MEMORY);
    lv->v[0] = *nd;
    lv->side[0] = (level_side){range, limit, id};
    if (lv->number)
        lv->number[0] = 0;
    lv->n = 1;
    return true;
}

/* The thread's counters, from visited to new_nodes (build_state.h keeps them together). */
#define COUNTS_AT offsetof(thread_state, visited)
#define COUNTS_SIZE (offsetof(thread_state, new_nodes) + sizeof(size_t) - COUNTS_AT)

/* A task given up (lt->full): its counters as they were (saved), and the nodes of its levels
 * that went to the shared count taken back, so that grow counts the task as if alone (they
 * are nodes grow makes too: the count never held more than the build's end holds). */
static void give_up(build *b, thread_state *th, const level_vec *lv, int top,
                    const unsigned char *saved)
{
    size_t made = 0, before;
    for (int j = top + 1; j <= ISM_GRID_MAX_DEPTH + 1; j++)
        made += lv[j].n;
    memcpy(&before, saved + offsetof(thread_state, new_nodes) - COUNTS_AT, sizeof before);
    atomic_fetch_sub(&b->nodes_total, before + made - th->new_nodes);
    memcpy((unsigned char *)th + COUNTS_AT, saved, COUNTS_SIZE);
}

static void free_tapes(level_tapes *lt)
{
    ism_leaf_tapes_free(&lt->table);
    ism_shorten_memo_free(&lt->met);
    free(lt->facts);
    free(lt->leaf);
}

/* The task's node v->v[0] and its subtree, decided level by level (ism_levels_apply); or
 * ISM_LEVELS_DECLINED, v untouched and the thread's counters as they were, when a tape found
 * no room in the task's table (level_tapes): grow's one tape a level never runs out. The
 * shared leaf_tapes may keep tapes the given-up leaves numbered (numbers follow the order
 * tapes are met anyway). */
enum ism_levels_result ism_grow_levels(build *b, thread_state *th, node_vec *v, int limit)
{
    level_vec lv[ISM_GRID_MAX_DEPTH + 2];
    memset(lv, 0, sizeof lv);
    int top = v->v[0].level, l = top;
    unsigned char saved[COUNTS_SIZE];
    memcpy(saved, (const unsigned char *)th + COUNTS_AT, COUNTS_SIZE);
    /* none when no tape shortens (every node on f's own: number 0) */
    level_tapes *lt = b->shortening ? calloc(1, sizeof *lt) : NULL;
    bool table = lt && ism_leaf_tapes_init(&lt->table, NULL);
    ism_corners *k = malloc(LEVEL_CHUNK * sizeof *k); /* the chunk's tested nodes' */
    if ((b->shortening && !table) || !k) {
        if (table)
            free_tapes(lt);
        free(lt);
        free(k);
        ism_build_fail(b, ISM_BUILD_NO_MEMORY);
        return ISM_LEVELS_FAILED;
    }
    if (lt && b->p->level_tapes_max)
        lt->table.max_n = b->p->level_tapes_max;
    bool ok = first_level(b, th, lt, &v->v[0], limit, &lv[top]);
    for (; ok && l <= ISM_GRID_MAX_DEPTH && lv[l].n; l++) {
        for (size_t from = 0; ok && from < lv[l].n; from += LEVEL_CHUNK) {
            size_t to = lv[l].n - from < LEVEL_CHUNK ? lv[l].n : from + LEVEL_CHUNK;
            ok = decide_chunk(b, th, lt, &lv[l], from, to, &lv[l + 1], k);
        }
        free(lv[l].side); /* the level is decided */
        lv[l].side = NULL;
    }
    /* No node past the finest lattice level is split: every split path stops at limit or
     * thin_depth, both at most ISM_GRID_MAX_DEPTH. A child appended there would be laid out
     * as an untested leaf, so say so loudly rather than mesh it. */
    assert(!ok || lv[ISM_GRID_MAX_DEPTH + 1].n == 0);
    ok = ok && lay_out(b, v, 0, lv, top, 0);
    bool declined = !ok && lt && lt->full && atomic_load(&b->failed) == ISM_BUILD_OK;
    if (declined)
        give_up(b, th, lv, top, saved);
    for (int j = top; j <= ISM_GRID_MAX_DEPTH + 1; j++) {
        free(lv[j].v);
        free(lv[j].side);
        free(lv[j].number);
    }
    if (lt)
        free_tapes(lt);
    free(lt);
    free(k);
    return declined ? ISM_LEVELS_DECLINED : ok ? ISM_LEVELS_GROWN : ISM_LEVELS_FAILED;
}
