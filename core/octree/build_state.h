/* build_state.h — the octree build's state shared by its two ways of growing a task's subtree:
 * depth-first (octree_build.c grow, which also owns the top levels, the tasks and the join)
 * and level by level (level_build.c): the build, each thread's scratch and memos, a task's
 * node array, and the per-node steps both call. Internal to those two files. */
#ifndef ISM_BUILD_STATE_H
#define ISM_BUILD_STATE_H

#include <pthread.h>
#include <stdalign.h>
#include <stdatomic.h>
#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>
#include "core/octree/cell_cache.h"
#include "core/octree/corners.h"
#include "core/octree/face_memo.h"
#include "core/octree/leaf_tapes.h"
#include "core/octree/node_balls.h"
#include "core/octree/octree_build.h"
#include "core/octree/quiet.h"
#include "core/octree/root_table.h"
#include "core/octree/sampler.h"
#include "core/octree/thin_search.h"
#include "core/util/cache_line.h"

/* A thread adds its new nodes to the shared count (the max_nodes budget) in batches this
 * large: one shared write per 512 splits instead of one per split, at the price of
 * exceeding the budget by at most this many nodes per thread before the build stops. A
 * subtree copied whole (copy_subtree) is counted at once, before it is allocated. */
#define NODE_BATCH 4096

typedef struct node_vec {
    ism_node *v;
    size_t n, cap;
    uint16_t *tape;  /* beside v when the build shortens tapes: octree.h's tape_of */
    size_t tape_cap;
} node_vec;

/* Nodes at the top levels left for the worker threads: each with the depth its subtree may
 * reach (see grow). */
typedef struct deferral {
    size_t node;
    int limit;
    int32_t previous; /* the node in the last round's tree, or -1 */
} deferral;

typedef struct thread_state {
    alignas(ISM_CACHE_LINE) ism_sampler s; /* threads' states in lines of their own: each
                                              writes its counters for every node */
    ism_point_entry *corners; /* memo of f and ∇f at lattice points (pure: never stale) */
    ism_node_memo memo;       /* memo of roots on node edges and crease labels at corners
                                 (cell_cache.h; pure too) */
    ism_tape *tapes[ISM_GRID_MAX_DEPTH + 1];
    /* tapes[l]'s number in build.leaf_tapes, known while written[l] == numbered[l]: the
     * leaves below one shortening share it without a lookup */
    uint32_t written[ISM_GRID_MAX_DEPTH + 1], numbered[ISM_GRID_MAX_DEPTH + 1];
    uint16_t number[ISM_GRID_MAX_DEPTH + 1];
    ism_leaf_tapes_cache tape_cache; /* this thread's hits in build.leaf_tapes */
    ism_thin_ws thin;         /* the hidden-piece search's scratch */
    ism_face_memo faces;      /* its verdicts on faces, for the node across (face_memo.h) */
    ism_root_log roots;       /* the roots memo.roots was filled with (root_table.h) */
    /* the counters, visited to new_nodes, together (level_build.c saves and restores them
     * whole when it gives a task up) */
    uint64_t visited, excluded, unresolved;
    uint64_t thin_searched, thin_found, thin_undecided, deep_leaves;
    uint64_t tape_misses;     /* leaves whose shortened tape found no room in leaf_tapes */
    uint64_t copied;          /* nodes copy_subtree wrote */
    size_t new_nodes;         /* made since the last batch went to build.nodes_total */
} thread_state;

typedef struct build {
    const ism_octree_build_params *p;
    const ism_grid *grid;
    ism_quiet quiet;             /* index of p->quiet */
    ism_node_balls node_balls;   /* index of p->node_balls */
    const ism_octree *previous;  /* p->previous when it may be used, else NULL */
    uint8_t *forced_below;       /* per node of previous: 1 when a force_split key's descent
                                    passes it (copy_subtree); NULL: no subtree copied */
    thread_state *threads;
    ism_point_entry *corner_memos; /* the threads' memos, end to end (thread_state.corners):
                                      p->corner_memos, or the build's own */
    ism_root_entry *root_memos;    /* ... and thread_state.memo's */
    ism_pair_entry *pair_memos;
    ism_label_entry *label_memos;
    int shortening;
    ism_leaf_tapes leaf_tapes;   /* the leaves' shortened tapes (octree.h) */
    /* written rarely, read by every node; the counters below live on lines of their own */
    atomic_int failed;           /* an enum ism_build_status other than OK */
    alignas(ISM_CACHE_LINE) atomic_size_t nodes_total; /* in batches (NODE_BATCH) */
    deferral *tasks;             /* node index (in the top array) and limit of each task */
    node_vec *task_out;          /* each task's subtree; [0] is the task's node itself */
    alignas(ISM_CACHE_LINE) atomic_size_t tasks_done;
    size_t ntasks;
    pthread_mutex_t progress_lock;
} build;

/* Room for extra more nodes (and their tape numbers when the build keeps them). */
bool ism_build_vec_reserve(const build *b, node_vec *v, size_t extra);

/* Appends nd (room reserved) with its tape number. */
static inline void ism_build_vec_put(node_vec *v, const ism_node *nd, uint16_t tape)
{
    if (v->tape)
        v->tape[v->n] = tape;
    v->v[v->n++] = *nd;
}

/* Child k of nd as a split appends it: undecided (a leaf until decided). */
static inline ism_node ism_build_child(const build *b, const ism_node *nd, int k)
{
    ism_node c = {{0, 0, 0}, -1, (uint8_t)(nd->level + 1), ISM_NODE_LEAF, 0, 0};
    ism_child_origin(b->grid, nd, k, c.org);
    return c;
}

/* Records the build's first failure (later ones keep it); false, for returning. */
bool ism_build_fail(build *b, enum ism_build_status st);
/* Adds the thread's new nodes to the shared count; false (and the build failed) beyond
 * max_nodes. */
bool ism_build_count_nodes(build *b, thread_state *th);
/* f's interval over nd into *range, and the tape to use below it (shortened when the box
 * proves min/max branches dominated). */
const ism_tape *ism_build_node_range(build *b, thread_state *th, const ism_node *nd,
                                     const ism_tape *tape, ism_interval *range);
/* The scratch tape ism_build_node_range shortens nd's tape into, when it shortens by
 * ism_tape_shorten (the build shortens and nd's level has one that can hold tape's
 * shortening), else NULL. */
ism_tape *ism_build_shorten_into(const build *b, thread_state *th, const ism_node *nd,
                                 const ism_tape *tape);
/* ism_tape_shorten's pass of ism_build_node_range alone (shorten.h: false when it cannot
 * run, *range then the whole line): f's interval over nd on tape into *range (counted as
 * one), the choices at its min/max in th->s.ws. */
bool ism_build_node_choices(build *b, thread_state *th, const ism_node *nd,
                            const ism_tape *tape, ism_interval *range);
/* Is fresh node nd split whatever its test says? */
bool ism_build_forced_split(const build *b, const ism_node *nd);
/* The intervals of nd's 8 children over tape, in one batched call. */
void ism_build_children_ranges(build *b, thread_state *th, const ism_node *nd,
                               const ism_tape *tape, ism_interval range[8]);
/* The flatness test of a fresh node and what follows it (octree_build.c): true when it is a
 * leaf; known: its corners computed ahead, or NULL. */
bool ism_build_test_node(build *b, thread_state *th, const ism_node *nd, const ism_tape *sub,
                         const ism_corners *known, ism_node *out, int *limit_io);

/* level_build.c: does the level-by-level build decide as grow would, and the task's node
 * v->v[0] and its subtree grown so: grown, failed (the build's status says why), or declined
 * (v untouched: the task is to be grown by grow). */
enum ism_levels_result { ISM_LEVELS_GROWN, ISM_LEVELS_FAILED, ISM_LEVELS_DECLINED };
bool ism_levels_apply(const build *b, const thread_state *th);
enum ism_levels_result ism_grow_levels(build *b, thread_state *th, node_vec *v, int limit);

#endif
